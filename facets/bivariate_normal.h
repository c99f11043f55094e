#pragma once
/// @file
/// @brief The standard bivariate normal over a convex polygon: its mass (by Owen's T over the
/// edges), mean, covariance and skew, accurate for a polygon that holds the whole density, cuts
/// it, is thin against it, or lies far out in its tail; and the convex clipping that makes such
/// polygons from a triangle. A general tool: the lobe rule (lobe_rule.h) integrates its
/// Gaussian lobe over a piece's lit part with it, in coordinates where the lobe is standard.

#include <array>
#include <cmath>
#include <glm/vec2.hpp>
#include <span>

namespace glint {

using Vec2 = glm::dvec2;

/// @brief The z component of the cross product of two plane vectors (twice the signed area of
/// the triangle they span, positive counter-clockwise).
inline double cross2(const Vec2& a, const Vec2& b) { return a.x * b.y - a.y * b.x; }

/// @brief Q(x) = 1 − Φ(x), the standard normal's upper tail, accurate deep in the tail.
inline double normalUpperTail(double x) { return 0.5 * std::erfc(x / 1.41421356237309504880); }

/// @brief A convex polygon in a triangle's reference coordinates (s, t), where the triangle is
/// (0,0), (1,0), (0,1). Four clips of the triangle leave at most 7 vertices.
struct ConvexPolygon {
  std::array<Vec2, 8> v{};
  int n = 0;
};

/// @brief Keeps the part of @p p where the function that is linear over the reference triangle,
/// with corner values @p f, is positive (Sutherland–Hodgman for one half-plane). Never writes
/// past 7 vertices.
void clipPolygon(ConvexPolygon& p, const std::array<double, 3>& f);

/// @brief The distance from the origin to the convex counter-clockwise polygon @p ccw (0 where
/// the origin is inside it).
double distanceToOrigin(std::span<const Vec2> ccw);

/// @brief ∫ φ₂(y) dy, ∫ y φ₂(y) dy and ∫ y yᵀ φ₂(y) dy over a polygon, φ₂ the standard bivariate
/// normal density e^{−|y|²/2} / 2π; and the mean and covariance of φ₂ restricted to it, which
/// a small polygon far from the origin cannot get from the raw moments (its covariance is the
/// difference of two numbers larger by the squared ratio of its distance to its size).
struct NormalMoments {
  double mass = 0.0;
  Vec2 first{0.0};
  double second_xx = 0.0, second_xy = 0.0, second_yy = 0.0;
  Vec2 mean{0.0};                                   ///< first / mass (0 without mass)
  double cov_xx = 0.0, cov_xy = 0.0, cov_yy = 0.0;  ///< about the mean, per unit mass
  /// The third moments about the mean, per unit mass: the skew that cutting the density
  /// gives it (0 for the whole plane; a half-normal's 0.218 across its edge).
  double skew_xxx = 0.0, skew_xxy = 0.0, skew_xyy = 0.0, skew_yyy = 0.0;
  /// False where the skew is not resolved in double precision (a polygon far out in the
  /// density's tail, not small enough for the quadrature): the skew_ fields are then 0.
  bool skew_known = false;
};

/// @brief The moments of the standard bivariate normal over the convex polygon with
/// counter-clockwise vertices @p ccw (at most 16).
///
/// - In closed form where that is well conditioned: the mass by Owen's T over its edges (the
///   winding number less each edge's tail beyond it), the higher moments by the divergence
///   theorem (∫ y φ₂ = −∮ φ₂ n ds, ∫ yᵢ yⱼ φ₂ = δᵢⱼ mass − ∮ yⱼ φ₂ nᵢ ds,
///   ∫ yᵢ yⱼ yₖ φ₂ = δᵢⱼ ∫ yₖ φ₂ + δᵢₖ ∫ yⱼ φ₂ − ∮ yⱼ yₖ φ₂ nᵢ ds).
/// - Otherwise (a polygon small against the density's scale, or far out in its tail, where the
///   edge terms cancel to below their own rounding), if the density varies by at most e⁸ over
///   it: by a degree-11 rule on triangles over each of which it varies by at most e², in a
///   frame at the polygon, so that mass, mean and covariance keep their precision however far
///   out the polygon is.
///
/// Never throws; an empty or degenerate polygon gives zeros.
NormalMoments standardNormalOverPolygon(std::span<const Vec2> ccw);

}  // namespace glint
