#pragma once
/// @file
/// @brief Coarse tessellation of the analytic shapes into facets that carry their exact
/// quadric, and of triangle meshes into PN, fitted-quadric or flat facets.

#include <array>
#include <cstddef>
#include <cstdint>
#include <glm/gtc/quaternion.hpp>
#include <optional>
#include <variant>
#include <vector>

#include "facets/target.h"

namespace glint {

// Each analytic shape knows, in one place, how it is tessellated (addCylinder() and its
// siblings below), how many coarse facets that makes (what a run's memory is reckoned from
// before it builds them), where an observer is inside it or on it (those are not computed) and
// whether it is convex (alone, it cannot shadow itself: no occlusion rays).
// Counts are doubles: a count too large to build is reckoned and refused, not wrapped.

/// @brief The open side surface of a right circular cylinder (no caps), reflecting outward.
struct CylinderShape {
  Vec3 centre_m{0.0};
  Vec3 axis{0.0, 0.0, 1.0};  ///< unit
  double radius_m = 1.0;
  double length_m = 1.0;

  /// @brief Rings along the axis, each about as long as a facet is wide.
  [[nodiscard]] double rings(int segments) const;
  /// @brief The coarse facets addCylinder() makes: two per segment and ring.
  [[nodiscard]] double coarseFacets(int segments) const { return 2.0 * segments * rings(segments); }
  /// @brief Whether @p x_m lies inside the closed cylinder grown by @p margin_m.
  [[nodiscard]] bool nearOrInside(const Vec3& x_m, double margin_m) const;
  /// The outside of the side surface never hides one part of itself from another.
  static constexpr bool kConvex = true;
};

/// @brief A sphere, reflecting outward.
struct SphereShape {
  Vec3 centre_m{0.0};
  double radius_m = 1.0;

  /// @brief Latitude bands pole to pole.
  [[nodiscard]] static int bands(int segments) { return segments / 2 > 2 ? segments / 2 : 2; }
  /// @brief The coarse facets addSphere() makes: two per segment and band, one at each pole.
  [[nodiscard]] static double coarseFacets(int segments) {
    return 2.0 * segments * (bands(segments) - 1);
  }
  /// @brief Whether @p x_m lies within radius + @p margin_m of the centre.
  [[nodiscard]] bool nearOrInside(const Vec3& x_m, double margin_m) const;
  static constexpr bool kConvex = true;
};

/// @brief A one-sided disk: only the side its normal points to reflects.
struct DiskShape {
  Vec3 centre_m{0.0};
  Vec3 normal{0.0, 0.0, 1.0};  ///< unit
  double radius_m = 1.0;

