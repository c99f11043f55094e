#include "facets/triangle_rule.h"

#include <Eigen/Eigenvalues>
#include <array>
#include <mutex>
#include <stdexcept>
#include <vector>

namespace glint {
namespace {

struct Gauss1D {
  std::vector<double> node;    // on [0, 1]
  std::vector<double> weight;  // sums to ∫₀¹ w(x) dx
};

// Golub–Welsch for the Jacobi weight (1 − x)^α on [−1, 1] (β = 0), mapped to [0, 1]. The
// three-term recurrence of the orthonormal polynomials is the symmetric tridiagonal matrix
// below; its eigenvalues are the nodes and μ₀ times the squared first components of its
// eigenvectors the weights.
Gauss1D gaussJacobi(int n, int alpha) {
  Eigen::MatrixXd j = Eigen::MatrixXd::Zero(n, n);
  const double a = alpha;
  for (int k = 0; k < n; ++k) {
    const double s = 2.0 * k + a;
    j(k, k) = s == 0.0 ? 0.0 : -a * a / (s * (s + 2.0));
    if (k > 0) {
      const double kk = k;
      const double off =
          std::sqrt(4.0 * kk * (kk + a) * kk * (kk + a) / (s * s * (s + 1.0) * (s - 1.0)));
      j(k, k - 1) = j(k - 1, k) = off;
    }
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(j);
  const double mu0 = std::pow(2.0, a + 1.0) / (a + 1.0);  // ∫ (1 − x)^α dx over [−1, 1]
  Gauss1D g;
  for (int i = 0; i < n; ++i) {
    const double x = eig.eigenvalues()(i);
    const double v = eig.eigenvectors()(0, i);
    g.node.push_back(0.5 * (x + 1.0));
    // dx = 2 dξ and (1 − x)^α = 2^α (1 − ξ)^α.
    g.weight.push_back(mu0 * v * v / std::pow(2.0, a + 1.0));
  }
  return g;
}

std::vector<TriangleNode> build(int n) {
  const Gauss1D xi = gaussJacobi(n, 1);   // ∫₀¹ (1 − ξ) g dξ
  const Gauss1D eta = gaussJacobi(n, 0);  // ∫₀¹ g dη
  std::vector<TriangleNode> rule;
  for (int i = 0; i < n; ++i) {
    for (int k = 0; k < n; ++k) {
      const double l1 = xi.node[i];
      const double l2 = (1.0 - xi.node[i]) * eta.node[k];
      // ∫_T f = Σ wξ wη f; the triangle's area is ½, so the normalised weight is twice that.
      rule.push_back({Vec3(1.0 - l1 - l2, l1, l2), 2.0 * xi.weight[i] * eta.weight[k]});
    }
  }
  return rule;
}

}  // namespace

std::span<const TriangleNode> conicalProductRule(int n) {
  constexpr int kMax = 12;
  if (n < 1 || n > kMax) throw std::invalid_argument("conicalProductRule: n out of range");
  static std::array<std::vector<TriangleNode>, kMax + 1> rules;
  static std::array<std::once_flag, kMax + 1> once;
  std::call_once(once[n], [n] { rules[n] = build(n); });
  return rules[n];
}

}  // namespace glint
