#pragma once
/// @file
/// @brief Curved triangles from three vertices and their normals alone: PN triangles (Vlachos,
/// Peters, Boyd, Mitchell, "Curved PN Triangles", I3D 2001), a cubic Bézier position with a
/// quadratic normal field, and Nagata patches (Nagata, "Simple local interpolation of surfaces
/// using normal vectors", CAGD 22, 2005) in the same form.

#include <array>
#include <cstdint>
#include <optional>

#include "facets/vec3.h"

namespace glint {

/// @brief How a PN triangle weights the mid-edge normals of its quadratic normal field.
///
/// A glint's irradiance is set by how fast the normal turns along the surface (the reflection
/// map's Jacobian), so the normal field must turn with the position, not only point the right
/// way at the vertices.
enum class PNNormalField : std::uint8_t {
  /// The Bernstein form n = Σ nᵢ bᵢ² + 2 Σ nᵢⱼ bᵢ bⱼ. On a circular edge with the bisecting
  /// mid-edge normal its direction is exactly the circle of normals (a rational quadratic with
  /// weight cos(α/2)), and in the interior it follows the surface's normal at the patch's own
  /// point to third order in the facet size, so its derivative, the curvature a glint sees,
  /// is right to second order. The default.
  Bernstein,
  /// As Vlachos et al. print it, n = Σ nᵢ bᵢ² + Σ nᵢⱼ bᵢ bⱼ: the mid-edge normal at half its
  /// Bernstein weight. The normal then leaves a vertex at half the rate the surface turns and
  /// catches up in the middle: its derivative is a quarter off at the facet's centre however
  /// fine the mesh, and a glint is tens of percent off until the facets are narrower than its
  /// lobe and the errors average out (a 5 120-triangle icosphere: 58 %). Kept to measure that.
  Vlachos,
};

/// @brief A PN triangle over barycentric coordinates (b0, b1, b2) of its vertices 0, 1, 2
/// (Vlachos' w, u, v). It interpolates the vertex positions and normals; its edges depend only
/// on the two vertices of the edge, so neighbours sharing vertex normals share the curve.
class PNTriangle {
 public:
  /// @brief From vertex positions @p p_m and unit vertex normals @p n.
  PNTriangle(const std::array<Vec3, 3>& p_m, const std::array<Vec3, 3>& n,
             PNNormalField field = PNNormalField::Bernstein);

  /// @brief A PN triangle whose edge curves are shared with its neighbours even across a
  /// crease (PN-AEN, McDonald and Kilgard 2010). @p across[e] holds the unit normals that the
  /// facet on the other side of edge e (vertices e, e+1 mod 3) has at those two vertices, in
  /// that order; on a boundary or a smooth edge they equal @p n. Each edge control point is the
  /// mean of the two sides' own, so both facets build the same edge and the surface neither
  /// cracks nor overlaps there, while each side keeps its own normal field (the crease stays
  /// sharp in the reflection).
  PNTriangle(const std::array<Vec3, 3>& p_m, const std::array<Vec3, 3>& n,
             const std::array<std::array<Vec3, 2>, 3>& across,
             PNNormalField field = PNNormalField::Bernstein);

  /// @brief A Nagata patch held as a PN triangle: the quadratic x(b) = Σ pᵢ bᵢ − Σ cᵢⱼ bᵢ bⱼ
  /// whose edge curves leave each vertex perpendicular to its normal (cᵢⱼ the edge's curvature
  /// coefficient, the least one in the span of the two normals), degree-elevated to a cubic net,
  /// with its own geometric normal ∂x/∂u × ∂x/∂v (a quadratic) as the normal field. @p across as
  /// above: an edge's coefficient is the mean of the two sides' own, so creases do not crack.
  /// Where an edge's normals are parallel the edge is straight (cᵢⱼ = 0).
  static PNTriangle nagata(const std::array<Vec3, 3>& p_m, const std::array<Vec3, 3>& n,
                           const std::array<std::array<Vec3, 2>, 3>& across);

  /// @brief Surface point at barycentric coordinates @p bary (components sum to 1).
  [[nodiscard]] Vec3 position(const Vec3& bary) const;

  /// @brief The derivative of position() along the barycentric direction @p delta (whose
  /// components sum to 0): the tangent ∂p/∂s of a parametrisation bary + s·delta.
  [[nodiscard]] Vec3 derivative(const Vec3& bary, const Vec3& delta) const;

  /// @brief The quadratic normal field, unnormalised: Σ nᵢ bᵢ² + 2 Σ nᵢⱼ bᵢ bⱼ over the
  /// controls (see PNNormalField for the mid-edge controls nᵢⱼ).
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
  PNTriangle() = default;
  void computeSagBound();

  std::array<Vec3, 10> b_;
  std::array<Vec3, 6> n_;  // Bernstein controls n200, n020, n002, n110, n011, n101
  double second_derivative_bound_m_ = 0.0;
};

}  // namespace glint
