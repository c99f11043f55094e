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

// A triangle of a unit sphere whose corners are about h apart (radians), its normals exact.
struct SmallSpherePatch {
  std::array<Vec3, 3> p, n;
  explicit SmallSpherePatch(double h) {
    auto at = [](double theta, double phi) {
      return Vec3(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi),
                  std::cos(theta));
    };
    p = {at(0.3, 0.0), at(0.3 + h, 0.0), at(0.3 + 0.5 * h, h)};
    n = p;
  }
};

// How far a patch's normal field is from the normal of the sphere at the patch's own points:
// the largest angle, and the largest relative error of its derivative (the curvature a glint
// sees: on a unit sphere dn/ds = dp/ds exactly), over a lattice of barycentric points.
struct Consistency {
  double angle_rad = 0.0;
  double derivative = 0.0;
};
Consistency consistencyOnUnitSphere(const PNTriangle& pn) {
  Consistency c;
  const double step = 1e-5;  // central differences: error ~1e-10, far below what is measured
  const std::array<Vec3, 2> dirs = {Vec3(-1, 1, 0), Vec3(-1, 0, 1)};
  for (int i = 1; i < 8; ++i) {
    for (int j = 1; i + j < 8; ++j) {
      const Vec3 b(1.0 - i / 8.0 - j / 8.0, i / 8.0, j / 8.0);
      c.angle_rad = std::max(c.angle_rad, angleBetween(*pn.normal(b), pn.position(b)));
      for (const Vec3& d : dirs) {
        const Vec3 dn = (*pn.normal(b + step * d) - *pn.normal(b - step * d)) / (2 * step);
        const Vec3 dp = pn.derivative(b, d);
        const Vec3 dtrue = dp - glm::dot(dp, *pn.normal(b)) * *pn.normal(b);
        c.derivative = std::max(c.derivative, glm::length(dn - dtrue) / glm::length(dtrue));
      }
    }
  }
  return c;
}

TEST(PNTriangle, NormalFieldTurnsWithTheSurfaceToSecondOrder) {
  // The Bernstein field's direction follows the sphere's normal at the patch's points to third
  // order in h and its derivative to second: halving h divides them by 8 and 4 (asymptotically;
  // ≥ 6 and ≥ 3 leave room for the next order at these sizes).
  const Consistency coarse =
      consistencyOnUnitSphere(PNTriangle(SmallSpherePatch(0.2).p, SmallSpherePatch(0.2).n));
  const Consistency fine =
      consistencyOnUnitSphere(PNTriangle(SmallSpherePatch(0.1).p, SmallSpherePatch(0.1).n));
  EXPECT_GT(coarse.angle_rad / fine.angle_rad, 6.0)
      << coarse.angle_rad << " rad at h = 0.2, " << fine.angle_rad << " at 0.1";
  EXPECT_GT(coarse.derivative / fine.derivative, 3.0)
      << coarse.derivative << " at h = 0.2, " << fine.derivative << " at 0.1";
  EXPECT_LT(fine.derivative, 1e-2) << "the curvature a glint sees, at 0.1 rad facets";
}

TEST(PNTriangle, PublishedNormalFieldMissesTheCurvatureAtAnySize) {
  // Vlachos' printed weights b_i b_j: the normal leaves a corner at half the surface's rate, so
  // near the corners its derivative is off by up to a half, and that does not shrink with h. The
  // Bernstein field, from the same controls, is within 1 %.
  for (const double h : {0.2, 0.05}) {
    const SmallSpherePatch s(h);
    const Consistency vlachos =
        consistencyOnUnitSphere(PNTriangle(s.p, s.n, PNNormalField::Vlachos));
    const Consistency bernstein = consistencyOnUnitSphere(PNTriangle(s.p, s.n));
    EXPECT_GT(vlachos.derivative, 0.2) << "h = " << h;
    EXPECT_LT(bernstein.derivative, 0.01) << "h = " << h;
  }
}

TEST(NagataPatch, InterpolatesVerticesAndNormalsWithItsOwnGeometricNormal) {
  const SmallSpherePatch s(0.3);
  const PNTriangle patch =
      PNTriangle::nagata(s.p, s.n, {{{s.n[0], s.n[1]}, {s.n[1], s.n[2]}, {s.n[2], s.n[0]}}});
  const std::array<Vec3, 3> corners = {Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)};
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(glm::length(patch.position(corners[i]) - s.p[i]), 0.0, 1e-15) << "vertex " << i;
    EXPECT_NEAR(angleBetween(*patch.normal(corners[i]), s.n[i]), 0.0, 1e-14) << "normal " << i;
  }
  // The normal field is the patch's own: ∂x/∂u × ∂x/∂v everywhere, not only at the corners.
  std::mt19937_64 rng(5);
  for (int k = 0; k < 100; ++k) {
    const Vec3 b = randomBary(rng);
    const Vec3 geometric =
        glm::cross(patch.derivative(b, Vec3(-1, 1, 0)), patch.derivative(b, Vec3(-1, 0, 1)));
    EXPECT_NEAR(angleBetween(*patch.normal(b), geometric), 0.0, 1e-13)
        << "at " << b.x << ", " << b.y;
  }
}

TEST(NagataPatch, EdgesLeaveEachVertexInItsTangentPlaneAndParallelNormalsStayFlat) {
  const SmallSpherePatch s(0.3);
  const std::array<std::array<Vec3, 2>, 3> own = {
      {{s.n[0], s.n[1]}, {s.n[1], s.n[2]}, {s.n[2], s.n[0]}}};
  const PNTriangle patch = PNTriangle::nagata(s.p, s.n, own);
  // Along edge 0 → 1 from vertex 0: the tangent is perpendicular to n0 (to rounding).
  const Vec3 t = patch.derivative(Vec3(1, 0, 0), Vec3(-1, 1, 0));
  EXPECT_NEAR(glm::dot(t, s.n[0]) / glm::length(t), 0.0, 1e-14);
  const Vec3 n(0.0, 0.0, 1.0);
  const std::array<Vec3, 3> flat = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  const PNTriangle plane = PNTriangle::nagata(flat, {n, n, n}, {{{n, n}, {n, n}, {n, n}}});
  EXPECT_EQ(plane.position(Vec3(0.2, 0.3, 0.5)).z, 0.0) << "parallel normals: the chord itself";
}

}  // namespace
}  // namespace glint
