#pragma once
// Triangles into an Embree scene, stored in single precision about an origin of the caller's
// (the occluder's and the terrain's scenes).
#include <embree3/rtcore.h>

#include "facets/occluder.h"

namespace glint::detail {

/// @brief Attaches @p mesh to @p scene as one triangle geometry, each vertex stored as
/// float(vertex − @p origin_m). A mesh without triangles attaches nothing.
void attachTriangles(RTCDevice device, RTCScene scene, const ShadowMesh& mesh,
                     const Vec3& origin_m);

}  // namespace glint::detail
