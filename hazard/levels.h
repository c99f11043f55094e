#pragma once
/// @file
/// @brief Irradiance levels judged beside the MPE: the visual-interference levels of the flight
/// zones of outdoor laser operations (ANSI Z136.6, FAA Order JO 7400.2 chapter 29, ICAO Doc
/// 9815), and levels an analyst names (a site's own dazzle or glare rule). Each is the unaided
/// eye's, like the MPE, and compared with the mean irradiance over the exposure; a flight zone's
/// under a pulsed laser with the most light any of its averaging windows holds (docs/hazard.md).

#include <string>
#include <vector>

namespace glint {

/// @brief The band in which the visual levels and the visual correction apply (nm): what the eye
/// sees. Outside it a visual level is refused, not judged.
inline constexpr double kVisibleMinNm = 400.0;
inline constexpr double kVisibleMaxNm = 700.0;

/// @brief The time over which the flight zones' levels average the light (s), the eye's aversion
/// response: their pulsed form, a radiant exposure per pulse, is the level times this
/// (100 µW/cm² and 25 µJ/cm² for the sensitive zone).
inline constexpr double kFlightZoneAveragingS = 0.25;

/// @brief The photopic luminous efficiency V(λ) of the CIE 1924 standard observer at
/// @p wavelength_nm, as tabulated every 5 nm (CIE 018:2019, ISO 23539:2005); between two
/// entries the larger of them, so that the visual correction is never below the curve (V is
/// unimodal: the larger neighbour bounds every value between them).
/// @pre kVisibleMinNm ≤ wavelength_nm ≤ kVisibleMaxNm
double photopicEfficiency(double wavelength_nm);

/// @brief A named irradiance level (scene keys `hazard.flight_zones` and `hazard.levels`).
struct ExposureLevel {
  std::string name;   ///< the outputs' key: `sensitive_zone`, or the analyst's
  std::string label;  ///< the terminal's words for it
  /// The level as its rule states it (W/m²): for a visually corrected level, the effective
  /// irradiance E × VCF.
  double level_w_m2 = 0.0;
  bool visually_corrected = false;  ///< compared with E × VCF, not E
  /// The visual correction factor at the laser's wavelength (photopicEfficiency()); 1 where the
  /// level is not corrected. completeHazard() sets it.
  double visual_correction = 1.0;
  /// The level is a mean over kFlightZoneAveragingS (the flight zones'), not over the exposure,
  /// so a pulsed laser reaches it where its brightest window does.
  bool averaged_over_window = false;
  /// The mean irradiance over the exposure at which the brightest averaging window reaches the
  /// level, as a multiple of the level (flightZonePulseFactor()); 1 for a continuous laser and a
  /// level averaged over the exposure. completeHazard() sets it.
  double pulse_factor = 1.0;
  std::string source;  ///< where the value comes from

  /// @brief The mean irradiance at the eye (W/m²) that reaches the level: level × pulse factor
  /// / VCF.
  [[nodiscard]] double thresholdW_m2() const {
    return level_w_m2 * pulse_factor / visual_correction;
  }
  /// @brief E / threshold: at least 1 where the level is reached.
  [[nodiscard]] double ratio(double irradiance_w_m2) const {
    return irradiance_w_m2 / thresholdW_m2();
  }
};

/// @brief The three visual-interference levels of the flight zones, each visually corrected
/// or not: the sensitive zone (100 µW/cm²), the critical zone (5 µW/cm²) and the laser-free
/// zone (50 nW/cm²). The Normal Flight Zone's limit is the MPE itself.
std::vector<ExposureLevel> flightZoneLevels(bool visual_correction);

/// @brief What a level's name may be: 1 to 64 lower-case letters, digits and '_', starting with a
/// letter, and none of the names the outputs already use for the MPE (`aided`, `mpe`).
/// @return why @p name is refused, or empty where it is fine.
std::string levelNameProblem(const std::string& name);

}  // namespace glint
