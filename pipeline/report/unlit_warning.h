#pragma once
/// @file
/// @brief The warning of a target the beam does not light: its result is empty because nothing
/// reflects, which says nothing of the hazard, and must not be read as "safe".

#include <string>
#include <vector>

#include "facets/integrator.h"
#include "pipeline/input/scene.h"

namespace glint {

/// @brief What @p scene's culled target (@p cull) calls for: when no facet of it is lit, one
/// warning saying so and why (outside the beam, behind the laser, facing away from it, in the
/// terrain's shadow; an object or the laser below the ground); otherwise none. For the
/// terminal and the `warnings` of summary.json and result.json.
std::vector<std::string> unlitTargetWarnings(const Scene& scene, const CullStats& cull);

}  // namespace glint
