#include "hazard/mpe.h"

#include <cmath>
#include <stdexcept>
#include <string>

// Every branch below is a row of a standard's MPE table, converted from J/cm² and W/cm² to
// J/m² and W/m² (× 10⁴):
// - the eye: ANSI Z136.1-2014 Table 5a, "Maximum Permissible Exposure (MPE) for point source
//   ocular exposure to a laser beam", with the correction factors of its Table 6; IEC
//   60825-1:2014 Table A.1 (α ≤ α_min, C6 = 1), whose rows for 400 nm to 1 mm give the same
//   values save the correction factor of 1150–1400 nm (C7 against ANSI's C_C);
// - the skin: ANSI Z136.1-2014 Table 7 and IEC 60825-1:2014 Table A.5, alike over 400 nm to 1 mm.
//
// Durations stop at 1 ns: below it the two standards' editions differ (ANSI 2014 has 1e-13 to
// 1e-11 s rows that IEC words differently), and a safety tool refuses rather than picks.

namespace glint {
namespace {

constexpr double kMinWavelengthNm = 400.0;
constexpr double kMaxWavelengthNm = 1.0e6;  // 1 mm
constexpr double kMinExposureS = 1.0e-9;
constexpr double kMaxExposureS = 3.0e4;

// C_A (IEC: C4): 1 over 400–700 nm, 10^(0.002 (λ − 700)) over 700–1050 nm, 5 over 1050–1400 nm.
double cA(double nm) {
  if (nm <= 700.0) return 1.0;
  if (nm < 1050.0) return std::pow(10.0, 0.002 * (nm - 700.0));
  return 5.0;
}

// C_B (IEC: C3): 1 over 400–450 nm, 10^(0.02 (λ − 450)) over 450–600 nm.
double cB(double nm) { return nm <= 450.0 ? 1.0 : std::pow(10.0, 0.02 * (nm - 450.0)); }

// 1050–1400 nm: 1 to 1150 nm, 10^(0.018 (λ − 1150)) to 1200 nm, and beyond 1200 nm 8 by ANSI
// Z136.1-2014 Table 6 (C_C), 8 + 10^(0.04 (λ − 1250)) by IEC 60825-1:2014 (C7), which climbs
// to 10⁶ at 1400 nm as the ocular media absorb what would reach the retina.
double cC(double nm, SafetyStandard standard) {
  if (nm <= 1150.0) return 1.0;
  if (nm < 1200.0) return std::pow(10.0, 0.018 * (nm - 1150.0));
  if (clauses(standard).near_ir_factor_climbs) return 8.0 + std::pow(10.0, 0.04 * (nm - 1250.0));
  return 8.0;
}

Mpe fromExposure(double h_j_m2, double t_s, MpeLimit limit, std::string rule) {
  return {h_j_m2 / t_s, h_j_m2, limit, std::move(rule)};
}
Mpe fromIrradiance(double e_w_m2, double t_s, MpeLimit limit, std::string rule) {
  return {e_w_m2, e_w_m2 * t_s, limit, std::move(rule)};
}

// Retinal thermal, 400–1050 nm.
Mpe retinalVisibleNearIr(double nm, double t) {
  const double ca = cA(nm);
  const char* band = nm <= 700.0 ? "400-700 nm" : "700-1050 nm";
  if (t < 5e-6) {  // 1e-11 to 5e-6 s: 2.0 C_A × 10⁻⁷ J/cm²
    return fromExposure(2.0e-3 * ca, t, MpeLimit::Thermal,
                        std::string(band) + ", 1e-11 to 5e-6 s: 2.0e-3 C_A J/m^2");
  }
  if (t < 10.0) {  // 5e-6 to 10 s: 1.8 C_A t^0.75 × 10⁻³ J/cm²
    return fromExposure(18.0 * ca * std::pow(t, 0.75), t, MpeLimit::Thermal,
                        std::string(band) + ", 5e-6 to 10 s: 18 C_A t^0.75 J/m^2");
  }
  // 10 to 3e4 s (T2 = 10 s for a point source): C_A × 10⁻³ W/cm²
  return fromIrradiance(10.0 * ca, t, MpeLimit::Thermal,
                        std::string(band) + ", 10 to 3e4 s: 10 C_A W/m^2");
}

// Retinal photochemical, 400–600 nm, 10 s and beyond (dual limit with the thermal one).
Mpe retinalPhotochemical(double nm, double t) {
  const double cb = cB(nm);
  if (t < 100.0) {  // 10 to 100 s: 1 C_B × 10⁻² J/cm²
    return fromExposure(100.0 * cb, t, MpeLimit::Photochemical,
                        "400-600 nm, 10 to 100 s: 100 C_B J/m^2 (photochemical)");
  }
  // 100 to 3e4 s: 1 C_B × 10⁻⁴ W/cm²
  return fromIrradiance(cb, t, MpeLimit::Photochemical,
                        "400-600 nm, 100 to 3e4 s: C_B W/m^2 (photochemical)");
}

// Retinal thermal, 1050–1400 nm.
Mpe retinalNearIr(double nm, double t, SafetyStandard standard) {
  const double cc = cC(nm, standard);
  const std::string factor = clauses(standard).near_ir_factor;
  if (t < 13e-6) {  // 1e-11 to 13e-6 s: 2.0 C_C × 10⁻⁶ J/cm²
    return fromExposure(2.0e-2 * cc, t, MpeLimit::Thermal,
                        "1050-1400 nm, 1e-11 to 1.3e-5 s: 2.0e-2 " + factor + " J/m^2");
  }
  if (t < 10.0) {  // 13e-6 to 10 s: 9.0 C_C t^0.75 × 10⁻³ J/cm²
    return fromExposure(90.0 * cc * std::pow(t, 0.75), t, MpeLimit::Thermal,
                        "1050-1400 nm, 1.3e-5 to 10 s: 90 " + factor + " t^0.75 J/m^2");
  }
  // 10 to 3e4 s: 5.0 C_C × 10⁻³ W/cm² (IEC: 10 C4 C7 W/m², C4 = 5)
  return fromIrradiance(50.0 * cc, t, MpeLimit::Thermal,
                        "1050-1400 nm, 10 to 3e4 s: 50 " + factor + " W/m^2");
}

// Corneal and lens thermal, 1.4 µm to 1 mm: a constant radiant exposure up to `flat_until_s`,
// then 0.56 t^0.25 J/cm² up to 10 s, then 0.1 W/cm² (the eye, and the skin where it lights
// less than 0.01 m²) or 0.01 W/cm² (the skin over more than 0.1 m²).
struct InfraredBand {
  const char* name;
  double flat_until_s;
  double flat_j_m2;
  const char* flat_rule;
};

Mpe infrared(const InfraredBand& band, double t, Tissue tissue) {
  const std::string name = band.name;
  if (t < band.flat_until_s) {
    return fromExposure(band.flat_j_m2, t, MpeLimit::Thermal, name + ", " + band.flat_rule);
  }
  if (t < 10.0) {  // to 10 s: 0.56 t^0.25 J/cm²
    return fromExposure(5600.0 * std::pow(t, 0.25), t, MpeLimit::Thermal,
                        name + ", to 10 s: 5600 t^0.25 J/m^2");
  }
  if (tissue == Tissue::Skin) {
    // The skin's table relaxes to 1000 W/m² for areas below 0.01 m² lit; glint does not know
    // the area a glint lights, so it takes the limit of the largest areas.
    return fromIrradiance(100.0, t, MpeLimit::Thermal,
                          name + ", 10 to 3e4 s, lit area above 0.1 m^2: 100 W/m^2");
  }
  return fromIrradiance(1000.0, t, MpeLimit::Thermal, name + ", 10 to 3e4 s: 1000 W/m^2");
}

constexpr InfraredBand kIr1400{"1400-1500 nm", 1e-3, 1.0e3, "to 1e-3 s: 1000 J/m^2"};
constexpr InfraredBand kIr1500{"1500-1800 nm", 10.0, 1.0e4, "to 10 s: 1e4 J/m^2"};
constexpr InfraredBand kIr1800{"1800-2600 nm", 1e-3, 1.0e3, "to 1e-3 s: 1000 J/m^2"};
constexpr InfraredBand kIr2600{"2600 nm-1 mm", 1e-7, 1.0e2, "to 1e-7 s: 100 J/m^2"};

// The skin, 400–1400 nm: 2 C_A × 10⁻² J/cm² to 100 ns, 1.1 C_A t^0.25 J/cm² to 10 s,
// 0.2 C_A W/cm² beyond.
Mpe skinVisibleNearIr(double nm, double t) {
  const double ca = cA(nm);
  if (t < 1e-7) {
    return fromExposure(200.0 * ca, t, MpeLimit::Thermal, "400-1400 nm, to 1e-7 s: 200 C_A J/m^2");
  }
  if (t < 10.0) {
    return fromExposure(1.1e4 * ca * std::pow(t, 0.25), t, MpeLimit::Thermal,
                        "400-1400 nm, 1e-7 to 10 s: 1.1e4 C_A t^0.25 J/m^2");
  }
  return fromIrradiance(2000.0 * ca, t, MpeLimit::Thermal,
                        "400-1400 nm, 10 to 3e4 s: 2000 C_A W/m^2");
}

// A band of a table: both ends included; where two name the same wavelength the lower MPE
// holds (at 1400 nm the retinal row is far below the corneal one).
struct Band {
  double from_nm, to_nm;
  Mpe (*mpe)(double nm, double t, SafetyStandard standard, Tissue tissue);
};

Mpe visibleEye(double nm, double t, SafetyStandard, Tissue) {
  Mpe thermal = retinalVisibleNearIr(nm, t);
  if (t < 10.0 || nm > 600.0) return thermal;
  Mpe photochemical = retinalPhotochemical(nm, t);
  return photochemical.irradiance_w_m2 < thermal.irradiance_w_m2 ? photochemical : thermal;
}

// Beyond 1400 nm the cornea's and lens's rows, the same for the eye and (but beyond 10 s) the
// skin.
const Band kInfraredBands[] = {
    {1400.0, 1500.0,
     [](double, double t, SafetyStandard, Tissue k) { return infrared(kIr1400, t, k); }},
    {1500.0, 1800.0,
     [](double, double t, SafetyStandard, Tissue k) { return infrared(kIr1500, t, k); }},
    {1800.0, 2600.0,
     [](double, double t, SafetyStandard, Tissue k) { return infrared(kIr1800, t, k); }},
    {2600.0, kMaxWavelengthNm,
     [](double, double t, SafetyStandard, Tissue k) { return infrared(kIr2600, t, k); }},
};

const Band kRetinalBands[] = {
    {400.0, 1050.0, visibleEye},
    {1050.0, 1400.0,
     [](double nm, double t, SafetyStandard s, Tissue) { return retinalNearIr(nm, t, s); }},
};

// IEC's C7 lets the retinal limit climb a millionfold towards 1400 nm, where the cornea and
// lens absorb instead. Its table has no anterior-eye row below 1400 nm; glint applies the
// 1400–1500 nm row there as well (the lower holds), so that the limit never rises above the
// one just past 1400 nm (docs/hazard.md).
const Band kIecAnteriorEyeBand{
    1200.0, 1400.0, [](double, double t, SafetyStandard, Tissue k) {
      Mpe m = infrared(kIr1400, t, k);
      m.rule = "1200-1400 nm, as 1400-1500 nm (glint: the anterior eye beside C7): " +
               m.rule.substr(m.rule.find(", ") + 2);
      return m;
    }};

const Band kSkinVisibleNearIrBand{400.0, 1400.0, [](double nm, double t, SafetyStandard, Tissue) {
                                    return skinVisibleNearIr(nm, t);
                                  }};

}  // namespace

Mpe tableMpe(double wavelength_nm, double exposure_s, SafetyStandard standard, Tissue tissue) {
  if (!(wavelength_nm >= kMinWavelengthNm && wavelength_nm <= kMaxWavelengthNm)) {
    throw std::out_of_range("the MPE table covers wavelengths from 400 nm to 1 mm; got " +
                            std::to_string(wavelength_nm) + " nm");
  }
  if (!(exposure_s >= kMinExposureS && exposure_s <= kMaxExposureS)) {
    throw std::out_of_range("the MPE table covers exposures from 1e-9 s to 3e4 s; got " +
                            std::to_string(exposure_s) + " s");
  }
  bool found = false;
  Mpe lowest;
  const auto consider = [&](const Band& band) {
    if (wavelength_nm < band.from_nm || wavelength_nm > band.to_nm) return;
    Mpe m = band.mpe(wavelength_nm, exposure_s, standard, tissue);
    if (!found || m.irradiance_w_m2 < lowest.irradiance_w_m2) lowest = std::move(m);
    found = true;
  };
  if (tissue == Tissue::Skin) {
    consider(kSkinVisibleNearIrBand);
  } else {
    for (const Band& band : kRetinalBands) consider(band);
    if (clauses(standard).anterior_eye_limit) consider(kIecAnteriorEyeBand);
  }
  for (const Band& band : kInfraredBands) consider(band);
  lowest.standard = standard;
  lowest.tissue = tissue;
  return lowest;
}

Mpe ocularMpe(double wavelength_nm, double exposure_s, SafetyStandard standard) {
  return tableMpe(wavelength_nm, exposure_s, standard, Tissue::Eye);
}

Mpe skinMpe(double wavelength_nm, double exposure_s, SafetyStandard standard) {
  return tableMpe(wavelength_nm, exposure_s, standard, Tissue::Skin);
}

const std::vector<double>& mpeRowEdgesS() {
  // Where the rows above change: the visible and near-infrared retinal rows (5 µs, 13 µs,
  // 10 s), the photochemical (100 s), the corneal bands' flat parts (100 ns, 1 ms, 10 s) and
  // the skin's (100 ns, 10 s).
  static const std::vector<double> edges{1e-7, 5e-6, 13e-6, 1e-3, 10.0, 100.0};
  return edges;
}

const char* toString(MpeLimit limit) {
  return limit == MpeLimit::Photochemical ? "photochemical" : "thermal";
}

std::string mpeCitation(const Mpe& mpe) {
  return std::string(clauses(mpe.standard).name) + " " + mpeTable(mpe.standard, mpe.tissue) + ": " +
         mpe.rule;
}

}  // namespace glint
