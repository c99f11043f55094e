#pragma once
/// @file
/// @brief Numbers and durations as messages, summaries and the terminal print them.

#include <string>

namespace glint {

/// @brief @p x through a printf format with one double conversion ("%.3g").
std::string formatNumber(const char* fmt, double x);

/// @brief "1.23 s", "4 min 05 s", "2 h 07 min": a duration for people.
std::string formatDuration(double seconds);

}  // namespace glint
