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
#include "pipeline/scene.h"

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
void runField(const RunArgs& args, std::ostream& err, PointExchange* exchange = nullptr);

/// @brief What the files of a run of @p scene record about it: the program, the scene file and
/// the hash of its text @p scene_text, the scheme ("adaptive" or "uniform"), the laser and MPE.
RunInfo runInfo(const Scene& scene, const std::string& scene_file, std::string_view scene_text,
                const std::string& scheme);

/// @brief Refuses a field with a non-finite value or statistic before anything is written:
/// no NaN or infinity may reach an output, nor read as "no hazard".
/// @throw std::runtime_error (an internal error: within pipeline/limits.h none can occur).
void requireFinite(const ObserverField& field, const std::string& region);

struct SceneTarget;
class MemoryWatch;

/// @brief The far field of @p target as @p scene asks (scene.far_field), with progress on
/// @p progress_to unless null. Refused before the work when its faces' memory floor exceeds
/// @p watch's budget, during it when @p watch stops the work (the message naming @p what),
/// and after it when a direction's intensity is not finite.
/// @throw InputError (the memory budget), std::runtime_error (a non-finite intensity).
FarField sceneFarField(const SceneTarget& target, const Scene& scene, const MemoryWatch& watch,
                       const std::string& what, std::ostream* progress_to, bool terminal,
                       PointExchange* exchange = nullptr);

/// @brief The hazard reach of a scene (observers/reach.h): its lattices about the lit ball of
/// @p far out to its far radius, summarized per threshold (the MPE, then the aided MPE).
struct SceneReach {
  NearReach near;
  std::vector<ReachSummary> summaries;
  double seconds = 0.0;
};

/// @brief Computes the scene's hazard reach beside its far field @p far (sceneFarField()):
/// refused before its lattices are allocated if one face's and the far field's memory would
/// pass the budget; with progress on @p progress_to ("reach points") unless null.
/// @throw InputError (the memory budget).
SceneReach sceneReach(const SceneTarget& target, const Scene& scene, const FarField& far,
                      const MemoryWatch& watch, const std::string& what, std::ostream* progress_to,
                      bool terminal, PointExchange* exchange = nullptr);

}  // namespace glint
