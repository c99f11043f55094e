#pragma once
/// @file
/// @brief Quadric surfaces PᵀQP = 0 (the paper's Eq. 3–6): evaluation, gradient normals and
/// projection of points onto the surface for exact 1→4 subdivision.

#include <array>
#include <glm/mat3x3.hpp>
#include <glm/mat4x4.hpp>
#include <optional>

#include "facets/vec3.h"

namespace glint {

/// @brief The quadric xᵀA x + 2 bᵀx + c = 0, i.e. Q = [[A, b], [bᵀ, c]] acting on P = (x, 1).
///
/// The sign is part of the surface: glint keeps every quadric oriented so that its gradient
/// 2(Ax + b) points out of the object, which makes the gradient the outward normal.
class Quadric {
 public:
  Quadric() = default;
  /// @brief From the symmetric 3×3 block @p a, the vector @p b and the constant @p c.
  Quadric(const glm::dmat3& a, const Vec3& b, double c);

  /// @brief The open side of a cylinder, gradient pointing away from the axis.
  static Quadric cylinder(const Vec3& centre_m, const Vec3& unit_axis, double radius_m);
  /// @brief The double cone with apex @p apex_m, axis @p unit_axis and radius growing by
  /// @p slope per metre along it (> 0), gradient pointing away from the axis on both nappes.
  static Quadric cone(const Vec3& apex_m, const Vec3& unit_axis, double slope);
  /// @brief A sphere, gradient pointing outward.
  static Quadric sphere(const Vec3& centre_m, double radius_m);
  /// @brief A plane through @p point_m, gradient along @p unit_normal.
  static Quadric plane(const Vec3& point_m, const Vec3& unit_normal);

  /// @brief The paper's 4×4 matrix Q.
  [[nodiscard]] glm::dmat4 matrix() const;

  /// @brief PᵀQP at @p x (zero on the surface; its units are those of the coefficients).
  [[nodiscard]] double value(const Vec3& x) const { return glm::dot(x, a_ * x + 2.0 * b_) + c_; }

  /// @brief ∇(PᵀQP) = 2(Ax + b); normal to the level set through @p x.
  [[nodiscard]] Vec3 gradient(const Vec3& x) const { return 2.0 * (a_ * x + b_); }

  /// @brief The root t of PᵀQP(x + t d) = 0 nearest to 0, if the line meets the surface.
  [[nodiscard]] std::optional<double> nearestRoot(const Vec3& x, const Vec3& d) const;

  /// @brief @p x moved along the gradient onto the surface (the nearest crossing), or nothing
  /// when the gradient vanishes or the line misses the surface.
  [[nodiscard]] std::optional<Vec3> project(const Vec3& x) const;

  /// @brief L with |∇Q(x) − ∇Q(y)| ≤ L |x − y| for all x, y: twice the spectral norm of A.
  [[nodiscard]] double gradientLipschitz() const { return gradient_lipschitz_; }

  /// @brief Unit eigenvectors of A, the quadric's principal axes, in order of increasing |λ|:
  /// along an axis of small |λ| the gradient, and so the normal, hardly changes (a cylinder's
  /// axis, λ = 0, along which its normals have no component at all).
  [[nodiscard]] const std::array<Vec3, 3>& principalAxes() const { return principal_axes_; }

  /// @brief The same surface with the opposite orientation.
  [[nodiscard]] Quadric flipped() const { return Quadric(-a_, -b_, -c_); }

  [[nodiscard]] const glm::dmat3& a() const { return a_; }
  [[nodiscard]] const Vec3& b() const { return b_; }
  [[nodiscard]] double c() const { return c_; }

 private:
  glm::dmat3 a_{0.0};
  Vec3 b_{0.0};
  double c_ = 0.0;
  double gradient_lipschitz_ = 0.0;
  std::array<Vec3, 3> principal_axes_{Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)};
};

/// @brief A circular boundary curve of a surface (the rim of a disk). Subdivision points on a
/// boundary edge are placed on it, so refinement converges to the true outline, not to the
/// inscribed polygon of the coarse facets.
struct RimCircle {
  Vec3 centre_m{0.0};
  Vec3 normal{0.0, 0.0, 1.0};  ///< unit normal of the circle's plane
  double radius_m = 1.0;

  /// @brief The point of the circle nearest to @p x (x itself when it lies on the axis).
  [[nodiscard]] Vec3 project(const Vec3& x) const {
    const Vec3 rel = x - centre_m;
    const auto radial = tryNormalize(rel - glm::dot(rel, normal) * normal);
    return radial ? centre_m + radius_m * *radial : x;
  }
};

}  // namespace glint
