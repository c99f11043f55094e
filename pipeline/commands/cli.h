#pragma once
/// @file
/// @brief The `glint` command line.

#include <ostream>

namespace glint {

/// @brief glint's exit statuses (docs/usage.md, "Exit status").
enum ExitStatus : int {
  kExitSuccess = 0,
  kExitInternalError = 1,  ///< a bug or a resource failure: never a clean "no hazard"
  kExitBadInput = 2,       ///< scene, points, study or command line; or an unwritable output
  // Interrupted by a signal: 128 + its number (export/atomic_file.h).
};

/// @brief Runs glint with the given arguments, printing results to @p out and messages to
/// @p err.
/// @return the ExitStatus.
int runGlint(int argc, const char* const* argv, std::ostream& out, std::ostream& err);

}  // namespace glint
