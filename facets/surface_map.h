#pragma once
/// @file
/// @brief The exact parametrisation of a coarse facet's curved surface over its barycentric
/// triangle: what a high-order rule needs (position, the normal the BRDF sees, area element).

#include <cstdint>

#include "facets/patch.h"
#include "facets/target.h"

namespace glint {

/// @brief A point of the surface and the measure there.
struct SurfacePoint {
  Vec3 position_m{0.0};        ///< object-local
  Vec3 normal{0.0, 0.0, 1.0};  ///< unit normal the BRDF sees (NormalModel::Surface)
  /// dA/du dv: surface area per unit area of the (u, v) = (b₁, b₂) parameter plane, where the
  /// whole facet is the triangle u, v ≥ 0, u + v ≤ 1 of area ½.
  double jacobian_m2 = 0.0;
  bool valid = false;  ///< false where the parametrisation breaks down (see SurfaceMap)
};

/// @brief S(b) for the barycentric coordinates b of one coarse facet, exact for its model:
/// - Flat: the chord triangle.
/// - Quadric: the chord point P(b) projected onto the quadric along the gradient at P (the
///   projection 1→4 subdivision uses; for spheres and cylinders the nearest surface point), so
///   facets that share a chord edge share its image. Area element and normal are exact (the
///   projection's derivative, the gradient). Rim edges (a disk's outline) are bent onto their
///   circle by a transfinite blend, P = chord + Σ_rim edges (bₑ + bₑ₊₁)² · (arc − chord)(t),
///   t = bₑ₊₁ / (bₑ + bₑ₊₁), so the pieces tile the true outline (squared, so that the blend is
///   smooth at the opposite corner). Invalid where the gradient vanishes or the projection line
///   misses the surface or runs nearly tangent to it.
/// - PN: the cubic patch itself, with its quadratic normal field (as the 1→4 scheme uses).
///
/// Unlike 1→4 subdivision (patch.h), which places each new corner from its parent's, S is one
/// map: pieces that tile the barycentric triangle tile the surface, whatever their depth.
class SurfaceMap {
 public:
  SurfaceMap() = default;
  SurfaceMap(const Target& target, std::uint32_t facet);

  /// @brief The coarse facet this map parametrises.
  [[nodiscard]] std::uint32_t facet() const { return facet_; }

  /// @brief The surface at barycentric coordinates @p bary (components sum to 1).
  [[nodiscard]] SurfacePoint at(const Vec3& bary) const;

  /// @brief The sub-facet of barycentric corners @p bary with its corners placed by at(), so
  /// that patchGeometry() bounds the piece this map integrates.
  [[nodiscard]] SubFacet subFacet(const std::array<Vec3, 3>& bary, std::uint8_t depth,
                                  std::uint8_t rim_edges) const;

  /// @brief As subFacet(bary, depth, rim_edges), with the surface at the corners already
  /// known: @p corners[k] = at(bary[k]).
  [[nodiscard]] SubFacet subFacet(const std::array<Vec3, 3>& bary, std::uint8_t depth,
                                  std::uint8_t rim_edges,
                                  const std::array<SurfacePoint, 3>& corners) const;

  /// @brief The four children of @p f (as split() orders them), corners placed by at().
  [[nodiscard]] std::array<SubFacet, 4> split(const SubFacet& f) const;

  /// @brief The children split() makes of @p f, before their corners are placed: barycentric
  /// corners (in the coarse facet), depth and rim bits, in split()'s order.
  struct Child {
    std::array<Vec3, 3> bary;
    std::uint8_t depth = 0;
    std::uint8_t rim_edges = 0;
  };
  [[nodiscard]] static std::array<Child, 4> children(const SubFacet& f);

  /// @brief patchGeometry(target, f, NormalModel::Surface) for a piece @p f of this map (the
  /// target the map was built on), its bounds widened to hold the piece as the map places it.
  /// The rim blend bends a rim facet's inner piece edges too, which patchGeometry, built for
  /// 1→4 subdivision's straight inner edges, does not see.
  [[nodiscard]] PatchGeometry geometry(const Target& target, const SubFacet& f) const;

  /// @brief How far the rim blend bends the edges of the piece with barycentric corners
  /// @p bary, placed at @p corner_m, off their chords: edges on the rim (bits of @p rim_edges)
  /// are exact arcs, which patchGeometry counts, and are left out. Zero without a rim.
  struct Bend {
    double offset_m = 0.0;  ///< the piece lies within this of its chord triangle
    double area_m2 = 0.0;   ///< it exceeds the chord triangle's area by at most this
  };
  [[nodiscard]] Bend bend(const std::array<Vec3, 3>& bary, const std::array<Vec3, 3>& corner_m,
                          std::uint8_t rim_edges) const;

 private:
  struct RimArc {
    bool present = false;
    Vec3 centre_m{0.0}, e1{0.0}, e2{0.0};  // arc(t) = c + R (cos tΔ e1 + sin tΔ e2)
    double radius_m = 0.0, angle_rad = 0.0;
  };
  // The chord point with rim blending, and its derivatives along u and v.
  void blended(const Vec3& bary, Vec3& p, Vec3& p_u, Vec3& p_v) const;

  SurfaceModel model_ = SurfaceModel::Flat;
  const Quadric* quadric_ = nullptr;
  const PNTriangle* pn_ = nullptr;
  std::uint32_t facet_ = 0;
  std::array<Vec3, 3> corner_m_{};
  Vec3 chord_normal_{0.0, 0.0, 1.0};
  std::array<RimArc, 3> rim_{};  // per edge (k, k+1)
  bool any_rim_ = false;
};

}  // namespace glint
