#pragma once
/// @file
/// @brief The ocular Maximum Permissible Exposure for a point source (ANSI Z136.1-2014
/// Table 5a, harmonised with IEC 60825-1:2014 Table A.1).

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
};

/// @brief The ocular MPE for intrabeam (point-source) viewing of a single exposure of
/// @p exposure_s seconds at @p wavelength_nm.
///
/// A glint is treated as a point source (apparent angular subtense ≤ α_min = 1.5 mrad): that
/// is the most restrictive case, so the MPE is conservative for larger apparent sources.
/// Repetitive pulses and extended-source relaxations are not modelled.
/// Valid for 400 nm ≤ wavelength ≤ 1 mm and 1 ns ≤ exposure ≤ 30 000 s; anything else throws
/// std::out_of_range naming the range: the table is never extrapolated.
Mpe ocularMpe(double wavelength_nm, double exposure_s,
              SafetyStandard standard = SafetyStandard::AnsiZ136_1_2014);

/// @brief The durations (s) at which some row of the table begins, at any wavelength, in
/// increasing order. Between two of them every row is a constant or a power of t with a
/// non-negative exponent as radiant exposure, so there the MPE in J/m² never falls as the
/// duration grows; at one of them it may (ANSI Z136.1-2014 Table 5a: 2.0e-3 J/m² to 5 µs,
/// 18 t^0.75 J/m² = 1.9e-3 J/m² from 5 µs at 400–700 nm).
const std::vector<double>& mpeRowEdgesS();

/// @brief The table row of @p mpe with the standard's and the table's name, as outputs record
/// it.
std::string mpeCitation(const Mpe& mpe);

/// @brief "thermal" or "photochemical".
const char* toString(MpeLimit limit);

}  // namespace glint
