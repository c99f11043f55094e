#pragma once
/// @file
/// @brief The target as an occluder: whether a light path from a facet to the laser or to an
/// observer is blocked by the target itself, traced by Embree (docs/meshes.md, "Occlusion").

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "facets/target.h"
#include "facets/vec3.h"

namespace glint {

/// @brief Triangles that cast shadows but reflect nothing, in world coordinates: the terrain
/// (geo/terrain.h), which masks the beam on its way to the target and each reflection on its
/// way to an observer.
struct ShadowMesh {
  std::vector<Vec3> vertices_m;
  std::vector<std::array<std::uint32_t, 3>> triangles;  ///< indices into vertices_m
};

/// @brief Whether a target can shadow itself: false only for one object that is convex
/// (TargetObject::convex), where every ray would come back clear.
bool needsOcclusion(const Target& target);

/// @brief The coarse facets of a target, each split to a fixed level on its own surface model,
/// in an Embree scene. Thread-safe queries.
///
/// Embree works in single precision, so the triangles are stored about the target's centre,
/// and each query starts above its facet by lift_m(): more than the facet's curved surface
/// departs from its flat pieces plus the float rounding of the scene, so a facet never
/// shadows itself.
class Occluder {
 public:
  /// @param target_shadows the target's own facets join the scene (its self-shadowing);
  /// @param terrain triangles that shadow too (none: null).
  explicit Occluder(const Target& target, int level = 2, bool target_shadows = true,
                    const ShadowMesh* terrain = nullptr);
  ~Occluder();
  Occluder(const Occluder&) = delete;
  Occluder& operator=(const Occluder&) = delete;

  /// @brief Whether nothing of the target lies on the segment from @p from_m to @p to_m
  /// (world coordinates; @p from_m already lifted off its facet), ignoring its first
  /// @p skip_m.
  [[nodiscard]] bool segmentClear(const Vec3& from_m, const Vec3& to_m, double skip_m = 0.0) const;

  /// @brief Whether nothing lies between @p skip_m and @p distance_m from @p from_m along unit
  /// @p direction.
  [[nodiscard]] bool rayClear(const Vec3& from_m, const Vec3& direction, double distance_m,
                              double skip_m = 0.0) const;

  /// @brief How far (m) above coarse facet @p coarse, along its surface normal, a ray
  /// starts.
  [[nodiscard]] double lift_m(std::uint32_t coarse) const { return lift_m_[coarse]; }

  /// @brief Triangles in the Embree scene.
  [[nodiscard]] std::size_t triangleCount() const { return triangles_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::vector<double> lift_m_;
  std::size_t triangles_ = 0;
};

}  // namespace glint
