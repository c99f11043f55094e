#pragma once
/// @file
/// @brief From a validated Scene to what the facet integrator works on.

#include "facets/integrator.h"
#include "pipeline/scene.h"

namespace glint {

/// @brief The scene's laser as a Beam.
Beam beamOf(const Scene& scene);

/// @brief The scene's objects tessellated into coarse facets. Tessellations are oriented by the
/// direction toward the laser, so rotating a whole scene rotates its facets with it.
Target buildTarget(const Scene& scene);

/// @brief The scene's accuracy settings; the floor defaults to 1e-9 × the beam's peak
/// irradiance, far below any exposure limit yet scaled to the scene.
IntegratorOptions integratorOptions(const Scene& scene);

}  // namespace glint
