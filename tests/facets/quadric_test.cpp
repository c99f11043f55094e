#include "facets/quadric.h"

#include <gtest/gtest.h>

#include <functional>

#include "facets/patch.h"
#include "facets/tessellate.h"

namespace glint {
namespace {

// Distance of x from the quadric surface to first order: |Q(x)| / |∇Q(x)|.
double distanceToSurface(const Quadric& q, const Vec3& x) {
  return std::abs(q.value(x)) / glm::length(q.gradient(x));
}

void forEachDescendant(const Target& t, const SubFacet& f, int levels,
                       const std::function<void(const SubFacet&)>& visit) {
  visit(f);
  if (levels == 0) return;
  for (const SubFacet& c : split(t, f)) forEachDescendant(t, c, levels - 1, visit);
}

TEST(Quadric, MatrixFormIsTheEquation) {
  const Quadric q = Quadric::cylinder(Vec3(0.3, -2, 1), glm::normalize(Vec3(1, 2, 3)), 0.7);
  const glm::dmat4 m = q.matrix();
  for (const Vec3& x : {Vec3(0, 0, 0), Vec3(1, -1, 2), Vec3(-3, 0.5, 4)}) {
    const glm::dvec4 p(x, 1.0);
    EXPECT_NEAR(glm::dot(p, m * p), q.value(x), 1e-12) << "PᵀQP at " << x.x << "," << x.y;
  }
}

TEST(Quadric, GradientIsTheOutwardNormal) {
  const Vec3 axis = glm::normalize(Vec3(0, 1, 1));
  const Quadric cyl = Quadric::cylinder(Vec3(0), axis, 2.0);
  const Vec3 radial = glm::normalize(Vec3(1, 1, -1));  // ⟂ axis
  const Vec3 on = 2.0 * radial + 5.0 * axis;
  EXPECT_NEAR(cyl.value(on), 0.0, 1e-12);
  EXPECT_NEAR(angleBetween(cyl.gradient(on), radial), 0.0, 1e-12);
  const Quadric sph = Quadric::sphere(Vec3(1, 2, 3), 4.0);
  EXPECT_NEAR(angleBetween(sph.gradient(Vec3(1, 2, 7)), Vec3(0, 0, 1)), 0.0, 1e-15);
  const Quadric pl = Quadric::plane(Vec3(0, 0, 1), Vec3(0, 0, 1));
  EXPECT_NEAR(angleBetween(pl.gradient(Vec3(5, 5, 1)), Vec3(0, 0, 1)), 0.0, 1e-15);
}

TEST(Quadric, GradientLipschitzIsTwiceTheSpectralNorm) {
  EXPECT_NEAR(Quadric::cylinder(Vec3(0), Vec3(0, 0, 1), 3.0).gradientLipschitz(), 2.0, 1e-14);
  EXPECT_NEAR(Quadric::sphere(Vec3(1), 3.0).gradientLipschitz(), 2.0, 1e-14);
  EXPECT_EQ(Quadric::plane(Vec3(0), Vec3(1, 0, 0)).gradientLipschitz(), 0.0);
}

TEST(Quadric, NearestRootHandlesPlanesTangentsAndMisses) {
  const Quadric pl = Quadric::plane(Vec3(0, 0, 2), Vec3(0, 0, 1));
  EXPECT_NEAR(*pl.nearestRoot(Vec3(0, 0, 0), Vec3(0, 0, 1)), 2.0, 1e-15);
  EXPECT_FALSE(pl.nearestRoot(Vec3(0, 0, 0), Vec3(1, 0, 0)).has_value()) << "parallel to plane";
  const Quadric sph = Quadric::sphere(Vec3(0), 1.0);
  EXPECT_NEAR(*sph.nearestRoot(Vec3(0.9, 0, 0), Vec3(1, 0, 0)), 0.1, 1e-15);
  EXPECT_NEAR(*sph.nearestRoot(Vec3(1.1, 0, 0), Vec3(1, 0, 0)), -0.1, 1e-15);
  EXPECT_FALSE(sph.nearestRoot(Vec3(0, 2, 0), Vec3(1, 0, 0)).has_value()) << "line misses";
}

TEST(Quadric, SubdivisionPointsLieOnTheSurface) {
  Target t;
  t.addMaterial({});
  const Vec3 ref = glm::normalize(Vec3(-1, 0.2, 0.1));
  addCylinder(t, {Vec3(1, 2, 3), glm::normalize(Vec3(0, 0.3, 1)), 0.5, 2.0}, 0, 12, ref);
  addSphere(t, {Vec3(-1, 0, 0), 0.7}, 0, 12, ref);
  addDisk(t, {Vec3(0, 0, 5), glm::normalize(Vec3(1, 1, 1)), 0.4}, 0, 12, ref);
  for (std::uint32_t i = 0; i < t.facetCount(); ++i) {
    const Quadric& q = t.quadrics[t.model_index[i]];
    const TargetObject& obj = t.objects[t.object[i]];
    forEachDescendant(t, coarseSubFacet(t, i), 4, [&](const SubFacet& f) {
      for (int k = 0; k < 3; ++k) {
        ASSERT_LT(distanceToSurface(q, f.corner_m[k]), 1e-13)
            << "facet " << i << " depth " << int(f.depth);
        // Corners on a rim edge lie on the true circle, not on the coarse polygon.
        if (obj.rim && (f.rim_edges >> k & 1u)) {
          ASSERT_NEAR(glm::length(f.corner_m[k] - obj.rim->centre_m), obj.rim->radius_m, 1e-13);
          ASSERT_NEAR(glm::length(f.corner_m[(k + 1) % 3] - obj.rim->centre_m), obj.rim->radius_m,
                      1e-13);
        }
      }
    });
  }
}

}  // namespace
}  // namespace glint
