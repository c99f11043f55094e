#pragma once
/// @file
/// @brief `glint run`: the adaptive hazard volume over the scene's observer box (the main job)
/// and the maps over its observer planes.

#include <cstdint>
#include <optional>
#include <ostream>
#include <string>
#include <string_view>
#include <vector>

#include "export/exr_map.h"
#include "export/field_files.h"
#include "observers/far_field.h"
#include "observers/field.h"
#include "observers/reach.h"
#include "pipeline/input/scene.h"

namespace glint {

/// @brief The arguments of `glint run`.
struct RunArgs {
  std::string scene_path;
  std::string out_dir;   ///< empty: out/<scene file stem> (out/<stem>_uniform for --uniform)
  bool uniform = false;  ///< the dense twin: every lattice point evaluated
  int threads = 0;       ///< 0: all cores
  bool quiet = false;    ///< no progress, no summary
  bool terminal = false;
  std::uint64_t memory_bytes = 0;           ///< the memory budget; 0: defaultMemoryBudgetBytes()
  std::optional<IntegrationScheme> scheme;  ///< overrides the scene's accuracy.scheme
};

/// @brief Runs the command: writes irradiance.vdb, irradiance.vti, irradiance.vthb (and its
/// folder), blocks.vtu and target.vtp for the box, `<name>.exr` for each plane, and
/// summary.json into the output folder, each whole or not at all.
/// @throw InputError, OutputError on bad input or an unwritable folder.
/// Under MPI (@p exchange with more than one rank) every rank computes the same fields, sharing
/// their points; rank 0 alone reports and writes, the same bytes as one process would.
void runScene(const RunArgs& args, std::ostream& err, PointExchange* exchange = nullptr);

}  // namespace glint
