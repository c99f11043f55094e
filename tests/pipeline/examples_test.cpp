// The shipped examples run, converge, and hold the accuracy the README promises.
#include <gtest/gtest.h>

#include <cmath>

#include "observers/point_set.h"
#include "pipeline/points_file.h"
#include "pipeline/scene.h"
#include "pipeline/target_builder.h"

namespace glint {
namespace {

std::string example(const std::string& name) {
  return std::string(GLINT_EXAMPLES_DIR) + "/" + name;
}

std::vector<ObserverResult> run(const std::string& scene_file, const std::string& points_file,
                                double tolerance_factor = 1.0) {
  const Scene scene = loadScene(example(scene_file));
  IntegratorOptions o = integratorOptions(scene);
  o.tolerance *= tolerance_factor;
  const FacetIntegrator fi(buildTarget(scene), beamOf(scene), o);
  return evaluatePoints(fi, loadPoints(example(points_file)), PointScheme{});
}

TEST(Examples, EveryExampleRunsAndConverges) {
  const std::vector<std::pair<std::string, std::string>> examples = {
      {"cylinder.json", "cylinder_186.csv"},
      {"cylinder_broad.json", "cylinder_186.csv"},
      {"sphere.json", "sphere_points.csv"},
      {"disk.json", "disk_points.csv"}};
  for (const auto& [scene, points] : examples) {
    const auto results = run(scene, points);
    std::size_t lit = 0;
    for (std::size_t i = 0; i < results.size(); ++i) {
      EXPECT_TRUE(results[i].converged) << scene << " observer " << i;
      EXPECT_TRUE(std::isfinite(results[i].irradiance_w_m2)) << scene << " observer " << i;
      lit += results[i].irradiance_w_m2 > 0.0 ? 1 : 0;
    }
    EXPECT_GT(lit, results.size() / 2) << scene << ": most observers see the glint";
  }
}

TEST(Examples, CylinderChangesLessThanATenthOfAPercentWhenTheToleranceIsHalved) {
  for (const char* scene : {"cylinder.json", "cylinder_broad.json"}) {
    const auto a = run(scene, "cylinder_186.csv");
    const auto b = run(scene, "cylinder_186.csv", 0.5);
    double worst = 0.0;
    for (std::size_t i = 0; i < a.size(); ++i) {
      const double scale = std::max(std::abs(b[i].irradiance_w_m2), 1e-9);
      worst = std::max(worst, std::abs(a[i].irradiance_w_m2 - b[i].irradiance_w_m2) / scale);
    }
    EXPECT_LT(worst, 1e-3) << scene;
  }
}

}  // namespace
}  // namespace glint
