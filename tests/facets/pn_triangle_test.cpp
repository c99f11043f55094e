#include "facets/pn_triangle.h"

#include <gtest/gtest.h>

#include <random>

namespace glint {
namespace {

// Three points of a sphere of radius 2 with their exact normals: a curved test patch.
struct SpherePatch {
  std::array<Vec3, 3> p, n;
  SpherePatch() {
    const std::array<Vec3, 3> dirs = {glm::normalize(Vec3(1, 0.1, 0.2)),
                                      glm::normalize(Vec3(0.2, 1, 0.1)),
                                      glm::normalize(Vec3(0.1, 0.2, 1))};
    for (int i = 0; i < 3; ++i) {
      n[i] = dirs[i];
      p[i] = 2.0 * dirs[i];
    }
  }
};

Vec3 randomBary(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  double a = u(rng), b = u(rng);
  if (a + b > 1.0) {
    a = 1.0 - a;
    b = 1.0 - b;
  }
  return Vec3(1.0 - a - b, a, b);
}

TEST(PNTriangle, InterpolatesVerticesAndNormals) {
  const SpherePatch s;
  const PNTriangle pn(s.p, s.n);
  const std::array<Vec3, 3> corners = {Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)};
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(glm::length(pn.position(corners[i]) - s.p[i]), 0.0, 1e-15) << "vertex " << i;
    EXPECT_NEAR(angleBetween(*pn.normal(corners[i]), s.n[i]), 0.0, 1e-15) << "normal " << i;
  }
}

TEST(PNTriangle, FlatWhenNormalsAgree) {
  const Vec3 n = glm::normalize(Vec3(0.2, -0.3, 1.0));
  const Vec3 u = anyPerpendicular(n), v = glm::cross(n, u);
  const std::array<Vec3, 3> p = {Vec3(1, 2, 3), Vec3(1, 2, 3) + 0.5 * u,
                                 Vec3(1, 2, 3) + 0.2 * u + 0.7 * v};
  const PNTriangle pn(p, {n, n, n});
  std::mt19937_64 rng(1);
  // Exact up to rounding of coordinates of size ~4: a few units of 4 × 2⁻⁵².
  const double rounding = 32.0 * 4.0 * 0x1p-52;
  for (int k = 0; k < 200; ++k) {
    const Vec3 b = randomBary(rng);
    const Vec3 linear = b[0] * p[0] + b[1] * p[1] + b[2] * p[2];
    EXPECT_NEAR(glm::dot(pn.position(b) - p[0], n), 0.0, rounding) << "stays in the plane";
    EXPECT_NEAR(glm::length(pn.position(b) - linear), 0.0, rounding) << "and is the flat triangle";
    EXPECT_NEAR(angleBetween(*pn.normal(b), n), 0.0, 1e-14) << "with a constant normal";
  }
  EXPECT_LT(pn.sagBound(0), rounding) << "no bulge to bound";
}

TEST(PNTriangle, SharedEdgeDependsOnlyOnItsTwoVertices) {
  // Two triangles on one edge (p0, p1) with different third vertices: the edge curve agrees,
  // so a PN mesh does not crack where vertex normals are shared.
  const SpherePatch s;
  const PNTriangle a(s.p, s.n);
  const Vec3 other = 2.0 * glm::normalize(Vec3(1, 1, -0.5));
  const PNTriangle b({s.p[1], s.p[0], other}, {s.n[1], s.n[0], glm::normalize(other)});
  for (double t = 0.0; t <= 1.0; t += 0.125) {
    EXPECT_NEAR(glm::length(a.position(Vec3(1 - t, t, 0)) - b.position(Vec3(t, 1 - t, 0))), 0.0,
                1e-15)
        << "t = " << t;
  }
}

TEST(PNTriangle, ConeAndSagBoundEverySubPatch) {
  const SpherePatch s;
  const PNTriangle pn(s.p, s.n);
  std::mt19937_64 rng(3);
  // Sub-triangles of the 1→4 hierarchy at depth d: the corner child, scaled by 2^-d.
  for (int depth = 0; depth <= 4; ++depth) {
    const double size = std::ldexp(1.0, -depth);
    const std::array<Vec3, 3> corners = {Vec3(1, 0, 0), Vec3(1 - size, size, 0),
                                         Vec3(1 - size, 0, size)};
    const Vec3 axis = *pn.normal((corners[0] + corners[1] + corners[2]) / 3.0);
    const double cone = pn.normalConeHalfAngle(corners, axis);
    const double sag = pn.sagBound(depth);
    const std::array<Vec3, 3> q = {pn.position(corners[0]), pn.position(corners[1]),
                                   pn.position(corners[2])};
    double worst_angle = 0.0, worst_sag = 0.0;
    for (int k = 0; k < 2000; ++k) {
      const Vec3 w = randomBary(rng);
      const Vec3 b = w[0] * corners[0] + w[1] * corners[1] + w[2] * corners[2];
      worst_angle = std::max(worst_angle, angleBetween(*pn.normal(b), axis));
      const Vec3 linear = w[0] * q[0] + w[1] * q[1] + w[2] * q[2];
      worst_sag = std::max(worst_sag, glm::length(pn.position(b) - linear));
    }
    EXPECT_LE(worst_angle, cone) << "depth " << depth;
    EXPECT_LE(worst_sag, sag) << "depth " << depth;
    // And the bounds shrink with the patch (they are not merely huge).
    EXPECT_LT(cone, 4.0 * worst_angle + 1e-12) << "depth " << depth;
  }
}

}  // namespace
}  // namespace glint
