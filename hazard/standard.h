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

/// @brief Where in a standard each limit glint applies is written.
struct StandardClauses {
  const char* name;              ///< as outputs cite it and scene files name it
  int edition_year;              ///< the edition's year
  const char* point_source_mpe;  ///< the table of ocular MPEs for a point source
  const char* skin_mpe;          ///< the table of MPEs for the skin
  const char* repeated_pulses;   ///< the clause of the rules for pulse trains
  const char* optical_aids;      ///< the clause on viewing through optics
};

/// @brief The clauses of @p standard.
const StandardClauses& clauses(SafetyStandard standard);

/// @brief The table of @p standard that holds the limits for @p tissue.
const char* mpeTable(SafetyStandard standard, Tissue tissue);

/// @brief The standard a scene file names by StandardClauses::name; none when unknown.
std::optional<SafetyStandard> standardNamed(std::string_view name);

/// @brief "eye" or "skin".
const char* toString(Tissue tissue);

}  // namespace glint
