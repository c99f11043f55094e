#pragma once
/// @file
/// @brief The laser-safety standard a run's limits follow, as a value: its name and the
/// clauses and tables each limit comes from, so that every limit, message and output cites the
/// same words from one place.

#include <cstdint>

namespace glint {

/// @brief The standards glint knows. ANSI Z136.1-2014 is the default (IEC 60825-1:2014 is
/// planned: its point-source table agrees with ANSI's for the rows glint uses, its rules for
/// repeated pulses are worded apart).
enum class SafetyStandard : std::uint8_t {
  AnsiZ136_1_2014,  ///< American National Standard for Safe Use of Lasers, 2014
};

/// @brief Where in a standard each limit glint applies is written.
struct StandardClauses {
  const char* name;              ///< as outputs cite it, e.g. "ANSI Z136.1-2014"
  const char* point_source_mpe;  ///< the table of ocular MPEs for a point source
  const char* repeated_pulses;   ///< the clause of the rules for pulse trains
  const char* optical_aids;      ///< the clause on viewing through optics
};

/// @brief The clauses of @p standard.
const StandardClauses& clauses(SafetyStandard standard);

}  // namespace glint
