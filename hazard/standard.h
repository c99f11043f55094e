#pragma once
/// @file
/// @brief The laser-safety standard a run's limits follow, and the tissue they protect, as
/// values: each standard's name, edition and the clauses and tables each limit comes from, so
/// that every limit, message and output cites the same words from one place.

#include <cstdint>
#include <optional>
#include <string_view>

namespace glint {

/// @brief The standards glint knows (scene key `hazard.standard`). ANSI Z136.1-2014 is the
/// default. Their point-source tables agree for most rows glint uses; they differ in the
/// correction factor of 1200–1400 nm and in the reduction for repeated pulses (docs/hazard.md).
enum class SafetyStandard : std::uint8_t {
  AnsiZ136_1_2014,  ///< American National Standard for Safe Use of Lasers, 2014
  Iec60825_1_2014,  ///< Safety of laser products, Part 1, edition 3.0 (2014), Annex A
};

/// @brief What the limits protect (scene key `hazard.tissue`): the eye (the default) or the
/// skin, for close-range work with high powers.
enum class Tissue : std::uint8_t { Eye, Skin };

/// @brief A standard as every rule of glint reads it: where each limit is written, and each way
/// in which the standards glint knows differ. A rule asks the clauses of its run's standard,
/// never which standard it is, so a standard added to kStandards is applied everywhere or
/// refused by the compiler (a field left out of its entry).
struct StandardClauses {
  const char* name;              ///< as outputs cite it and scene files name it
  int edition_year;              ///< the edition's year
  const char* point_source_mpe;  ///< the table of ocular MPEs for a point source
  const char* skin_mpe;          ///< the table of MPEs for the skin
  const char* repeated_pulses;   ///< the clause of the rules for pulse trains
  const char* optical_aids;      ///< the clause on viewing through optics

  // The retinal near infrared, 1200–1400 nm.
  const char* near_ir_factor;  ///< the correction factor's name (ANSI C_C, IEC C7)
  /// Whether that factor climbs beyond 1250 nm as 8 + 10^(0.04 (λ − 1250)) (IEC's C7) rather
  /// than staying 8 (ANSI's C_C).
  bool near_ir_factor_climbs;
  /// Whether a separate limit protects the eye's anterior parts in 1200–1400 nm (IEC).
  bool anterior_eye_limit;

  // Rule 3 (repeated pulses): the single-pulse limit reduced to scale × N^-0.25, at least
  // floor, once more than from_pulses pulses are counted within window_s (the exposure if
  // shorter); with only_within_t_i only for pulses no longer than T_i.
  const char* rule_three_factor;   ///< the reduction's name (ANSI C_P, IEC C5)
  const char* rule_three_formula;  ///< as citations write it
  const char* rule_three_key;      ///< the summary's key of the reduction
  double rule_three_window_s;      ///< +∞: the whole exposure (ANSI's n)
  double rule_three_from_pulses;   ///< −∞: every count reduces
  double rule_three_scale;
  double rule_three_floor;
  bool rule_three_only_within_t_i;
  /// Whether a citation names the pulses counted (N within T2).
  bool rule_three_cites_count;
};

/// @brief The clauses of @p standard.
const StandardClauses& clauses(SafetyStandard standard);

/// @brief Every standard glint knows, the default first.
inline constexpr SafetyStandard kStandards[] = {SafetyStandard::AnsiZ136_1_2014,
                                                SafetyStandard::Iec60825_1_2014};

/// @brief The table of @p standard that holds the limits for @p tissue.
const char* mpeTable(SafetyStandard standard, Tissue tissue);

/// @brief The standard a scene file names by StandardClauses::name; none when unknown.
std::optional<SafetyStandard> standardNamed(std::string_view name);

/// @brief "eye" or "skin".
const char* toString(Tissue tissue);

}  // namespace glint
