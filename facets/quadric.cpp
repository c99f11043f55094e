#include "facets/quadric.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

namespace glint {

Quadric::Quadric(const glm::dmat3& a, const Vec3& b, double c) : a_(a), b_(b), c_(c) {
  Eigen::Matrix3d m;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) m(i, j) = 0.5 * (a[j][i] + a[i][j]);
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> direct;
  direct.computeDirect(m, Eigen::EigenvaluesOnly);
  gradient_lipschitz_ = 2.0 * direct.eigenvalues().cwiseAbs().maxCoeff();
  // The axes from the iterative solver: its eigenvectors stay accurate where eigenvalues
  // repeat (a cylinder's 1, 1, 0), where the closed form's lose digits.
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(m);
  if (eig.info() != Eigen::Success) return;  // the coordinate axes: still axes, just less apt
  std::array<int, 3> order{0, 1, 2};
  std::sort(order.begin(), order.end(), [&](int i, int j) {
    return std::abs(eig.eigenvalues()(i)) < std::abs(eig.eigenvalues()(j));
  });
  for (int k = 0; k < 3; ++k) {
    const auto v = eig.eigenvectors().col(order[k]);
    if (const auto unit = tryNormalize(Vec3(v(0), v(1), v(2)))) principal_axes_[k] = *unit;
  }
}

Quadric Quadric::cylinder(const Vec3& centre_m, const Vec3& unit_axis, double radius_m) {
  // |x − c|² − ((x − c)·a)² − R² with A = I − a aᵀ.
  const glm::dmat3 a = glm::dmat3(1.0) - glm::outerProduct(unit_axis, unit_axis);
  const Vec3 ac = a * centre_m;
  return Quadric(a, -ac, glm::dot(centre_m, ac) - radius_m * radius_m);
}

Quadric Quadric::cone(const Vec3& apex_m, const Vec3& unit_axis, double slope) {
  // |x − p|² − (1 + k²)((x − p)·a)² with A = I − (1 + k²) a aᵀ: 2A(x − p) has the radial part
  // of x − p, outward on either side of the apex.
  const glm::dmat3 a =
      glm::dmat3(1.0) - (1.0 + slope * slope) * glm::outerProduct(unit_axis, unit_axis);
  const Vec3 ap = a * apex_m;
  return Quadric(a, -ap, glm::dot(apex_m, ap));
}

Quadric Quadric::sphere(const Vec3& centre_m, double radius_m) {
  return Quadric(glm::dmat3(1.0), -centre_m, glm::dot(centre_m, centre_m) - radius_m * radius_m);
}

Quadric Quadric::plane(const Vec3& point_m, const Vec3& unit_normal) {
  return Quadric(glm::dmat3(0.0), 0.5 * unit_normal, -glm::dot(unit_normal, point_m));
}

glm::dmat4 Quadric::matrix() const {
  glm::dmat4 q(0.0);
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) q[j][i] = a_[j][i];
    q[3][i] = b_[i];
    q[i][3] = b_[i];
  }
  q[3][3] = c_;
  return q;
}

std::optional<double> Quadric::nearestRoot(const Vec3& x, const Vec3& d) const {
  // PᵀQP(x + t d) = α t² + 2β t + γ.
  const double alpha = glm::dot(d, a_ * d);
  const double beta = glm::dot(d, a_ * x + b_);
  const double gamma = value(x);
  if (gamma == 0.0) return 0.0;
  if (alpha == 0.0) {
    if (beta == 0.0) return std::nullopt;
    return -gamma / (2.0 * beta);
  }
  const double disc = beta * beta - alpha * gamma;
  if (disc < 0.0) return std::nullopt;
  // The cancellation-free pair of roots: q/α and γ/q with q = −(β + sign(β)√disc).
  const double q = -(beta + std::copysign(std::sqrt(disc), beta));
  const double t_far = q / alpha;
  if (q == 0.0) return t_far;
  const double t_near = gamma / q;
  return std::abs(t_near) <= std::abs(t_far) ? t_near : t_far;
}

std::optional<Vec3> Quadric::project(const Vec3& x) const {
  const auto dir = tryNormalize(gradient(x));
  if (!dir) return std::nullopt;
  const auto t = nearestRoot(x, *dir);
  if (!t) return std::nullopt;
  return x + *t * *dir;
}

}  // namespace glint
