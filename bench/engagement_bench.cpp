// Time samples against error for an engagement (docs/engagement.md): the adaptive sampling of
// `glint points`, against uniform steps 100 times finer than its mean step (the reference), and
// the coarsest uniform steps (by doubling) that come within 1 % of that reference at every
// observer above 1 % of the brightest peak. Times are side by side in one run.
//
//   glint_engagement_bench SCENE.json POINTS.csv
#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <utility>

#include "observers/exposure.h"
#include "pipeline/input/points_file.h"
#include "pipeline/input/scene.h"
#include "pipeline/setup/target_builder.h"
#include "support/exposure_compare.h"

using namespace glint;
using test::exposureErrors;
using test::sampleCount;

namespace {

double secondsSince(const std::chrono::steady_clock::time_point& t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app("Adaptive time sampling against uniform steps");
  std::string scene_path, points_path;
  app.add_option("scene", scene_path)->required();
  app.add_option("points", points_path)->required();
  CLI11_PARSE(app, argc, argv);

  const Scene scene = loadScene(scene_path);
  if (!scene.engagement) {
    std::fprintf(stderr, "%s has no engagement\n", scene_path.c_str());
    return 2;
  }
  const std::vector<Vec3> points = loadPoints(points_path);
  const FacetIntegrator reference = buildIntegrator(scene, scene.accuracy);
  const Motion motion(scene.engagement->motion, scene.laser);

  auto t0 = std::chrono::steady_clock::now();
  const std::vector<ExposureHistory> adaptive =
      integrateExposures(reference, motion, points, scene.engagement->time);
  const double adaptive_s = secondsSince(t0);
  const std::size_t adaptive_n = sampleCount(adaptive);
  const double mean_step = motion.durationS() * static_cast<double>(points.size()) /
                           static_cast<double>(adaptive_n - points.size());
  const int fine_steps = static_cast<int>(std::ceil(100.0 * motion.durationS() / mean_step));
  t0 = std::chrono::steady_clock::now();
  const std::vector<ExposureHistory> fine = uniformExposures(reference, motion, points, fine_steps);
  const double fine_s = secondsSince(t0);
  const test::ExposureErrors e = exposureErrors(adaptive, fine);
  std::printf("%s, %zu observers over %g s\n", scene_path.c_str(), points.size(),
              motion.durationS());
  std::printf(
      "adaptive: %zu samples, %.2f s; against %d uniform steps (%zu samples, %.2f s): "
      "exposure within %.2e, peak within %.2e\n",
      adaptive_n, adaptive_s, fine_steps, sampleCount(fine), fine_s, e.exposure, e.peak);
  for (int steps = 64; steps <= fine_steps / 2; steps *= 2) {
    t0 = std::chrono::steady_clock::now();
    const std::vector<ExposureHistory> u = uniformExposures(reference, motion, points, steps);
    const double u_s = secondsSince(t0);
    const test::ExposureErrors ue = exposureErrors(u, fine);
    std::printf(
        "uniform %6d steps: %8zu samples (%.1f x adaptive), %.2f s (%.1f x): exposure "
        "within %.2e, peak within %.2e\n",
        steps, sampleCount(u),
        static_cast<double>(sampleCount(u)) / static_cast<double>(adaptive_n), u_s,
        u_s / adaptive_s, ue.exposure, ue.peak);
    if (ue.within(0.01)) break;
  }
  return 0;
}
