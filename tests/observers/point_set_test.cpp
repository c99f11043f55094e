#include "observers/point_set.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include <algorithm>

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

// The 40 observers under 1, 2, 3 and 7 threads: 3 and 7 divide them unevenly, so chunks and
// workspaces fall differently, and each thread count must still give the same bits.
TEST(PointSet, ResultsAreIdenticalForAnyThreadCount) {
  const FacetIntegrator fi = cylinder();
  const auto points = arc();
  auto evaluate = [&](int threads) {
    // The global limit lets the arena have that many threads on a smaller machine; the arena
    // is what the work is split for.
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism,
                              static_cast<std::size_t>(threads));
    tbb::task_arena arena(threads);
    std::vector<ObserverResult> results;
    arena.execute([&] {
      EXPECT_EQ(tbb::this_task_arena::max_concurrency(), threads) << "premise: the split's width";
      results = evaluatePoints(fi, points, PointScheme{});
    });
    return results;
  };
  const std::vector<ObserverResult> one = evaluate(1);
  ASSERT_EQ(one.size(), points.size());
  const auto lit = std::count_if(one.begin(), one.end(),
                                 [](const ObserverResult& r) { return r.irradiance_w_m2 > 0.0; });
  ASSERT_GE(lit, 30) << "premise: most observers receive light (a 0 is 0 under any split)";
  for (int threads : {2, 3, 7}) {
    const std::vector<ObserverResult> many = evaluate(threads);
    ASSERT_EQ(many.size(), points.size()) << threads << " threads";
    for (std::size_t i = 0; i < points.size(); ++i) {
      EXPECT_EQ(one[i].irradiance_w_m2, many[i].irradiance_w_m2)
          << "observer " << i << ", " << threads << " threads against 1: bitwise";
      EXPECT_EQ(one[i].error_estimate_w_m2, many[i].error_estimate_w_m2)
          << "observer " << i << ", " << threads << " threads";
      EXPECT_EQ(one[i].evaluations, many[i].evaluations)
          << "observer " << i << ", " << threads << " threads";
    }
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
