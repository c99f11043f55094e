#pragma once
/// @file
/// @brief `glint points`: irradiance at observer points from a CSV file.

#include <cstdint>
#include <optional>
#include <ostream>
#include <string>

#include "facets/integrator.h"  // IntegrationScheme

namespace glint {

class PointExchange;

/// @brief The arguments of `glint points`.
struct PointsArgs {
  std::string scene_path;
  std::string points_path;
  std::string out_path = "-";               ///< "-" writes the table to standard output
  std::optional<double> tolerance;          ///< overrides the scene's accuracy.tolerance
  std::optional<int> uniform_level;         ///< the uniform twin instead of adaptive refinement
  std::optional<NormalModel> normals;       ///< overrides the scene's accuracy.normals
  std::optional<IntegrationScheme> scheme;  ///< overrides the scene's accuracy.scheme
  int threads = 0;                          ///< 0: all cores
  bool quiet = false;                       ///< no progress, no summary
  bool terminal = false;                    ///< standard error is a terminal (progress redraws)
  std::uint64_t memory_bytes = 0;           ///< the memory budget; 0: defaultMemoryBudgetBytes()
  /// With an engagement: every observer's irradiance samples to this CSV file as well.
  std::optional<std::string> time_series_path;
};

/// @brief Runs the command. Inputs are validated and the output file opened before any work.
/// Under MPI (@p exchange with more than one rank) the ranks share the observers; rank 0 alone
/// reports and writes, the same bytes as one process would.
/// @throw InputError, OutputError on bad input or unwritable output (no file is left behind).
void runPoints(const PointsArgs& args, std::ostream& out, std::ostream& err,
               PointExchange* exchange = nullptr);

}  // namespace glint
