// Occlusion: an L-shaped target whose shadow and hidden parts can be worked out by hand, and
// the promise that a target never shadows itself where nothing is in the way.
#include <gtest/gtest.h>

#include <cmath>

#include "facets/integrator.h"
#include "facets/occluder.h"
#include "facets/tessellate.h"

namespace glint {
namespace {

// Adds the quad a, b, c, d (counter-clockwise from its reflecting side) as two triangles.
void addQuad(TriangleMesh& m, const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  const auto base = static_cast<std::uint32_t>(m.positions_m.size());
  const Vec3 n = glm::normalize(glm::cross(b - a, c - a));
  for (const Vec3& p : {a, b, c, d}) {
    m.positions_m.push_back(p);
    m.normals.push_back(n);
  }
  m.triangles.push_back({base, base + 1, base + 2});
  m.triangles.push_back({base, base + 2, base + 3});
}

// The L: a floor in z = 0 over x in [0, 2], y in [-1, 1] (facing +z), in 0.5 m × 1 m cells,
// and a wall of height 1 m at x = 1 facing −x, toward the laser. With `skip_shadowed`, the
// floor cells behind the wall (x > 1) are left out.
TriangleMesh lShape(bool skip_shadowed) {
  TriangleMesh m;
  for (int i = 0; i < 4; ++i) {
    const double x0 = 0.5 * i, x1 = x0 + 0.5;
    if (skip_shadowed && x0 >= 1.0) continue;
    for (double y0 : {-1.0, 0.0}) {
      addQuad(m, {x0, y0, 0.0}, {x1, y0, 0.0}, {x1, y0 + 1.0, 0.0}, {x0, y0 + 1.0, 0.0});
    }
  }
  addQuad(m, {1.0, -1.0, 0.0}, {1.0, -1.0, 1.0}, {1.0, 1.0, 1.0}, {1.0, 1.0, 0.0});
  return m;
}

Target targetOf(const TriangleMesh& mesh) {
  Target t;
  t.addMaterial({0.9, 0.0, Beckmann{0.3}});  // a broad lobe: light reaches every observer
  addMesh(t, Vec3(0.0), 0, mesh, MeshSurface::Flat);
  return t;
}

// Down at 45° from the −x side: the wall's shadow covers the floor from x = 1 to x = 2.
Beam laser() {
  Beam b;
  b.origin_m = Vec3(-50.0, 0.0, 50.0);
  b.direction = glm::normalize(Vec3(1.0, 0.0, -1.0));
  b.power_w = 100.0;
  b.profile = BeamProfile::FlatTop;
  b.radius_m = 10.0;
  return b;
}

IntegratorOptions options(bool occlusion) {
  IntegratorOptions o;
  o.occlusion = occlusion;
  return o;
}

TEST(Occlusion, TheWallShadowsTheFloorBehindIt) {
  const FacetIntegrator it(targetOf(lShape(false)), laser(), options(true));
  const CullStats& c = it.cullStats();
  EXPECT_TRUE(c.occlusion) << "an L is not convex: rays must be traced";
  // Floor cells at x in [1, 2]: 4 cells, 8 triangles, all behind the 1 m wall under 45°.
  EXPECT_EQ(c.shadowed, 8u) << "lit " << c.lit << ", facing away " << c.facing_away;
  EXPECT_EQ(c.lit, 8u + 2u) << "the floor in front of the wall and the wall itself";
}

TEST(Occlusion, LitFacetsEqualTheTargetWithoutItsShadowedPart) {
  // From above on the laser's side every lit facet is in view: the full L with occlusion must
  // give what the L without the shadowed cells gives with no rays at all, term by term.
  const FacetIntegrator with_rays(targetOf(lShape(false)), laser(), options(true));
  const FacetIntegrator by_hand(targetOf(lShape(true)), laser(), options(false));
  IntegratorWorkspace ws;
  for (const Vec3& observer :
       {Vec3(-10.0, 0.0, 10.0), Vec3(-6.0, 4.0, 3.0), Vec3(-3.0, -5.0, 8.0)}) {
    const double e = with_rays.uniform(observer, 2, ws).irradiance_w_m2;
    const double expected = by_hand.uniform(observer, 2, ws).irradiance_w_m2;
    ASSERT_GT(expected, 0.0);
    EXPECT_NEAR(e, expected, 1e-12 * expected) << "observer " << observer.x << ", " << observer.z;
  }
}

TEST(Occlusion, TheWallHidesTheLitFloorFromBehind) {
  // At (11, 0, 10) the lit floor (x < 1) is seen only through the wall (every segment crosses
  // x = 1 below z = 0.75), the shadowed floor is dark and the wall faces away: nothing.
  const Vec3 observer(11.0, 0.0, 10.0);
  IntegratorWorkspace ws;
  const FacetIntegrator with_rays(targetOf(lShape(false)), laser(), options(true));
  const FacetIntegrator without(targetOf(lShape(false)), laser(), options(false));
  EXPECT_EQ(with_rays.uniform(observer, 2, ws).irradiance_w_m2, 0.0);
  EXPECT_EQ(with_rays.adaptive(observer, ws).irradiance_w_m2, 0.0);
  EXPECT_GT(without.uniform(observer, 2, ws).irradiance_w_m2, 0.0)
      << "without rays the floor's light would be counted";
}

TEST(Occlusion, CurvedFacetsNeverShadowThemselves) {
  // Two objects, so rays are traced, far apart, lit from the side and seen from where neither
  // is in the other's way: every ray must come back clear, so the result is the same bits.
  Target t;
  t.addMaterial({0.9, 0.0, Beckmann{0.05}});
  const Vec3 toward_laser(0.0, -1.0, 0.0);
  addSphere(t, {{-20.0, 0.0, 0.0}, 1.0}, 0, 16, toward_laser);
  addCylinder(t, {{20.0, 0.0, 0.0}, glm::normalize(Vec3(0.3, 0.2, 1.0)), 0.5, 3.0}, 0, 16,
              toward_laser);
  Beam b;
  b.origin_m = Vec3(0.0, -100.0, 0.0);
  b.direction = Vec3(0.0, 1.0, 0.0);
  b.power_w = 100.0;
  b.profile = BeamProfile::FlatTop;
  b.radius_m = 30.0;
  const FacetIntegrator with_rays(t, b, options(true));
  const FacetIntegrator without(t, b, options(false));
  EXPECT_TRUE(with_rays.cullStats().occlusion);
  EXPECT_EQ(with_rays.cullStats().shadowed, 0u);
  EXPECT_EQ(with_rays.cullStats().lit, without.cullStats().lit);
  IntegratorWorkspace ws;
  for (const Vec3& observer :
       {Vec3(-20.0, -30.0, 2.0), Vec3(20.0, -30.0, -3.0), Vec3(0.0, -40.0, 0.0)}) {
    EXPECT_EQ(with_rays.adaptive(observer, ws).irradiance_w_m2,
              without.adaptive(observer, ws).irradiance_w_m2)
        << "observer " << observer.x << ", " << observer.y << ", " << observer.z;
  }
}

TEST(Occlusion, ASingleConvexShapeTracesNoRays) {
  Target t;
  t.addMaterial({0.9, 0.0, Beckmann{0.05}});
  addSphere(t, {Vec3(0.0), 1.0}, 0, 16, Vec3(0.0, -1.0, 0.0));
  EXPECT_FALSE(needsOcclusion(t));
  addDisk(t, {Vec3(5.0, 0.0, 0.0), Vec3(0.0, -1.0, 0.0), 1.0}, 0, 16, Vec3(0.0, -1.0, 0.0));
  EXPECT_TRUE(needsOcclusion(t)) << "two objects can shadow each other";
}

TEST(Occluder, SegmentsThroughAPlateAreBlockedAndBesideItClear) {
  Target t;
  t.addMaterial({0.9, 0.0, Beckmann{0.05}});
  TriangleMesh plate;
  addQuad(plate, {-1.0, -1.0, 0.0}, {1.0, -1.0, 0.0}, {1.0, 1.0, 0.0}, {-1.0, 1.0, 0.0});
  addMesh(t, Vec3(100.0, 200.0, 300.0), 0, plate, MeshSurface::Flat);
  const Occluder occluder(t);
  const Vec3 o(100.0, 200.0, 300.0);
  EXPECT_FALSE(occluder.segmentClear(o + Vec3(0.2, 0.3, -1.0), o + Vec3(-0.1, 0.2, 1.0)));
  EXPECT_TRUE(occluder.segmentClear(o + Vec3(1.2, 0.3, -1.0), o + Vec3(1.1, 0.2, 1.0)));
  EXPECT_TRUE(occluder.segmentClear(o + Vec3(0.2, 0.3, 0.5), o + Vec3(-0.1, 0.2, 1.0)))
      << "a segment that ends before the plate";
  EXPECT_LT(occluder.lift_m(0), 1e-5) << "a flat facet is lifted by float rounding only";
}

}  // namespace
}  // namespace glint
