#pragma once
/// @file
/// @brief Curved PN triangles (Vlachos, Peters, Boyd, Mitchell, "Curved PN Triangles", I3D
/// 2001): a cubic Bézier position and an independent quadratic normal field built from three
/// vertices and their normals alone.

#include <array>
#include <optional>

#include "facets/vec3.h"

namespace glint {

/// @brief A PN triangle over barycentric coordinates (b0, b1, b2) of its vertices 0, 1, 2
/// (Vlachos' w, u, v). It interpolates the vertex positions and normals; its edges depend only
/// on the two vertices of the edge, so neighbours sharing vertex normals share the curve.
class PNTriangle {
 public:
  /// @brief From vertex positions @p p_m and unit vertex normals @p n.
  PNTriangle(const std::array<Vec3, 3>& p_m, const std::array<Vec3, 3>& n);

  /// @brief A PN triangle whose edge curves are shared with its neighbours even across a
  /// crease (PN-AEN, McDonald and Kilgard 2010). @p across[e] holds the unit normals that the
  /// facet on the other side of edge e (vertices e, e+1 mod 3) has at those two vertices, in
  /// that order; on a boundary or a smooth edge they equal @p n. Each edge control point is the
  /// mean of the two sides' own, so both facets build the same edge and the surface neither
  /// cracks nor overlaps there, while each side keeps its own normal field (the crease stays
  /// sharp in the reflection).
  PNTriangle(const std::array<Vec3, 3>& p_m, const std::array<Vec3, 3>& n,
             const std::array<std::array<Vec3, 2>, 3>& across);

  /// @brief Surface point at barycentric coordinates @p bary (components sum to 1).
  [[nodiscard]] Vec3 position(const Vec3& bary) const;

  /// @brief The derivative of position() along the barycentric direction @p delta (whose
  /// components sum to 0): the tangent ∂p/∂s of a parametrisation bary + s·delta.
  [[nodiscard]] Vec3 derivative(const Vec3& bary, const Vec3& delta) const;

  /// @brief The quadratic normal field, unnormalised (Vlachos Eq. for n(u, v)).
  [[nodiscard]] Vec3 normalField(const Vec3& bary) const;

  /// @brief Unit normal at @p bary, or nothing where the field vanishes.
  [[nodiscard]] std::optional<Vec3> normal(const Vec3& bary) const {
    return tryNormalize(normalField(bary));
  }

  /// @brief A half-angle (rad) of a cone around unit @p axis containing every normal of the
  /// sub-triangle with barycentric corners @p corners; π when no cone under 90° does.
  /// Rigorous: the restriction of the normal field is again a quadratic Bézier triangle, whose
  /// six control vectors (from the blossom of the field) span all its values with nonnegative
  /// weights.
  [[nodiscard]] double normalConeHalfAngle(const std::array<Vec3, 3>& corners,
                                           const Vec3& axis) const;

  /// @brief An upper bound (m) of the distance between the patch over a sub-triangle of
  /// subdivision @p depth and the flat triangle of its corners. From the largest second
  /// difference of the control net: |p − linear| ≤ ½ max|D²p| max|x − vᵢ|², and each 1→4
  /// level halves the parameter size.
  [[nodiscard]] double sagBound(int depth) const;

  /// @brief The ten Bézier control points b300, b030, b003, b210, b120, b021, b012, b102, b201,
  /// b111.
  [[nodiscard]] const std::array<Vec3, 10>& controlPoints() const { return b_; }

 private:
  std::array<Vec3, 10> b_;
  std::array<Vec3, 6> n_;  // n200, n020, n002, n110, n011, n101
  double second_derivative_bound_m_ = 0.0;
};

}  // namespace glint
