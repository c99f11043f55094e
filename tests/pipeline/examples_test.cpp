// The shipped examples run, converge, and hold the accuracy the README promises.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "observers/point_set.h"
#include "pipeline/points_file.h"
#include "pipeline/scene.h"
#include "pipeline/target_builder.h"
#include "support/cli.h"

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

TEST(Examples, FinnedMissileOcclusionOnlyEverRemovesLight) {
  // The finned missile with and without occlusion rays, over the eye-level plane: the rays can
  // only take light away (within the integration tolerance), and here they do take some.
  const Scene scene = loadScene(example("finned_missile.json"));
  IntegratorOptions with = integratorOptions(scene);
  IntegratorOptions without = with;
  without.occlusion = false;
  const FacetIntegrator occluded(buildTarget(scene), beamOf(scene), with);
  const FacetIntegrator open(buildTarget(scene), beamOf(scene), without);
  EXPECT_TRUE(occluded.cullStats().occlusion);
  EXPECT_GT(occluded.cullStats().shadowed, 0u) << "the fins shadow the body";
  EXPECT_EQ(occluded.cullStats().lit + occluded.cullStats().shadowed, open.cullStats().lit);
  std::vector<Vec3> points;
  for (int i = 0; i < 16; ++i)
    for (int j = 0; j < 16; ++j) points.push_back({-15.0 + 2.0 * i, -15.0 + 2.0 * j, 1.7});
  const auto a = evaluatePoints(occluded, points, PointScheme{});
  const auto b = evaluatePoints(open, points, PointScheme{});
  std::size_t dimmed = 0;
  for (std::size_t k = 0; k < points.size(); ++k) {
    const double slack = 2.0 * with.tolerance * b[k].irradiance_w_m2 + 2.0 * with.floor_w_m2;
    EXPECT_LE(a[k].irradiance_w_m2, b[k].irradiance_w_m2 + slack)
        << "observer (" << points[k].x << ", " << points[k].y << ")";
    dimmed += a[k].irradiance_w_m2 < 0.99 * b[k].irradiance_w_m2 ? 1 : 0;
  }
  EXPECT_GT(dimmed, 0u) << "somewhere on the plane the fins must hide part of the body";
}

TEST(Examples, DefaultExampleShowsAHazardZoneInsideItsBoxWithoutWarning) {
  // The README's first command runs examples/cylinder.json at 0.1 m (minutes); the same scene
  // at 0.5 m voxels shows the same things in seconds: a hazard zone that ends inside the box,
  // and points on the shadow's edge lines (y = ±0.5 m, where the lit and the visible side meet
  // in a line) that do not converge but provably cannot be hazardous: a note, no warning.
  auto scene = nlohmann::json::parse(std::ifstream(example("cylinder.json")));
  scene["observers"]["voxel_m"] = 0.5;
  scene["observers"]["block_m"] = 2.0;
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "glint_default_example";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "cylinder.json") << scene.dump();
  const auto r = test::glint({"run", (dir / "cylinder.json").string(), "-o", (dir / "out").string()});
  ASSERT_EQ(r.status, 0) << r.err;
  const auto summary = nlohmann::json::parse(std::ifstream(dir / "out" / "summary.json"));
  const auto& hazard = summary["hazard"];
  const auto& zone = hazard["nominal_hazard_zone"];
  EXPECT_GT(hazard["peak_hazard_ratio"].get<double>(), 2.0) << hazard.dump();
  EXPECT_GT(zone["points"].get<int>(), 20) << zone.dump();
  EXPECT_FALSE(zone["reaches_box_edge"].get<bool>()) << zone.dump();
  const double reach = zone["farthest_from_target_m"].get<double>();
  EXPECT_GT(reach, 1.5) << "the backscattered fan reaches about 2.5 m";
  EXPECT_LT(reach, 3.0) << "and ends a metre inside the box's 4 m";
  ASSERT_TRUE(summary.contains("unconverged")) << "the premise: points on the shadow's edges";
  EXPECT_FALSE(summary["unconverged"]["may_be_hazardous"].get<bool>()) << summary["unconverged"];
  EXPECT_LT(summary["unconverged"]["max_hazard_ratio_plus_error"].get<double>(), 0.1);
  EXPECT_FALSE(hazard["unconverged_may_be_hazardous"].get<bool>());
  EXPECT_EQ(r.err.find("warning"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("so none of them can be hazardous"), std::string::npos) << r.err;
  std::filesystem::remove_all(dir);
}

TEST(Examples, FinnedMissileRunsThroughGlintRun) {
  const std::filesystem::path out =
      std::filesystem::temp_directory_path() / "glint_finned_missile_run";
  std::filesystem::remove_all(out);
  const auto r = test::glint({"run", std::string(GLINT_TEST_DATA_DIR) + "/finned_missile_coarse.json",
                              "-o", out.string(), "--quiet"});
  ASSERT_EQ(r.status, 0) << r.err;
  const auto summary = nlohmann::json::parse(std::ifstream(out / "summary.json"));
  EXPECT_TRUE(summary["target"]["occlusion_rays"].get<bool>());
  EXPECT_GT(summary["target"]["shadowed"].get<int>(), 0);
  const auto& mesh = summary["meshes"][0];
  EXPECT_EQ(mesh["triangles"].get<int>(), 2064) << mesh.dump();
  EXPECT_EQ(mesh["open_edges"].get<int>(), 0) << "the body and each fin are closed";
  EXPECT_GT(mesh["crease_edges"].get<int>(), 0) << "the tail disc, the nose joint and the fins";
  EXPECT_GT(summary["planes"][0]["peak_hazard_ratio"].get<double>(), 1.0);
  EXPECT_TRUE(std::filesystem::exists(out / "eye_level.exr"));
  std::filesystem::remove_all(out);
}

}  // namespace
}  // namespace glint
