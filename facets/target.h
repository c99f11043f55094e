#pragma once
/// @file
/// @brief The target: its coarse facets (struct-of-arrays), the surface model each facet
/// subdivides on, and the materials and frames of its objects.

#include <array>
#include <cstdint>
#include <optional>
#include <vector>

#include "facets/material.h"
#include "facets/pn_triangle.h"
#include "facets/quadric.h"
#include "facets/vec3.h"

namespace glint {

/// @brief How the surface between a facet's corners is found when the facet is split 1→4.
enum class SurfaceModel : std::uint8_t {
  Flat,     ///< the plane of the corners: midpoints stay on the chord
  Quadric,  ///< an exact (or fitted) quadric: midpoints are projected onto it
  PN,       ///< a PN triangle: midpoints are evaluated at the parameter midpoint
};

/// @brief One object of the target. Its facets are stored relative to @c origin_m, so a scene
/// placed far from the world origin keeps full precision in the facet geometry.
struct TargetObject {
  Vec3 origin_m{0.0};            ///< world position of the object's local origin
  std::uint32_t material = 0;    ///< index into Target::materials
  std::optional<RimCircle> rim;  ///< object-local boundary circle (a disk's rim)
  /// No part of the surface can hide another part from the laser or from an observer (the
  /// outside of a sphere or a cylinder, a disk): alone, it needs no occlusion rays.
  bool convex = false;
};

/// @brief The coarse facets of a whole target. Corners are counter-clockwise seen from the
/// reflecting side, so the cross product of the edges points out of the surface.
struct Target {
  std::vector<Material> materials;
  std::vector<TargetObject> objects;
  std::vector<Quadric> quadrics;         ///< object-local
  std::vector<PNTriangle> pn_triangles;  ///< object-local

  // One entry per coarse facet.
  std::vector<std::array<Vec3, 3>> corners_m;  ///< object-local corner positions
  std::vector<std::uint32_t> object;           ///< owning object
  std::vector<SurfaceModel> model;             ///< how the facet subdivides
  std::vector<std::uint32_t> model_index;      ///< into quadrics or pn_triangles
  std::vector<std::uint8_t> rim_edges;         ///< bit k: edge (k, k+1) lies on the rim

  [[nodiscard]] std::size_t facetCount() const { return corners_m.size(); }
  /// @brief The narrowest width of the target's materials' directional terms (rad,
  /// narrowestWidthRad()).
  [[nodiscard]] std::optional<double> narrowestWidthRad() const {
    return glint::narrowestWidthRad(materials);
  }

  std::uint32_t addMaterial(const Material& m);
  std::uint32_t addObject(const TargetObject& o);
  std::uint32_t addQuadric(const Quadric& q);
  std::uint32_t addPNTriangle(const PNTriangle& t);
  void addFacet(std::uint32_t object_index, const std::array<Vec3, 3>& corners,
                SurfaceModel surface, std::uint32_t surface_index, std::uint8_t rim = 0);
};

}  // namespace glint
