#include "facets/occluder.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "facets/detail/embree_triangles.h"
#include "facets/patch.h"

namespace glint {

bool needsOcclusion(const Target& target) {
  return target.objects.size() > 1 || (target.objects.size() == 1 && !target.objects[0].convex);
}

struct Occluder::Impl {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  Vec3 frame_origin_m{0.0};  // the Embree scene's coordinates are relative to this

  ~Impl() {
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
  }

  bool clear(const Vec3& from_m, const Vec3& direction, double distance_m, double skip_m) const {
    return detail::rayClear(scene, frame_origin_m, from_m, direction, skip_m, distance_m);
  }
};

Occluder::Occluder(const Target& target, int level, bool target_shadows, const ShadowMesh* terrain)
    : impl_(std::make_unique<Impl>()) {
  // The pieces of every coarse facet, in world coordinates.
  ShadowMesh pieces;
  lift_m_.resize(target.facetCount());
  Vec3 lo(std::numeric_limits<double>::infinity()), hi(-std::numeric_limits<double>::infinity());
  std::vector<SubFacet> leaves;
  for (std::uint32_t i = 0; i < target.facetCount(); ++i) {
    const Vec3 origin = target.objects[target.object[i]].origin_m;
    const auto& c = target.corners_m[i];
    const Vec3 chord_centre = (c[0] + c[1] + c[2]) / 3.0;
    const Vec3 chord_normal =
        tryNormalize(glm::cross(c[1] - c[0], c[2] - c[0])).value_or(Vec3(0.0));
    subFacetsAtDepth(target, i, level, leaves);
    // Without the target's own shadows its pieces still set the frame and the lifts, but stay
    // out of the scene.
    // How far the surface bulges off the chord, sampled at the pieces' corners: the lift
    // clears it with half again to spare.
    double bulge = 0.0;
    for (const SubFacet& f : leaves) {
      std::array<Vec3, 3> world;
      for (int k = 0; k < 3; ++k) {
        bulge = std::max(bulge, std::abs(glm::dot(f.corner_m[k] - chord_centre, chord_normal)));
        world[k] = f.corner_m[k] + origin;
        lo = glm::min(lo, world[k]);
        hi = glm::max(hi, world[k]);
      }
      if (target_shadows) {
        const auto first = static_cast<std::uint32_t>(pieces.vertices_m.size());
        pieces.vertices_m.insert(pieces.vertices_m.end(), world.begin(), world.end());
        pieces.triangles.push_back({first, first + 1, first + 2});
      }
    }
    lift_m_[i] = 1.5 * bulge;
  }
  triangles_ = pieces.triangles.size() + (terrain != nullptr ? terrain->triangles.size() : 0);
  if (triangles_ == 0) return;

  impl_->frame_origin_m = 0.5 * (lo + hi);
  // Float rounding of the stored triangles: a few ulps of the largest coordinate.
  const double half_extent = 0.5 * glm::length(hi - lo);
  const double rounding_m =
      16.0 * static_cast<double>(std::numeric_limits<float>::epsilon()) * half_extent;
  for (double& lift : lift_m_) lift += rounding_m;

  impl_->device = rtcNewDevice(nullptr);
  if (!impl_->device) throw std::runtime_error("Embree: cannot create a device");
  impl_->scene = rtcNewScene(impl_->device);
  rtcSetSceneFlags(impl_->scene, RTC_SCENE_FLAG_ROBUST);
  rtcSetSceneBuildQuality(impl_->scene, RTC_BUILD_QUALITY_HIGH);
  detail::attachTriangles(impl_->device, impl_->scene, pieces, impl_->frame_origin_m);
  // The terrain in the target's frame too: far off it rounds to ~1e-7 of its distance, below
  // any elevation model's resolution, while the target keeps its own precision.
  if (terrain != nullptr)
    detail::attachTriangles(impl_->device, impl_->scene, *terrain, impl_->frame_origin_m);
  rtcCommitScene(impl_->scene);
}

Occluder::~Occluder() = default;

bool Occluder::segmentClear(const Vec3& from_m, const Vec3& to_m, double skip_m) const {
  if (!impl_->scene) return true;
  const Vec3 d = to_m - from_m;
  const double length = glm::length(d);
  if (!(length > skip_m)) return true;
  return impl_->clear(from_m, d / length, length, skip_m);
}

bool Occluder::rayClear(const Vec3& from_m, const Vec3& direction, double distance_m,
                        double skip_m) const {
  if (!impl_->scene || !(distance_m > skip_m)) return true;
  return impl_->clear(from_m, direction, distance_m, skip_m);
}

namespace detail {

bool rayClear(RTCScene scene, const Vec3& frame_origin_m, const Vec3& origin_m,
              const Vec3& direction, double near_m, double far_m) {
  const Vec3 o = origin_m - frame_origin_m;
  RTCRay ray{};
  ray.org_x = static_cast<float>(o.x);
  ray.org_y = static_cast<float>(o.y);
  ray.org_z = static_cast<float>(o.z);
  ray.dir_x = static_cast<float>(direction.x);
  ray.dir_y = static_cast<float>(direction.y);
  ray.dir_z = static_cast<float>(direction.z);
  ray.tnear = static_cast<float>(near_m);
  ray.tfar = static_cast<float>(far_m);
  ray.mask = 0xFFFFFFFFu;
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  rtcOccluded1(scene, &context, &ray);
  // Embree marks a blocked ray by setting tfar to -inf.
  return ray.tfar >= 0.0f;
}

void attachTriangles(RTCDevice device, RTCScene scene, const ShadowMesh& mesh,
                     const Vec3& origin_m) {
  if (mesh.triangles.empty()) return;
  RTCGeometry geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
  auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0,
                                                        RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                                        mesh.vertices_m.size()));
  auto* t = static_cast<unsigned*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0,
                                                           RTC_FORMAT_UINT3, 3 * sizeof(unsigned),
                                                           mesh.triangles.size()));
  for (std::size_t k = 0; k < mesh.vertices_m.size(); ++k) {
    const Vec3 p = mesh.vertices_m[k] - origin_m;
    v[3 * k + 0] = static_cast<float>(p.x);
    v[3 * k + 1] = static_cast<float>(p.y);
    v[3 * k + 2] = static_cast<float>(p.z);
  }
  for (std::size_t k = 0; k < mesh.triangles.size(); ++k) {
    for (std::size_t c = 0; c < 3; ++c) t[3 * k + c] = mesh.triangles[k][c];
  }
  rtcCommitGeometry(geometry);
  rtcAttachGeometry(scene, geometry);
  rtcReleaseGeometry(geometry);
}

}  // namespace detail
}  // namespace glint
