#pragma once
/// @file
/// @brief Coarse tessellation of the analytic shapes into facets that carry their exact
/// quadric, and of triangle meshes into PN, fitted-quadric or flat facets.

#include <array>
#include <concepts>
#include <cstddef>
#include <cstdint>
#include <glm/gtc/quaternion.hpp>
#include <optional>
#include <variant>
#include <vector>

#include "facets/target.h"

namespace glint {

// Each analytic shape knows, in one place, its name in scene files, how it is tessellated
// (addTo()), how many coarse facets that makes (what a run's memory is reckoned from before it
// builds them), where an observer is inside it or on it (those are not computed), whether it
// is convex (alone, it cannot shadow itself: no occlusion rays), the direction a pose turns and
// how a pose places it. AnalyticShapeType below is the list; every alternative of
// AnalyticShape must satisfy it, so a shape missing one of them does not compile.
// Counts are doubles: a count too large to build is reckoned and refused, not wrapped.

/// @brief The open side surface of a right circular cylinder (no caps), reflecting outward.
struct CylinderShape {
  Vec3 centre_m{0.0};
  Vec3 axis{0.0, 0.0, 1.0};  ///< unit
  double radius_m = 1.0;
  double length_m = 1.0;

  static constexpr const char* kName = "cylinder";
  static constexpr const char* kOrientationName = "axis";  ///< the key of orientation()
  /// @brief The direction a pose turns: the axis.
  [[nodiscard]] std::optional<Vec3> orientation() const { return axis; }
  /// @brief This cylinder with its centre at @p centre_m and its axis turned by @p turn.
  [[nodiscard]] CylinderShape placed(const Vec3& centre_m, const glm::dquat& turn) const;
  /// @brief Adds it to @p target as addCylinder() does.
  std::uint32_t addTo(Target& target, std::uint32_t material, int segments,
                      const Vec3& reference) const;

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

  static constexpr const char* kName = "sphere";
  static constexpr const char* kOrientationName = nullptr;
  /// @brief Nothing: any turn leaves a sphere as it was.
  [[nodiscard]] std::optional<Vec3> orientation() const { return std::nullopt; }
  /// @brief This sphere with its centre at @p centre_m.
  [[nodiscard]] SphereShape placed(const Vec3& centre_m, const glm::dquat& turn) const;
  /// @brief Adds it to @p target as addSphere() does.
  std::uint32_t addTo(Target& target, std::uint32_t material, int segments,
                      const Vec3& reference) const;

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

  static constexpr const char* kName = "disk";
  static constexpr const char* kOrientationName = "normal";
  /// @brief The direction a pose turns: the normal.
  [[nodiscard]] std::optional<Vec3> orientation() const { return normal; }
  /// @brief This disk with its centre at @p centre_m and its normal turned by @p turn.
  [[nodiscard]] DiskShape placed(const Vec3& centre_m, const glm::dquat& turn) const;
  /// @brief Adds it to @p target as addDisk() does.
  std::uint32_t addTo(Target& target, std::uint32_t material, int segments,
                      const Vec3& reference) const;

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

/// @brief The open side surface of a right circular cone's frustum (no caps), reflecting
/// outward: radius @p radius_m at the end −axis × length/2 from the centre, @p top_radius_m at
/// the end +axis × length/2, both positive and different (equal radii are a cylinder; a sharp
/// apex has no normal, so a pointed nose is a frustum with a small top).
///
/// Its surface is exact, but not its two end circles: subdivision projects along the quadric's
/// gradient, which on a cone leans along the axis, so an end follows the circle only to about
/// the coarse chord's sagitta × the slope (2 mm for 16 segments of a 0.5 m radius at slope
/// 0.2). A glint cut by an end is off by as much (0.2 % in tests/facets/analytic_shape_test.cpp's
/// cone, seen from (2, 2.5, 1)); more segments bring it down as their square.
struct ConeShape {
  Vec3 centre_m{0.0};         ///< the middle of the axis between the two ends
  Vec3 axis{0.0, 0.0, 1.0};   ///< unit, from the base toward the top
  double radius_m = 1.0;      ///< at the base
  double top_radius_m = 0.5;  ///< at the top
  double length_m = 1.0;      ///< between the ends, along the axis

