#pragma once
/// @file
/// @brief The ball around a target's lit facets.

#include "facets/integrator.h"

namespace glint {

/// @brief The ball around the lit facets: where their light spreads from (the far field's origin
/// and size, the adaptive field's centre of spread, the reach's centre).
struct LitBall {
  /// The centre of the lit facets' corners' bounding box: distances and directions of the far
  /// field and the reach are taken from here.
  Vec3 centre_m{0.0};
  double radius_m = 0.0;  ///< holds every lit curved patch (their bounding balls)
};

/// @brief The ball of @p integrator's lit facets; radius 0 when nothing is lit.
LitBall litBall(const FacetIntegrator& integrator);

}  // namespace glint
