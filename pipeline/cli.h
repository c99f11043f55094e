#pragma once
/// @file
/// @brief The `glint` command line.

#include <ostream>

namespace glint {

/// @brief Runs glint with the given arguments, printing results to @p out and messages to
/// @p err.
/// @return the exit status: 0 success, 2 bad input (scene, points, command line) or an output
/// that cannot be written, 1 an internal error.
int runGlint(int argc, const char* const* argv, std::ostream& out, std::ostream& err);

}  // namespace glint
