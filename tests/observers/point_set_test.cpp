#include "observers/point_set.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include "support/scenes.h"

namespace glint {
namespace {

FacetIntegrator cylinder() {
  const Beam beam = test::flatTop(Vec3(0), Vec3(1, 0, 0), 100.0, 2.0);
  return test::singleObject(
      test::mirror(0.9, 0.01, 0.05), beam,
      [](Target& t, std::uint32_t m, Vec3 ref) {
        addCylinder(t, {Vec3(0), Vec3(0, 0, 1), 0.5, 2.0}, m, 16, ref);
      },
      test::accuracy(1e-3));
}

std::vector<Vec3> arc() {
  std::vector<Vec3> p;
  for (int k = 0; k < 40; ++k)
    p.push_back(Vec3(-4 * std::cos(0.08 * k), 4 * std::sin(0.08 * k), 0.2));
  return p;
}

TEST(PointSet, ResultsAreIdenticalForAnyThreadCount) {
  const FacetIntegrator fi = cylinder();
  const auto points = arc();
  std::vector<ObserverResult> one, two;
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
    one = evaluatePoints(fi, points, PointScheme{});
  }
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
    two = evaluatePoints(fi, points, PointScheme{});
  }
  ASSERT_EQ(one.size(), points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    EXPECT_EQ(one[i].irradiance_w_m2, two[i].irradiance_w_m2) << "observer " << i << " bitwise";
    EXPECT_EQ(one[i].evaluations, two[i].evaluations) << "observer " << i;
  }
}

TEST(PointSet, MatchesTheIntegratorPointByPointAndCountsProgress) {
  const FacetIntegrator fi = cylinder();
  const auto points = arc();
  WorkCounter counter;
  const auto results = evaluatePoints(fi, points, PointScheme{}, &counter);
  IntegratorWorkspace ws;
  std::int64_t total = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const ObserverResult r = fi.adaptive(points[i], ws);
    EXPECT_EQ(results[i].irradiance_w_m2, r.irradiance_w_m2) << "observer " << i;
    total += r.evaluations;
  }
  EXPECT_EQ(counter.items_done.load(), points.size());
  EXPECT_EQ(counter.evaluations.load(), total);
}

}  // namespace
}  // namespace glint
