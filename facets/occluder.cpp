#include "facets/occluder.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

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
    const Vec3 o = from_m - frame_origin_m;
    RTCRay ray{};
    ray.org_x = static_cast<float>(o.x);
    ray.org_y = static_cast<float>(o.y);
    ray.org_z = static_cast<float>(o.z);
    ray.dir_x = static_cast<float>(direction.x);
    ray.dir_y = static_cast<float>(direction.y);
    ray.dir_z = static_cast<float>(direction.z);
    ray.tnear = static_cast<float>(skip_m);
    ray.tfar = static_cast<float>(distance_m);
    ray.mask = 0xFFFFFFFFu;
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    rtcOccluded1(scene, &context, &ray);
    // Embree marks a blocked ray by setting tfar to -inf.
    return ray.tfar >= 0.0f;
  }
};

Occluder::Occluder(const Target& target, int level, bool target_shadows, const ShadowMesh* terrain)
    : impl_(std::make_unique<Impl>()) {
  // The pieces of every coarse facet, in world coordinates for now.
  std::vector<std::array<Vec3, 3>> pieces;
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
      if (target_shadows) pieces.push_back(world);
    }
    lift_m_[i] = 1.5 * bulge;
  }
  terrain_triangles_ = terrain != nullptr ? terrain->triangles.size() : 0;
  triangles_ = pieces.size() + terrain_triangles_;
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
  if (!pieces.empty()) {
    RTCGeometry geometry = rtcNewGeometry(impl_->device, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* vertices = static_cast<float*>(
        rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                3 * sizeof(float), 3 * pieces.size()));
    auto* indices = static_cast<unsigned*>(rtcSetNewGeometryBuffer(
        geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), pieces.size()));
    for (std::size_t t = 0; t < pieces.size(); ++t) {
      for (int k = 0; k < 3; ++k) {
        const Vec3 v = pieces[t][k] - impl_->frame_origin_m;
        const std::size_t at = 3 * t + static_cast<std::size_t>(k);
        vertices[3 * at + 0] = static_cast<float>(v.x);
        vertices[3 * at + 1] = static_cast<float>(v.y);
        vertices[3 * at + 2] = static_cast<float>(v.z);
        indices[at] = static_cast<unsigned>(at);
      }
    }
    rtcCommitGeometry(geometry);
    rtcAttachGeometry(impl_->scene, geometry);
    rtcReleaseGeometry(geometry);
  }
  if (terrain_triangles_ > 0) {
    // In the target's frame too: the terrain far off rounds to ~1e-7 of its distance, below
    // any elevation model's resolution, while the target keeps its own precision.
    RTCGeometry ground = rtcNewGeometry(impl_->device, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(ground, RTC_BUFFER_TYPE_VERTEX, 0,
                                                          RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                                          terrain->vertices_m.size()));
    auto* t = static_cast<unsigned*>(rtcSetNewGeometryBuffer(ground, RTC_BUFFER_TYPE_INDEX, 0,
                                                             RTC_FORMAT_UINT3, 3 * sizeof(unsigned),
                                                             terrain->triangles.size()));
    for (std::size_t k = 0; k < terrain->vertices_m.size(); ++k) {
      const Vec3 p = terrain->vertices_m[k] - impl_->frame_origin_m;
      v[3 * k + 0] = static_cast<float>(p.x);
      v[3 * k + 1] = static_cast<float>(p.y);
      v[3 * k + 2] = static_cast<float>(p.z);
    }
    for (std::size_t k = 0; k < terrain->triangles.size(); ++k) {
      for (std::size_t c = 0; c < 3; ++c) t[3 * k + c] = terrain->triangles[k][c];
    }
    rtcCommitGeometry(ground);
    rtcAttachGeometry(impl_->scene, ground);
    rtcReleaseGeometry(ground);
  }
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

}  // namespace glint
