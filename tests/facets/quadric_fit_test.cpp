#include "facets/quadric_fit.h"

#include <gtest/gtest.h>

#include <utility>

#include "facets/tessellate.h"

namespace glint {
namespace {

struct Facet {
  std::array<Vec3, 3> p, n;
};

Facet onSphere(const Vec3& centre, double radius, double spread) {
  Facet f;
  const std::array<Vec3, 3> dirs = {glm::normalize(Vec3(spread, 0, 1)),
                                    glm::normalize(Vec3(-0.5 * spread, 0.87 * spread, 1)),
                                    glm::normalize(Vec3(-0.5 * spread, -0.87 * spread, 1))};
  for (int i = 0; i < 3; ++i) {
    f.n[i] = dirs[i];
    f.p[i] = centre + radius * dirs[i];
  }
  return f;
}

TEST(QuadricFit, InterpolatesVerticesAndNormalsAndHugsTheSurface) {
  const Vec3 centre(1, 2, 3);
  const double radius = 2.0;
  const Facet f = onSphere(centre, radius, 0.4);
  const QuadricFit fit = fitQuadric(f.p, f.n);
  ASSERT_EQ(fit.status, QuadricFitStatus::Ok) << "rank gap " << fit.rank_gap;
  const Quadric& q = *fit.quadric;
  // Three vertices and normals fix the sphere only up to the z² term of the chord frame, so
  // the fit follows the sphere to second order in the facet's height h over its chord: at
  // most h² / R away from it (twice the leading term h² / 2R).
  const Vec3 mean = (f.p[0] + f.p[1] + f.p[2]) / 3.0;
  const double circumradius = glm::length(f.p[0] - mean);
  const double h = radius - std::sqrt(radius * radius - circumradius * circumradius);
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(q.value(f.p[i]) / glm::length(q.gradient(f.p[i])), 0.0, 1e-12) << "vertex " << i;
    EXPECT_NEAR(angleBetween(q.gradient(f.p[i]), f.n[i]), 0.0, 1e-9) << "normal " << i;
    const auto m = q.project(0.5 * (f.p[i] + f.p[(i + 1) % 3]));
    ASSERT_TRUE(m.has_value());
    EXPECT_NEAR(glm::length(*m - centre), radius, h * h / radius) << "edge " << i;
  }
  const auto c = q.project(mean);
  ASSERT_TRUE(c.has_value());
  EXPECT_NEAR(glm::length(*c - centre), radius, h * h / radius) << "centre";
}

TEST(QuadricFit, FlatFacetIsSingularAndFallsBackToPN) {
  const Vec3 n(0, 0, 1);
  const std::array<Vec3, 3> p = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  const QuadricFit fit = fitQuadric(p, {n, n, n});
  EXPECT_EQ(fit.status, QuadricFitStatus::Singular) << "rank gap " << fit.rank_gap;
  EXPECT_FALSE(fit.quadric.has_value());

  Target t;
  t.addMaterial({});
  const MeshStats stats =
      addMesh(t, Vec3(0), 0, {p[0], p[1], p[2]}, {n, n, n}, {{0, 1, 2}}, MeshSurface::QuadricFit);
  EXPECT_EQ(stats.fit_fallbacks, 1u);
  EXPECT_EQ(stats.quadric_fits, 0u);
  ASSERT_EQ(t.facetCount(), 1u);
  EXPECT_EQ(t.model[0], SurfaceModel::PN) << "a refused fit falls back to a PN triangle";
}

TEST(QuadricFit, NearlyFlatFacetIsIllConditioned) {
  // A patch of a sphere so large the facet is flat to ~1e-10 of its size: unique in exact
  // arithmetic, not to be trusted in doubles.
  const Facet f = onSphere(Vec3(0), 1e9, 1e-9);
  const QuadricFit fit = fitQuadric(f.p, f.n);
  EXPECT_TRUE(fit.status == QuadricFitStatus::IllConditioned ||
              fit.status == QuadricFitStatus::Singular)
      << toString(fit.status) << ", rank gap " << fit.rank_gap;
}

TEST(QuadricFit, VerdictDoesNotDependOnPlaceOrSize) {
  const Facet a = onSphere(Vec3(0), 1.0, 0.3);
  Facet b = a;
  for (auto& p : b.p) p = 1e-3 * p + Vec3(1e4, -2e4, 3e4);
  const QuadricFit fa = fitQuadric(a.p, a.n), fb = fitQuadric(b.p, b.n);
  EXPECT_EQ(fa.status, fb.status);
  EXPECT_NEAR(fa.rank_gap, fb.rank_gap, 1e-6 * fa.rank_gap);
}

TEST(QuadricFit, OpposedNormalsAreRefused) {
  Facet f = onSphere(Vec3(0), 1.0, 0.3);
  f.n[1] = -f.n[1];
  const QuadricFit fit = fitQuadric(f.p, f.n);
  EXPECT_NE(fit.status, QuadricFitStatus::Ok) << "rank gap " << fit.rank_gap;
}

TEST(QuadricFit, AFitWhoseNormalsNoConeBoundsIsRefused) {
  // Facets of a cylinder of radius 0.15 m with its exact normals: a short one is fitted; one
  // 0.6 m long is not, because over a ball that large the gradient of the fitted quadric (that
  // of the cylinder, up to the chord plane's z² term) may vanish by its Lipschitz bound
  // (2 L r ≥ |∇Q|): no normal cone could bound it, and observers would refine it blind.
  const double r = 0.15;
  auto on = [&](double phi, double z) {
    return std::pair{Vec3(r * std::cos(phi), r * std::sin(phi), z),
                     Vec3(std::cos(phi), std::sin(phi), 0.0)};
  };
  for (const auto& [length, expected] :
       {std::pair{0.05, QuadricFitStatus::Ok}, std::pair{0.6, QuadricFitStatus::Unbounded}}) {
    const auto [p0, n0] = on(0.0, 0.0);
    const auto [p1, n1] = on(0.3, 0.0);
    const auto [p2, n2] = on(0.15, length);
    const QuadricFit fit = fitQuadric({p0, p1, p2}, {n0, n1, n2});
    EXPECT_EQ(fit.status, expected) << "facet " << length << " m long: " << toString(fit.status);
  }
}

}  // namespace
}  // namespace glint
