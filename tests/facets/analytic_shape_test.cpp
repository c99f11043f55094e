// Every analytic shape, tested by being one: the suite is typed over the alternatives of
// AnalyticShape, so a shape added there runs all of it, and does not compile until it has an
// example here and an exact parametrisation in support/brute_force.h. Each is checked for what
// the rest of glint takes from it: the facets it says it makes, corners on its quadric with
// the gradient as the outward normal, the pose that moves and turns it, where an observer is
// inside it, and the irradiance it reflects against the independent brute force.
#include <gtest/gtest.h>

#include <cmath>
#include <glm/gtc/quaternion.hpp>
#include <string>
#include <variant>

#include "facets/integrator.h"
#include "facets/tessellate.h"
#include "support/brute_force.h"
#include "support/scenes.h"

namespace glint {
namespace {

// One example of each shape, about the origin, 1 m across or so. The laser lies toward +x.
template <class S>
S example();
template <>
CylinderShape example() {
  return {Vec3(0.0), Vec3(0, 0, 1), 0.5, 2.0};
}
template <>
SphereShape example() {
  return {Vec3(0.0), 0.5};
}
template <>
DiskShape example() {
  return {Vec3(0.0), glm::normalize(Vec3(1, 0.3, 0.2)), 0.5};
}
template <>
ConeShape example() {
  return {Vec3(0.0), glm::normalize(Vec3(0.2, 0, 1)), 0.5, 0.2, 1.5};
}

// The shape's exact parametrisation; the sphere's pole is kept off the equator where its glints
// are looked for.
test::brute::Parametrisation exact(const CylinderShape& s) { return test::brute::cylinder(s); }
test::brute::Parametrisation exact(const SphereShape& s) {
  return test::brute::sphere(s, Vec3(0, 0, 1));
}
test::brute::Parametrisation exact(const DiskShape& s) { return test::brute::disk(s); }
test::brute::Parametrisation exact(const ConeShape& s) { return test::brute::cone(s); }

template <class V>
struct TypesOf;
template <class... S>
struct TypesOf<std::variant<S...>> {
  using type = ::testing::Types<S...>;
};

struct ShapeName {
  template <class S>
  static std::string GetName(int) {
    return S::kName;
  }
};

template <class S>
class AnalyticShapes : public ::testing::Test {};
TYPED_TEST_SUITE(AnalyticShapes, TypesOf<AnalyticShape>::type, ShapeName);

TYPED_TEST(AnalyticShapes, TessellationMakesTheFacetsItCounts) {
  const TypeParam shape = example<TypeParam>();
  for (int segments : {4, 7, 16, 64}) {
    Target target;
    const std::uint32_t m = target.addMaterial(test::mirror(0.9, 0.01));
    shape.addTo(target, m, segments, Vec3(1, 0, 0));
    EXPECT_EQ(static_cast<double>(target.facetCount()), shape.coarseFacets(segments))
        << TypeParam::kName << ", " << segments << " segments";
    EXPECT_EQ(target.objects.at(0).convex, TypeParam::kConvex) << TypeParam::kName;
  }
}

// The corners lie on the quadric each facet carries, and each facet winds counter-clockwise
// seen from the side its quadric's gradient points to: the side that reflects.
TYPED_TEST(AnalyticShapes, CornersLieOnTheQuadricAndFacetsFaceAlongItsGradient) {
  const TypeParam shape = example<TypeParam>();
  Target target;
  shape.addTo(target, target.addMaterial(test::mirror(0.9, 0.01)), 16, Vec3(1, 0, 0));
  for (std::size_t f = 0; f < target.facetCount(); ++f) {
    ASSERT_EQ(target.model[f], SurfaceModel::Quadric);
    const Quadric& q = target.quadrics.at(target.model_index[f]);
    const auto& c = target.corners_m[f];
    for (const Vec3& x : c) {
      // |Q| / |∇Q| is the distance to the surface to first order; corners are exact to rounding.
      const double g = glm::length(q.gradient(x));
      EXPECT_LE(std::abs(q.value(x)), 1e-12 * g + 1e-15)
          << TypeParam::kName << " facet " << f << ": a corner off its quadric";
    }
    const Vec3 centroid = (c[0] + c[1] + c[2]) / 3.0;
    const Vec3 winding = glm::cross(c[1] - c[0], c[2] - c[0]);
    EXPECT_GT(glm::dot(winding, q.gradient(centroid)), 0.0)
        << TypeParam::kName << " facet " << f << " faces against its quadric's gradient";
  }
}

TYPED_TEST(AnalyticShapes, APoseMovesItsCentreAndTurnsItsOrientation) {
  const TypeParam shape = example<TypeParam>();
  const glm::dquat turn = glm::angleAxis(0.7, glm::normalize(Vec3(1, -2, 0.5)));
  const Vec3 centre(3.0, -1.0, 2.0);
  const TypeParam moved = shape.placed(centre, turn);
  EXPECT_EQ(moved.centre_m, centre) << TypeParam::kName;
  EXPECT_EQ(moved.radius_m, shape.radius_m) << TypeParam::kName;
  ASSERT_EQ(moved.orientation().has_value(), shape.orientation().has_value()) << TypeParam::kName;
  ASSERT_EQ(TypeParam::kOrientationName != nullptr, shape.orientation().has_value())
      << TypeParam::kName << ": a turned direction needs its name in scene files";
  if (shape.orientation()) {
    const Vec3 expected = turn * *shape.orientation();
    EXPECT_NEAR(glm::length(*moved.orientation() - expected), 0.0, 1e-15) << TypeParam::kName;
    EXPECT_NEAR(glm::length(*moved.orientation()), 1.0, 1e-15) << TypeParam::kName;
  }
  // The free functions the scene and study use answer as the members do.
  const AnalyticShape any = moved;
  EXPECT_EQ(centreOf(any), centre);
  EXPECT_EQ(axisOf(any).has_value(), moved.orientation().has_value());
  EXPECT_EQ(std::string(nameOf(any)), TypeParam::kName);
}

TYPED_TEST(AnalyticShapes, AnObserverAtItsCentreIsInsideAndOneFarOffIsNot) {
  const TypeParam shape = example<TypeParam>();
  EXPECT_TRUE(shape.nearOrInside(shape.centre_m, 0.01)) << TypeParam::kName;
  EXPECT_FALSE(shape.nearOrInside(shape.centre_m + Vec3(10.0, 0.0, 0.0), 0.01)) << TypeParam::kName;
  // Every corner of the tessellation is within a hair of the shape.
  Target target;
  shape.addTo(target, target.addMaterial(test::mirror(0.9, 0.01)), 16, Vec3(1, 0, 0));
  for (std::size_t f = 0; f < target.facetCount(); ++f) {
    for (const Vec3& x : target.corners_m[f]) {
      EXPECT_TRUE(shape.nearOrInside(shape.centre_m + x, 1e-9)) << TypeParam::kName;
    }
  }
}

// At observers that see a glint of the shape (the mirror image of the laser in a lit normal,
// taken from the shape's exact parametrisation), and at one that sees only the glow of a
// Lambertian coat, the lobe scheme's converged answer is within its tolerance of the brute
// force. (A cone's glint cut by one of its ends is not among them: docs/scene.md says how
// closely its ends are followed.)
TYPED_TEST(AnalyticShapes, ItsIrradianceMatchesTheBruteForceReference) {
  const TypeParam shape = example<TypeParam>();
  constexpr double kTolerance = 1e-3, kFloor = 1e-6;
  Beam beam;
  beam.direction = Vec3(-1, 0, 0);
  beam.origin_m = Vec3(100, 0.05, -0.03);
  beam.power_w = 500.0;
  beam.profile = BeamProfile::FlatTop;
  beam.radius_m = 3.0;
  const test::brute::Parametrisation exact_shape = exact(shape);
  struct Case {
    Material material;
    Vec3 observer_m;
  };
  std::vector<Case> cases;
  for (double u : {0.35, 0.6}) {
    const double t = exact_shape.u0 + u * (exact_shape.u1 - exact_shape.u0);
    const auto [v0, v1] = exact_shape.v_range(t);
    // The point of this line most squarely lit: a glint's source.
    test::brute::SurfacePoint best = exact_shape.at(t, v0);
    for (int k = 0; k <= 64; ++k) {
      const test::brute::SurfacePoint p = exact_shape.at(t, v0 + (v1 - v0) * k / 64.0);
      if (glm::dot(p.normal, -beam.direction) > glm::dot(best.normal, -beam.direction)) best = p;
    }
    ASSERT_GT(glm::dot(best.normal, -beam.direction), 0.2) << TypeParam::kName;
    const Vec3 reflected =
        beam.direction - 2.0 * glm::dot(beam.direction, best.normal) * best.normal;
    cases.push_back({test::mirror(0.85, 0.05, 0.05), best.x_m + 3.0 * reflected});
  }
  cases.push_back({test::mirror(0.0, 0.05, 0.5), shape.centre_m + Vec3(2.0, 2.5, 1.0)});
  for (const Case& c : cases) {
    const FacetIntegrator integrator = test::singleObject(
        c.material, beam,
        [&](Target& t, std::uint32_t m, Vec3 toward) { shape.addTo(t, m, 16, toward); },
        test::accuracy(kTolerance, kFloor));
    const Vec3& o = c.observer_m;
    const test::brute::Estimate ref = test::brute::irradiance(exact_shape, beam, c.material, o);
    ASSERT_LE(ref.error, 0.01 * (kTolerance * ref.value + kFloor)) << TypeParam::kName;
    IntegratorWorkspace ws;
    const ObserverResult r = integrator.adaptive(o, ws);
    ASSERT_TRUE(r.converged) << TypeParam::kName;
    EXPECT_GT(ref.value, 0.0) << TypeParam::kName << ": the observer sees nothing";
    EXPECT_NEAR(r.irradiance_w_m2, ref.value, kTolerance * ref.value + kFloor + ref.error)
        << TypeParam::kName << " at (" << o.x << ", " << o.y << ", " << o.z << ")";
  }
}

}  // namespace
}  // namespace glint