  /// @brief Rings from the centre out, about as wide as the outer facets are long.
  [[nodiscard]] static double rings(int segments);
  /// @brief The coarse facets addDisk() makes: a fan at the centre, two per segment beyond.
  [[nodiscard]] static double coarseFacets(int segments) {
    return segments * (2.0 * rings(segments) - 1.0);
  }
  /// @brief Whether @p x_m lies within @p margin_m of the disk (a slab as thick as the margin).
  [[nodiscard]] bool nearOrInside(const Vec3& x_m, double margin_m) const;
  static constexpr bool kConvex = true;  ///< flat: nothing of it is in front of the rest
};

/// @brief One of the analytic shapes.
using AnalyticShape = std::variant<CylinderShape, SphereShape, DiskShape>;

/// @brief Adds @p shape as addCylinder(), addSphere() or addDisk() would.
std::uint32_t addShape(Target& target, const AnalyticShape& shape, std::uint32_t material,
                       int segments, const Vec3& reference);

/// @brief The coarse facets addShape() makes of @p shape.
double coarseFacets(const AnalyticShape& shape, int segments);

/// @brief Whether @p x_m lies inside @p shape or within @p margin_m of it.
bool nearOrInside(const AnalyticShape& shape, const Vec3& x_m, double margin_m);

/// @brief Whether @p shape is convex (TargetObject::convex).
bool isConvex(const AnalyticShape& shape);

/// @brief The centre of @p shape.
Vec3 centreOf(const AnalyticShape& shape);

/// @brief The direction @p shape is turned by: a cylinder's axis, a disk's normal; nothing for a
/// sphere, which any turn leaves as it was.
std::optional<Vec3> axisOf(const AnalyticShape& shape);

/// @brief @p shape with its centre at @p centre_m and its axis turned by the unit quaternion
/// @p turn (and normalised again, as a scene file's is read).
AnalyticShape placed(const AnalyticShape& shape, const Vec3& centre_m, const glm::dquat& turn);

/// @brief Adds a cylinder as one object: @p segments facets around, rings along the axis so
/// that facets are about as long as wide. @p reference (unit) fixes the azimuth of the
/// tessellation, so that passing a scene-derived direction (toward the laser) makes the
/// tessellation rotate with the scene. With segments a multiple of 4 the terminator of a beam
/// across the axis runs along facet edges.
/// @return the object index.
std::uint32_t addCylinder(Target& target, const CylinderShape& shape, std::uint32_t material,
                          int segments, const Vec3& reference);

/// @brief Adds a sphere as latitude bands around the pole @p reference (toward the laser), so
/// the lit hemisphere is whole bands: @p segments around, segments/2 bands pole to pole.
std::uint32_t addSphere(Target& target, const SphereShape& shape, std::uint32_t material,
                        int segments, const Vec3& reference);

/// @brief Adds a disk as a central fan and rings, @p segments around; its rim edges are
/// flagged so subdivision follows the true circle.
std::uint32_t addDisk(Target& target, const DiskShape& shape, std::uint32_t material, int segments,
                      const Vec3& reference);

/// @brief The surface a mesh's facets are given (docs/meshes.md: measured against the shapes
/// glint knows exactly, bench/RESULTS.md).
enum class MeshSurface {
  Flat,        ///< the chord triangles
  PN,          ///< PN triangles with the Bernstein normal field (PNNormalField): the default
  QuadricFit,  ///< the quadric through each facet's vertices and normals, PN where it fails
  Nagata,      ///< Nagata's quadratic patches with their own normals
  PNVlachos,   ///< PN triangles with the normal field as published: only to measure it
};

/// @brief The surface's name in scene files (`pn`, `nagata`, `quadric_fit`, `flat`; the
/// published PN field, which no scene selects, `pn_published`).
const char* toString(MeshSurface surface);

/// @brief An indexed triangle mesh in one object's frame (metres), as a file gives it.
/// Vertices at one position may repeat with different normals (a crease); the mesh is stitched
/// by exact position, not by index.
struct TriangleMesh {
  std::vector<Vec3> positions_m;
  std::vector<Vec3> normals;  ///< per vertex; zero where the file gave none (see fillNormals)
  std::vector<std::array<std::uint32_t, 3>> triangles;  ///< counter-clockwise from outside
};

/// @brief Gives every triangle corner whose vertex has a zero normal the area-weighted mean of
/// the face normals around its position, over the faces within @p crease_angle_rad of the
/// corner's own face: smooth across gentle bends, sharp across creases. Such corners get new
/// vertices, one per position and normal (shared by the corners that agree).
/// @return the number of corners given a normal.
std::size_t fillNormals(TriangleMesh& mesh, double crease_angle_rad);

/// @brief The unit normal of triangle @p corners_m (counter-clockwise from outside), or
/// nothing for one that has zero area or a non-finite corner: the triangles addMesh() drops.
std::optional<Vec3> usableTriangleNormal(const std::array<Vec3, 3>& corners_m);

/// @brief How many of @p mesh's triangles addMesh() would keep.
std::size_t usableTriangles(const TriangleMesh& mesh);

/// @brief What happened to a mesh's triangles: counts for the run summary.
struct MeshStats {
  std::size_t triangles = 0;           ///< triangles offered
  std::size_t facets = 0;              ///< facets added
  std::size_t degenerate_dropped = 0;  ///< zero-area or non-finite triangles
  std::size_t normals_repaired = 0;    ///< vertex normals that were zero, non-finite or
                                       ///< facing away from the face, replaced by the face normal
  std::size_t quadric_fits = 0;        ///< facets on a fitted quadric
  std::size_t fit_fallbacks = 0;       ///< fits refused (singular, ill-conditioned, ...) → PN
  std::size_t crease_edges = 0;        ///< PN edges whose two sides disagree on the normals
  std::size_t open_edges = 0;          ///< edges with no (or more than one) neighbour
};

/// @brief Adds a triangle mesh as one object, its positions relative to @p origin_m.
/// PN facets share every edge curve with their neighbour, creases included (PNTriangle's
/// PN-AEN constructor), so the curved surface is as closed as the mesh.
MeshStats addMesh(Target& target, const Vec3& origin_m, std::uint32_t material,
                  const TriangleMesh& mesh, MeshSurface surface);

/// @brief As above, from separate arrays (per-vertex @p normals).
MeshStats addMesh(Target& target, const Vec3& origin_m, std::uint32_t material,
                  const std::vector<Vec3>& positions_m, const std::vector<Vec3>& normals,
                  const std::vector<std::array<std::uint32_t, 3>>& triangles, MeshSurface surface);

}  // namespace glint
