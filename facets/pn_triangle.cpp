#include "facets/pn_triangle.h"

#include <algorithm>
#include <cmath>

namespace glint {
namespace {

// Control point index for exponents (i, j, k) of (b0, b1, b2), i + j + k = 3.
int controlIndex(int i, int j, int k) {
  if (i == 3) return 0;
  if (j == 3) return 1;
  if (k == 3) return 2;
  if (i == 2 && j == 1) return 3;
  if (i == 1 && j == 2) return 4;
  if (j == 2 && k == 1) return 5;
  if (j == 1 && k == 2) return 6;
  if (i == 1 && k == 2) return 7;
  if (i == 2 && k == 1) return 8;
  return 9;  // (1, 1, 1)
}

// Edge control point near vertex p_i toward p_j: a third of the way along the edge,
// projected into the tangent plane of the normal n_i.
Vec3 edgeControl(const Vec3& p_i, const Vec3& p_j, const Vec3& n_i) {
  const double w = glm::dot(p_j - p_i, n_i);
  return (2.0 * p_i + p_j - w * n_i) / 3.0;
}

}  // namespace

PNTriangle::PNTriangle(const std::array<Vec3, 3>& p, const std::array<Vec3, 3>& n,
                       PNNormalField field)
    : PNTriangle(p, n, {{{n[0], n[1]}, {n[1], n[2]}, {n[2], n[0]}}}, field) {}

PNTriangle::PNTriangle(const std::array<Vec3, 3>& p, const std::array<Vec3, 3>& n,
                       const std::array<std::array<Vec3, 2>, 3>& across, PNNormalField field) {
  // Near vertex i on edge e, toward j; `other` is the neighbour's normal at vertex i. The sum
  // is symmetric, so the neighbour computes the very same double.
  auto shared = [&](int i, int j, const Vec3& other) {
    return 0.5 * (edgeControl(p[i], p[j], n[i]) + edgeControl(p[i], p[j], other));
  };
  b_[0] = p[0];
  b_[1] = p[1];
  b_[2] = p[2];
  b_[3] = shared(0, 1, across[0][0]);  // b210
  b_[4] = shared(1, 0, across[0][1]);  // b120
  b_[5] = shared(1, 2, across[1][0]);  // b021
  b_[6] = shared(2, 1, across[1][1]);  // b012
  b_[7] = shared(2, 0, across[2][0]);  // b102
  b_[8] = shared(0, 2, across[2][1]);  // b201
  Vec3 e(0.0);
  for (int k = 3; k < 9; ++k) e += b_[k];
  e /= 6.0;
  const Vec3 v = (p[0] + p[1] + p[2]) / 3.0;
  b_[9] = e + 0.5 * (e - v);

  // Mid-edge normal: the average normal reflected across the plane perpendicular to the edge,
  // which lets the normal field capture inflections the position cannot.
  auto midNormal = [&](int i, int j) {
    const Vec3 d = p[j] - p[i];
    const double len2 = glm::dot(d, d);
    const double vij = len2 > 0.0 ? 2.0 * glm::dot(d, n[i] + n[j]) / len2 : 0.0;
    if (auto m = tryNormalize(n[i] + n[j] - vij * d)) return *m;
    return n[i];
  };
  const double weight = field == PNNormalField::Bernstein ? 1.0 : 0.5;
  n_ = {n[0],
        n[1],
        n[2],
        weight * midNormal(0, 1),
        weight * midNormal(1, 2),
        weight * midNormal(0, 2)};
  computeSagBound();
}

PNTriangle PNTriangle::nagata(const std::array<Vec3, 3>& p, const std::array<Vec3, 3>& n,
                              const std::array<std::array<Vec3, 2>, 3>& across) {
  // The edge curve x(t) = pᵢ + (d − c) t + c t², d = pⱼ − pᵢ, leaves pᵢ along d − c and reaches
  // pⱼ along d + c; with c = α nᵢ + β nⱼ, tangency to both normals is the 2×2 system
  // [1 γ; γ 1] (α, β) = (nᵢ·d, −nⱼ·d), γ = nᵢ·nⱼ.
  auto curvature = [&](int i, int j, const Vec3& ni, const Vec3& nj) {
    const Vec3 d = p[j] - p[i];
    const double gamma = glm::dot(ni, nj);
    const double det = 1.0 - gamma * gamma;
    // Parallel normals (to a microradian) leave the edge straight: its sag is then below the
    // rounding of the positions, while α and β would divide two vanishing numbers.
    if (!(det > 1e-12)) return Vec3(0.0);
    const double a = glm::dot(ni, d), b = -glm::dot(nj, d);
    return ((a - gamma * b) * ni + (b - gamma * a) * nj) / det;
  };
  auto shared = [&](int e) {
    const int i = e, j = (e + 1) % 3;
    return 0.5 * (curvature(i, j, n[i], n[j]) + curvature(i, j, across[e][0], across[e][1]));
  };
  // The quadratic's Bernstein mid controls, mᵢⱼ = (pᵢ + pⱼ − cᵢⱼ) / 2, raised to the cubic net.
  const std::array<Vec3, 3> c = {shared(0), shared(1), shared(2)};  // edges 01, 12, 20
  const Vec3 m01 = 0.5 * (p[0] + p[1] - c[0]);
  const Vec3 m12 = 0.5 * (p[1] + p[2] - c[1]);
  const Vec3 m20 = 0.5 * (p[2] + p[0] - c[2]);
  PNTriangle t;
  t.b_ = {p[0],
          p[1],
          p[2],
          (p[0] + 2.0 * m01) / 3.0,
          (p[1] + 2.0 * m01) / 3.0,
          (p[1] + 2.0 * m12) / 3.0,
          (p[2] + 2.0 * m12) / 3.0,
          (p[2] + 2.0 * m20) / 3.0,
          (p[0] + 2.0 * m20) / 3.0,
          (m01 + m12 + m20) / 3.0};
  // The geometric normal is a quadratic: its Bernstein controls from its values at the corners
  // and edge midpoints, nᵢⱼ = 2 N(midpoint) − (Nᵢ + Nⱼ) / 2.
  auto geometric = [&](const Vec3& bary) {
    return glm::cross(t.derivative(bary, Vec3(-1.0, 1.0, 0.0)),
                      t.derivative(bary, Vec3(-1.0, 0.0, 1.0)));
  };
  const std::array<Vec3, 3> at = {geometric(Vec3(1.0, 0.0, 0.0)), geometric(Vec3(0.0, 1.0, 0.0)),
                                  geometric(Vec3(0.0, 0.0, 1.0))};
  auto mid = [&](int i, int j) {
    Vec3 bary(0.0);
    bary[i] = bary[j] = 0.5;
    return 2.0 * geometric(bary) - 0.5 * (at[i] + at[j]);
  };
  t.n_ = {at[0], at[1], at[2], mid(0, 1), mid(1, 2), mid(0, 2)};
  t.computeSagBound();
  return t;
}

void PNTriangle::computeSagBound() {
  // Largest second difference of the net in the two parameter directions and their mix.
  double m = 0.0;
  const int basis[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  for (const auto& beta : basis) {
    auto ctrl = [&](int i, int j, int k) {
      return b_[controlIndex(beta[0] + i, beta[1] + j, beta[2] + k)];
    };
    const Vec3 ss = ctrl(0, 2, 0) - 2.0 * ctrl(1, 1, 0) + ctrl(2, 0, 0);
    const Vec3 tt = ctrl(0, 0, 2) - 2.0 * ctrl(1, 0, 1) + ctrl(2, 0, 0);
    const Vec3 st = ctrl(0, 1, 1) - ctrl(1, 1, 0) - ctrl(1, 0, 1) + ctrl(2, 0, 0);
    m = std::max({m, glm::length(ss), glm::length(tt), glm::length(st)});
  }
  second_derivative_bound_m_ = 6.0 * m;
}

Vec3 PNTriangle::position(const Vec3& t) const {
  const double w = t[0], u = t[1], v = t[2];
  return b_[0] * (w * w * w) + b_[1] * (u * u * u) + b_[2] * (v * v * v) +
         3.0 * (b_[3] * (w * w * u) + b_[4] * (w * u * u) + b_[5] * (u * u * v) +
                b_[6] * (u * v * v) + b_[7] * (w * v * v) + b_[8] * (w * w * v)) +
         6.0 * b_[9] * (w * u * v);
}

Vec3 PNTriangle::derivative(const Vec3& t, const Vec3& d) const {
  // Partial derivatives of the homogeneous cubic in (w, u, v), contracted with d.
  const double w = t[0], u = t[1], v = t[2];
  const Vec3 dw = 3.0 * (b_[0] * (w * w) + b_[3] * (2 * w * u) + b_[4] * (u * u) + b_[7] * (v * v) +
                         b_[8] * (2 * w * v)) +
                  6.0 * b_[9] * (u * v);
  const Vec3 du = 3.0 * (b_[1] * (u * u) + b_[3] * (w * w) + b_[4] * (2 * w * u) +
                         b_[5] * (2 * u * v) + b_[6] * (v * v)) +
                  6.0 * b_[9] * (w * v);
  const Vec3 dv = 3.0 * (b_[2] * (v * v) + b_[5] * (u * u) + b_[6] * (2 * u * v) +
                         b_[7] * (2 * w * v) + b_[8] * (w * w)) +
                  6.0 * b_[9] * (w * u);
  return d[0] * dw + d[1] * du + d[2] * dv;
}

Vec3 PNTriangle::normalField(const Vec3& t) const {
  const double w = t[0], u = t[1], v = t[2];
  return n_[0] * (w * w) + n_[1] * (u * u) + n_[2] * (v * v) +
         2.0 * (n_[3] * (w * u) + n_[4] * (u * v) + n_[5] * (w * v));
}

double PNTriangle::normalConeHalfAngle(const std::array<Vec3, 3>& c, const Vec3& axis) const {
  // The field is a homogeneous quadratic N; its blossom is B(x, y) = (N(x + y) − N(x) − N(y))/2
  // and the sub-triangle's Bernstein controls are N(cᵢ) and B(cᵢ, cⱼ).
  const std::array<Vec3, 3> at = {normalField(c[0]), normalField(c[1]), normalField(c[2])};
  auto blossom = [&](int i, int j) { return 0.5 * (normalField(c[i] + c[j]) - at[i] - at[j]); };
  const std::array<Vec3, 6> controls = {at[0],         at[1],         at[2],
                                        blossom(0, 1), blossom(1, 2), blossom(0, 2)};
  double half_angle = 0.0;
  for (const Vec3& m : controls) {
    if (glm::dot(m, m) == 0.0) continue;
    half_angle = std::max(half_angle, angleBetween(axis, m));
  }
  // Beyond 90° the cone is no longer convex and the hull argument fails.
  return half_angle < 0.5 * kPi ? half_angle : kPi;
}

double PNTriangle::sagBound(int depth) const {
  // In (s, t) = (b1, b2) coordinates two points of the unit triangle differ by |Δs| + |Δt| ≤ 2.
  const double size = std::ldexp(2.0, -depth);
  return 0.5 * second_derivative_bound_m_ * size * size;
}

}  // namespace glint
