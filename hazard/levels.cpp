// The visual-interference levels of the flight zones and the photopic correction they take.
#include "hazard/levels.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace glint {
namespace {

// V(λ), CIE 1924 photopic observer, 400 nm to 700 nm every 5 nm (the CIE's own 5 nm table; its
// 1 nm table is an interpolation of these).
constexpr std::array<double, 61> kPhotopic5nm = {
    0.000396, 0.00064, 0.00121, 0.00218, 0.004,   0.0073,   0.0116,  0.01684, 0.023,
    0.0298,   0.038,   0.048,   0.06,    0.0739,  0.09098,  0.1126,  0.13902, 0.1693,
    0.20802,  0.2586,  0.323,   0.4073,  0.503,   0.6082,   0.71,    0.7932,  0.862,
    0.91485,  0.954,   0.9803,  0.99495, 1.0,     0.995,    0.9786,  0.952,   0.9154,
    0.87,     0.8163,  0.757,   0.6949,  0.631,   0.5668,   0.503,   0.4412,  0.381,
    0.321,    0.265,   0.217,   0.175,   0.1382,  0.107,    0.0816,  0.061,   0.04458,
    0.032,    0.0232,  0.017,   0.01192, 0.00821, 0.005723, 0.004102};

constexpr const char* kFlightZoneSource =
    "ANSI Z136.6-2015 flight-zone exposure levels (FAA Order JO 7400.2 ch. 29, AC 70-1; ICAO Doc "
    "9815)";

}  // namespace

double photopicEfficiency(double wavelength_nm) {
  const double x = std::clamp((wavelength_nm - kVisibleMinNm) / 5.0, 0.0,
                              static_cast<double>(kPhotopic5nm.size() - 1));
  const auto below = static_cast<std::size_t>(std::floor(x));
  const auto above = static_cast<std::size_t>(std::ceil(x));
  return std::max(kPhotopic5nm[below], kPhotopic5nm[above]);
}

std::vector<ExposureLevel> flightZoneLevels(bool visual_correction) {
  const auto level = [&](const char* name, const char* label, double w_m2) {
    ExposureLevel l;
    l.name = name;
    l.label = label;
    l.level_w_m2 = w_m2;
    l.visually_corrected = visual_correction;
    l.averaged_over_window = true;
    l.source = kFlightZoneSource;
    return l;
  };
  // 1 W/m² = 100 µW/cm².
  return {level("sensitive_zone", "sensitive flight zone (100 µW/cm²)", 1.0),
          level("critical_zone", "critical flight zone (5 µW/cm²)", 0.05),
          level("laser_free_zone", "laser-free flight zone (50 nW/cm²)", 5e-4)};
}

std::string levelNameProblem(const std::string& name) {
  if (name.empty() || !(name[0] >= 'a' && name[0] <= 'z') ||
      !std::all_of(name.begin(), name.end(), [](char c) {
        return (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_';
      })) {
    return "must be lower-case letters, digits and '_', starting with a letter (it names the "
           "level's keys and channels)";
  }
  if (name.size() > 64)
    return "must be at most 64 characters (it names the level's keys and channels)";
  if (name == "aided" || name == "mpe" || name == "hazard") {
    return "is the name of the MPE's own entries; choose another";
  }
  return {};
}

}  // namespace glint
