#pragma once
/// @file
/// @brief The regions a command computes from a scene, as `glint run` and a study's scenarios
/// both compute them: an observer field (the box or a plane), the far field and the hazard
/// reach, each watched against the memory budget, shown as progress and refused when a value
/// is not finite (nothing of it may then be written).

#include <ostream>
#include <string>
#include <vector>

#include "facets/target.h"
#include "observers/far_field.h"
#include "observers/field.h"
#include "observers/reach.h"
#include "pipeline/setup/target_builder.h"
#include "pipeline/setup/work_watch.h"

namespace glint {

/// @brief The centre of the target's bounding box: the nominal hazard zone's reach is measured
/// from it.
Vec3 targetCentre(const Target& target);

/// @brief The field of @p problem over @p spec (the dense twin with @p dense), with progress
/// counting @p noun ("points", a plane's name).
/// @throw InputError when the memory watch stops the work; std::runtime_error when a value is
/// not finite (requireFinite()).
ObserverField sceneField(const FieldProblem& problem, const FieldSpec& spec, bool dense,
                         const WorkWatch& w, const char* noun);

/// @brief Refuses a field with a non-finite value or statistic before anything is written:
/// no NaN or infinity may reach an output, nor read as "no hazard".
/// @throw std::runtime_error (an internal error: within pipeline/base/limits.h none can occur).
void requireFinite(const ObserverField& field, const std::string& region);

/// @brief "the far field (6 × N² directions)": the far field of @p spec in a message.
std::string farFieldDescription(const FarFieldSpec& spec);

/// @brief The far field of @p target as @p scene asks (scene.far_field). Refused before the
/// work when its faces' memory floor exceeds the budget, during it when the watch stops the
/// work, and after it when a direction's intensity is not finite.
/// @throw InputError (the memory budget), std::runtime_error (a non-finite intensity).
FarField sceneFarField(const SceneTarget& target, const Scene& scene, const WorkWatch& w);

/// @brief The hazard reach of a scene (observers/reach.h): its lattices about the lit ball of
/// the far field out to its far radius, summarized per threshold (the MPE, then the aided MPE).
struct SceneReach {
  NearReach near;
  std::vector<ReachSummary> summaries;
  double seconds = 0.0;          ///< the lattice's
  double summary_seconds = 0.0;  ///< the summaries' (each threshold's reach and volume)
};

/// @brief Computes the scene's hazard reach beside its far field @p far (sceneFarField()):
/// refused before its lattices are allocated if one face's and the far field's memory would
/// pass the budget; with progress ("reach points") where the watch shows it.
/// @throw InputError (the memory budget).
SceneReach sceneReach(const SceneTarget& target, const Scene& scene, const FarField& far,
                      const FarHazard& beyond, const WorkWatch& w);

}  // namespace glint
