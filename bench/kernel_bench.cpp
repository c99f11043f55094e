// Kernel throughput (Google Benchmark): reflection calculations per second, single-threaded for
// the kernel itself and the per-observer integration, then over all observers of the paper's
// cylinder on 1 and 2 threads (and as many as asked) to show how it scales.
//
//   glint_kernel_bench [--benchmark_format=csv] [--benchmark_out=kernel.csv ...]
#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include <vector>

#include "facets/reflection.h"
#include "observers/point_set.h"
#include "pipeline/input/points_file.h"
#include "pipeline/input/scene.h"
#include "pipeline/setup/target_builder.h"

namespace glint {
namespace {

const Scene& paperCylinder() {
  static const Scene scene = loadScene(GLINT_EXAMPLES_DIR "/cylinder.json");
  return scene;
}

// Every lit facet of the paper's cylinder split to `level`: what the uniform twin evaluates.
std::vector<PatchGeometry> subFacets(const FacetIntegrator& fi, int level) {
  std::vector<SubFacet> facets;
  for (const Candidate& c : fi.candidates()) facets.push_back(c.facet);
  for (int l = 0; l < level; ++l) {
    std::vector<SubFacet> next;
    for (const SubFacet& f : facets)
      for (const SubFacet& child : split(fi.target(), f)) next.push_back(child);
    facets = std::move(next);
  }
  std::vector<PatchGeometry> out;
  for (const SubFacet& f : facets)
    out.push_back(patchGeometry(fi.target(), f, NormalModel::Surface));
  return out;
}

// Reflection calculations per second, in all and per thread. Every benchmark reports both:
// Google Benchmark's CSV wants the same columns in every row.
void reportRate(benchmark::State& state, double reflections, std::size_t threads) {
  state.counters["reflections_per_s"] =
      benchmark::Counter(reflections, benchmark::Counter::kIsRate);
  state.counters["reflections_per_s_per_thread"] =
      benchmark::Counter(reflections / static_cast<double>(threads), benchmark::Counter::kIsRate);
}

// One reflection calculation (Eq. 1 with clipping at the terminator), one thread.
void ReflectionKernel(benchmark::State& state) {
  const Scene& scene = paperCylinder();
  const FacetIntegrator fi(buildTarget(scene), scene.laser, scene.accuracy);
  const std::vector<PatchGeometry> patches = subFacets(fi, 4);
  const Material& material = fi.target().materials.front();
  const Vec3 observer(-10.0 * std::cos(1.0), 10.0 * std::sin(1.0), 0.3);
  for (auto _ : state) {
    double sum = 0.0;
    for (const PatchGeometry& g : patches) sum += facetIrradiance(g, observer, fi.beam(), material);
    benchmark::DoNotOptimize(sum);
  }
  reportRate(state, static_cast<double>(state.iterations() * patches.size()), 1);
}
BENCHMARK(ReflectionKernel)->Unit(benchmark::kMillisecond);

// The adaptive integration of one observer (bounds, priority queue, kernel), one thread.
void AdaptiveObserver(benchmark::State& state) {
  const Scene& scene = paperCylinder();
  const FacetIntegrator fi(buildTarget(scene), scene.laser, scene.accuracy);
  IntegratorWorkspace ws;
  const Vec3 observer(-10.0 * std::cos(1.0), 10.0 * std::sin(1.0), 0.3);
  std::int64_t evaluations = 0;
  for (auto _ : state) {
    const ObserverResult r = fi.adaptive(observer, ws);
    evaluations += r.evaluations;
    benchmark::DoNotOptimize(r.irradiance_w_m2);
  }
  reportRate(state, static_cast<double>(evaluations), 1);
}
BENCHMARK(AdaptiveObserver)->Unit(benchmark::kMillisecond);

// The finned missile (examples/finned_missile.json) over a row of its eye-level observers, one
// thread, with occlusion rays (argument 1) and without (0): the cost of the rays, net of the
// facets they hide.
void FinnedMissileObservers(benchmark::State& state) {
  static const Scene scene = loadScene(GLINT_EXAMPLES_DIR "/finned_missile.json");
  IntegratorOptions options = scene.accuracy;
  options.occlusion = state.range(0) != 0;
  const FacetIntegrator fi(buildTarget(scene), scene.laser, options);
  IntegratorWorkspace ws;
  std::int64_t evaluations = 0;
  for (auto _ : state) {
    double sum = 0.0;
    for (int i = 0; i < 16; ++i) {
      const ObserverResult r = fi.adaptive(Vec3(-8.0 + i, -6.0, 1.7), ws);
      evaluations += r.evaluations;
      sum += r.irradiance_w_m2;
    }
    benchmark::DoNotOptimize(sum);
  }
  reportRate(state, static_cast<double>(evaluations), 1);
}
BENCHMARK(FinnedMissileObservers)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// The paper's 186 observers on `threads` threads: reflections per second in all and per core.
void ObserversOnThreads(benchmark::State& state) {
  const auto threads = static_cast<std::size_t>(state.range(0));
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
  const Scene& scene = paperCylinder();
  const FacetIntegrator fi(buildTarget(scene), scene.laser, scene.accuracy);
  const std::vector<Vec3> points = loadPoints(GLINT_EXAMPLES_DIR "/cylinder_186.csv");
  std::int64_t evaluations = 0;
  for (auto _ : state) {
    for (const ObserverResult& r : evaluatePoints(fi, points, PointScheme{}))
      evaluations += r.evaluations;
  }
  reportRate(state, static_cast<double>(evaluations), threads);
}
BENCHMARK(ObserversOnThreads)
    ->Arg(1)
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MeasureProcessCPUTime();

}  // namespace
}  // namespace glint

BENCHMARK_MAIN();