  static constexpr const char* kName = "cone";
  static constexpr const char* kOrientationName = "axis";
  /// @brief The direction a pose turns: the axis.
  [[nodiscard]] std::optional<Vec3> orientation() const { return axis; }
  /// @brief This cone with its centre at @p centre_m and its axis turned by @p turn.
  [[nodiscard]] ConeShape placed(const Vec3& centre_m, const glm::dquat& turn) const;
  /// @brief Adds it to @p target as addCone() does.
  std::uint32_t addTo(Target& target, std::uint32_t material, int segments,
                      const Vec3& reference) const;
  /// @brief The slant length along the surface between the ends.
  [[nodiscard]] double slantLengthM() const;
  /// @brief Rings along the axis, each about as long (along the slant) as a facet is wide at the
  /// wider end.
  [[nodiscard]] double rings(int segments) const;
  /// @brief The coarse facets addCone() makes: two per segment and ring.
  [[nodiscard]] double coarseFacets(int segments) const { return 2.0 * segments * rings(segments); }
  /// @brief Whether @p x_m lies inside the closed frustum grown by @p margin_m (within the
  /// larger radius + margin of the axis and half the length + margin of the centre along it).
  [[nodiscard]] bool nearOrInside(const Vec3& x_m, double margin_m) const;
  /// The outside of a cone's side surface never hides one part of itself from another.
  static constexpr bool kConvex = true;
};

/// @brief What every analytic shape provides (see above); a shape that lacks one of them is
/// refused by the compiler where AnalyticShape lists it.
template <class S>
concept AnalyticShapeType = requires(const S& s, Target& target, const Vec3& x,
                                     const glm::dquat& turn) {
  { S::kName } -> std::convertible_to<const char*>;
  { S::kOrientationName } -> std::convertible_to<const char*>;
  { S::kConvex } -> std::convertible_to<bool>;
  { s.centre_m } -> std::convertible_to<Vec3>;
  { s.radius_m } -> std::convertible_to<double>;
  { s.orientation() } -> std::same_as<std::optional<Vec3>>;
  { s.placed(x, turn) } -> std::same_as<S>;
  { s.coarseFacets(4) } -> std::convertible_to<double>;
  { s.nearOrInside(x, 0.0) } -> std::same_as<bool>;
  { s.addTo(target, std::uint32_t{0}, 4, x) } -> std::same_as<std::uint32_t>;
};

/// @brief One of the analytic shapes.
using AnalyticShape = std::variant<CylinderShape, SphereShape, DiskShape, ConeShape>;

namespace detail {
template <class... S>
constexpr bool allAnalyticShapes(const std::variant<S...>*) {
  return (AnalyticShapeType<S> && ...);
}
}  // namespace detail
static_assert(detail::allAnalyticShapes(static_cast<const AnalyticShape*>(nullptr)),
              "every alternative of AnalyticShape must satisfy AnalyticShapeType");

/// @brief Adds @p shape as its addTo() does.
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

/// @brief The direction @p shape is turned by (its orientation()): a cylinder's or cone's axis,
/// a disk's normal; nothing for a sphere, which any turn leaves as it was.
std::optional<Vec3> axisOf(const AnalyticShape& shape);

/// @brief The name of that direction in scene files ("axis", "normal"); null for a sphere.
const char* axisNameOf(const AnalyticShape& shape);

/// @brief The name of @p shape in scene files ("cylinder", ...).
const char* nameOf(const AnalyticShape& shape);

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

/// @brief Adds a cone's frustum as one object, as addCylinder() adds a cylinder: @p segments
/// around, rings along the axis, the tessellation's azimuth fixed by @p reference.
std::uint32_t addCone(Target& target, const ConeShape& shape, std::uint32_t material, int segments,
                      const Vec3& reference);

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
