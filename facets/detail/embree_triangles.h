#pragma once
// Triangles into an Embree scene, stored in single precision about an origin of the caller's
// (the occluder's and the terrain's scenes), and the occlusion ray both trace.
#include <embree3/rtcore.h>

#include "facets/occluder.h"

namespace glint::detail {

/// @brief Attaches @p mesh to @p scene as one triangle geometry, each vertex stored as
/// float(vertex − @p origin_m). A mesh without triangles attaches nothing.
void attachTriangles(RTCDevice device, RTCScene scene, const ShadowMesh& mesh,
                     const Vec3& origin_m);

/// @brief Whether nothing of @p scene lies between @p near_m and @p far_m along unit
/// @p direction from @p origin_m, the scene's coordinates being relative to @p frame_origin_m.
bool rayClear(RTCScene scene, const Vec3& frame_origin_m, const Vec3& origin_m,
              const Vec3& direction, double near_m, double far_m);

}  // namespace glint::detail
