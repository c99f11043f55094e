#pragma once
/// @file
/// @brief Coarse tessellation of the analytic shapes into facets that carry their exact
/// quadric, and of triangle meshes into PN, fitted-quadric or flat facets.

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "facets/target.h"

namespace glint {

/// @brief The open side surface of a right circular cylinder (no caps), reflecting outward.
struct CylinderShape {
  Vec3 center_m{0.0};
  Vec3 axis{0.0, 0.0, 1.0};  ///< unit
  double radius_m = 1.0;
  double length_m = 1.0;
};

/// @brief A sphere, reflecting outward.
struct SphereShape {
  Vec3 center_m{0.0};
  double radius_m = 1.0;
};

/// @brief A one-sided disk: only the side its normal points to reflects.
struct DiskShape {
  Vec3 center_m{0.0};
  Vec3 normal{0.0, 0.0, 1.0};  ///< unit
  double radius_m = 1.0;
};

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
