#pragma once
/// @file
/// @brief The Maximum Permissible Exposure for a point source, for the eye or the skin, under
/// ANSI Z136.1-2014 (Tables 5a and 7) or IEC 60825-1:2014 (Tables A.1 and A.5).

#include <string>
#include <vector>

#include "hazard/standard.h"

namespace glint {

/// @brief Which biological limit set the MPE.
enum class MpeLimit {
  Thermal,        ///< retinal thermal (400–1400 nm) or corneal/lens thermal (beyond 1400 nm)
  Photochemical,  ///< retinal photochemical (400–600 nm, beyond 10 s): the lower of the two won
};

/// @brief The MPE of one exposure, averaged over its duration.
struct Mpe {
  double irradiance_w_m2 = 0.0;        ///< MPE as mean irradiance over the exposure
  double radiant_exposure_j_m2 = 0.0;  ///< the same limit as energy per area (irradiance × t)
  MpeLimit limit = MpeLimit::Thermal;
  std::string
      rule;  ///< the table row that applied, e.g. "400-700 nm, 5e-6-10 s: 18 C_A t^0.75 J/m²"
  SafetyStandard standard = SafetyStandard::AnsiZ136_1_2014;  ///< whose table the row is
  Tissue tissue = Tissue::Eye;                                ///< which of its tables
};

/// @brief The MPE of @p standard for @p tissue, a single exposure of @p exposure_s seconds at
/// @p wavelength_nm.
///
/// For the eye, intrabeam (point-source) viewing: a glint is treated as a point source
/// (apparent angular subtense ≤ α_min = 1.5 mrad), the most restrictive case, so the MPE is
/// conservative for larger apparent sources. For the skin beyond 10 s at 1.4 µm to 1 mm, the
/// limit of lit areas above 0.1 m² (glint does not know the area a glint lights).
/// Repetitive pulses are applied by pulseTrainMpe() (hazard/hazard.h).
/// Valid for 400 nm ≤ wavelength ≤ 1 mm and 1 ns ≤ exposure ≤ 30 000 s; anything else throws
/// std::out_of_range naming the range: the tables are never extrapolated.
Mpe tableMpe(double wavelength_nm, double exposure_s, SafetyStandard standard, Tissue tissue);

/// @brief The ocular MPE for intrabeam (point-source) viewing: tableMpe() for the eye.
Mpe ocularMpe(double wavelength_nm, double exposure_s,
              SafetyStandard standard = SafetyStandard::AnsiZ136_1_2014);

/// @brief The skin's MPE: tableMpe() for the skin.
Mpe skinMpe(double wavelength_nm, double exposure_s,
            SafetyStandard standard = SafetyStandard::AnsiZ136_1_2014);

/// @brief The durations (s) at which some row of the tables begins, at any wavelength, for
/// either standard and tissue, in increasing order. Between two of them every row is a constant or
/// a power of t with a non-negative exponent as radiant exposure, so there the MPE in J/m² never
/// falls as the duration grows; at one of them it may (ANSI Z136.1-2014 Table 5a: 2.0e-3 J/m² to 5
/// µs, 18 t^0.75 J/m² = 1.9e-3 J/m² from 5 µs at 400–700 nm).
const std::vector<double>& mpeRowEdgesS();

/// @brief The table row of @p mpe with the standard's and the table's name, as outputs record
/// it.
std::string mpeCitation(const Mpe& mpe);

/// @brief "thermal" or "photochemical".
const char* toString(MpeLimit limit);

}  // namespace glint
