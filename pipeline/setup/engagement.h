#pragma once
/// @file
/// @brief An engagement computed (docs/engagement.md): each observer's irradiance over the span
/// sampled in time and judged (its worst window, or its train of pulses), and the maps of a
/// plane or the box that glint run and a study's scenarios write
/// (report/engagement_report.h reports them).

#include <cstdint>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "export/exr_map.h"
#include "export/lattice_vdb.h"
#include "hazard/exposure_train.h"
#include "observers/exposure.h"
#include "pipeline/input/scene.h"
#include "pipeline/setup/work_watch.h"

namespace glint {

/// @brief Each observer's history and its verdict.
struct EngagementResults {
  std::vector<ExposureHistory> histories;
  std::vector<ExposureVerdict> verdicts;
  double seconds = 0.0;
};

/// @brief The scene's engagement at @p points (their places at t = 0), sampled in time by
/// integrateExposures() from @p reference and judged, watched and shown as @p w says (its
/// `what` names the points in a message). Under MPI (`w.exchange`) the ranks share the points,
/// and every rank receives every history.
/// @throw std::runtime_error when the memory watch stops the work.
EngagementResults sampleEngagement(const FacetIntegrator& reference, const Scene& scene,
                                   std::span<const Vec3> points, const WorkWatch& w);

/// @brief Judges every history of @p histories under the scene's hazard and engagement.
EngagementResults judgeEngagement(std::vector<ExposureHistory> histories, const Scene& scene);

/// @brief An engagement's maps over one region of `glint run` (a plane or the box), arrays
/// indexed as the lattice's points, [(k × nodes[1] + j) × nodes[0] + i]: each point's exposure,
/// peak, time above the MPE, verdict (hazard_ratio, the larger of the worst window's and the
/// train's) and the rule that sets it, the pulses rule 3 counted, the worst window's length,
/// the stare verdict, and its status (1 integrated, 3 dark over the whole span by the bound, 5
/// integrated but unconverged).
struct EngagementMaps {
  PlaneGrid grid;  ///< a plane's (its first two axes for the box)
  std::vector<float> exposure_j_m2, peak_irradiance_w_m2, time_above_mpe_s, hazard_ratio,
      hazard_rule, pulses, aided_hazard_ratio, stare_hazard_ratio, worst_window_s, status;
  /// Per level of the scene (HazardSpec::levels): its channel's name, `time_above_<level>_s`,
  /// and how long each point's irradiance is at or above the level's threshold.
  std::vector<std::pair<std::string, std::vector<float>>> time_above_level_s;
  std::vector<std::int64_t> level_reached;  ///< per level: points where that time is above 0
  std::int64_t integrated = 0;              ///< lattice points sampled in time
  std::int64_t hazardous = 0;               ///< hazard_ratio ≥ 1
  std::int64_t train_decides = 0;           ///< points whose verdict rule 3 sets
  std::int64_t stare_hazardous = 0;         ///< stare_hazard_ratio ≥ 1
  std::int64_t aided_hazardous = 0;         ///< aided_hazard_ratio ≥ 1 (with an aid)
  std::int64_t unconverged = 0;
  /// @brief The EXR channels, in the order the file holds them.
  [[nodiscard]] std::vector<ExrChannel> channels() const;
  /// @brief The same as the box's VDB grids, with their units.
  [[nodiscard]] std::vector<LatticeChannel> latticeChannels() const;
};

/// @brief The maps of the plane @p spec, whose lattice points @p lit (flags indexed [j × width +
/// i]) were integrated in that order into @p results; the others are dark.
EngagementMaps engagementMaps(const FieldSpec& spec, std::span<const std::uint8_t> lit,
                              const EngagementResults& results, const HazardSpec& hazard);

/// @brief One region (a plane or the box) of an engagement as glint run and a study's scenario
/// compute it: the lattice points no bound can prove dark (in lattice order), their histories
/// and the maps.
struct EngagementRegion {
  std::vector<Vec3> points;
  EngagementResults results;
  EngagementMaps maps;
};

/// @brief Maps the engagement of @p scene over the lattice @p spec (a plane's or the box's):
/// culled by litByBound(), the rest sampled by sampleEngagement() from the integrator of
/// @p target at the scene's accuracy, watched as @p w says (its `what` names the region);
/// results.seconds counts the culling too.
/// @throw std::runtime_error when the memory watch stops the work or a map value is not finite
/// (nothing may then be written).
EngagementRegion engagementRegion(const FacetIntegrator& target, const Scene& scene,
                                  const FieldSpec& spec, const WorkWatch& w);

}  // namespace glint
