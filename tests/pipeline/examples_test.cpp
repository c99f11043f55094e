// The shipped examples run, converge, and hold the accuracy the README promises.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
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

TEST(Examples, RangeSceneIsAKilometreBoxWhoseSheetIsHazardousToAbout490Metres) {
  // examples/range_2km.json as its description says: at least 1e9 lattice points at 0.25 m or
  // finer, and, back along the beam, the sheet above the MPE at 470 m and below it at 505 m
  // (its radiant intensity, 1.19e7 W/sr, over the 50 W/m² MPE: sqrt(I / MPE) = 488 m).
  const Scene scene = loadScene(example("range_2km.json"));
  const FieldSpec spec = fieldSpec(scene);
  const auto n = spec.nodes();
  EXPECT_LE(spec.voxel_m, 0.25);
  EXPECT_GE(static_cast<double>(n[0]) * n[1] * n[2], 1e9) << n[0] << "×" << n[1] << "×" << n[2];
  const FacetIntegrator fi(buildTarget(scene), beamOf(scene), integratorOptions(scene));
  IntegratorWorkspace ws;
  const double mpe = scene.hazard.mpe_w_m2;
  ASSERT_NEAR(mpe, 50.0, 0.5) << "1064 nm, 10 s";
  const ObserverResult inside = fi.adaptive(Vec3(-470.0, 0.0, 0.0), ws);
  const ObserverResult outside = fi.adaptive(Vec3(-505.0, 0.0, 0.0), ws);
  EXPECT_GT(inside.irradiance_w_m2, mpe) << "470 m back along the beam";
  EXPECT_LT(outside.irradiance_w_m2, mpe) << "505 m back along the beam";
  EXPECT_TRUE(inside.converged && outside.converged);
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

// The README's first command runs examples/cylinder.json at 0.1 m (minutes); the same scene
// at 0.5 m voxels shows the same things in seconds. `edit` changes the scene before the run.
struct CoarseRun {
  test::Outcome run;
  nlohmann::json summary;
};
CoarseRun runCoarseDefaultExample(const std::string& name,
                                  const std::function<void(nlohmann::json&)>& edit = {}) {
  auto scene = nlohmann::json::parse(std::ifstream(example("cylinder.json")));
  scene["observers"]["voxel_m"] = 0.5;
  scene["observers"]["block_m"] = 2.0;
  if (edit) edit(scene);
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "cylinder.json") << scene.dump();
  CoarseRun r;
  r.run = test::glint({"run", (dir / "cylinder.json").string(), "-o", (dir / "out").string()});
  if (r.run.status == 0)
    r.summary = nlohmann::json::parse(std::ifstream(dir / "out" / "summary.json"));
  std::filesystem::remove_all(dir);
  return r;
}

TEST(Examples, DefaultExampleShowsAHazardZoneInsideItsBoxWithoutWarning) {
  // A hazard zone that ends inside the box, and every point converged: those on the shadow's
  // edge lines (y = ±0.5 m, where the lit and the visible side meet in a line) too, since no
  // piece that cannot both see the laser and be seen is kept there.
  const CoarseRun r = runCoarseDefaultExample("glint_default_example");
  ASSERT_EQ(r.run.status, 0) << r.run.err;
  const auto& hazard = r.summary["hazard"];
  const auto& zone = hazard["nominal_hazard_zone"];
  EXPECT_GT(hazard["peak_hazard_ratio"].get<double>(), 2.0) << hazard.dump();
  EXPECT_GT(zone["points"].get<int>(), 20) << zone.dump();
  EXPECT_FALSE(zone["reaches_box_edge"].get<bool>()) << zone.dump();
  const double reach = zone["farthest_from_target_m"].get<double>();
  EXPECT_GT(reach, 1.5) << "the backscattered fan reaches about 2.5 m";
  EXPECT_LT(reach, 3.0) << "and ends a metre inside the box's 4 m";
  EXPECT_FALSE(r.summary.contains("unconverged")) << r.summary["unconverged"];
  EXPECT_FALSE(hazard["unconverged_may_be_hazardous"].get<bool>());
  EXPECT_EQ(r.run.err.find("warning"), std::string::npos) << r.run.err;
  EXPECT_EQ(r.run.err.find("note:"), std::string::npos) << r.run.err;
}

TEST(Examples, UnconvergedPointsWarnOnlyWhereTheirBoundReachesTheMpe) {
  // 100 evaluations per observer leave many points short of their tolerance. Each is judged
  // by its irradiance plus its error estimate: at the example's 6 kW the bound passes the MPE
  // (a warning: they may be hazardous); at 60 mW, 1e-5 of it, the same bounds are 1e-5 as
  // large and the run can say that none of them is hazardous (a note).
  for (const double power_w : {6000.0, 0.06}) {
    const CoarseRun r =
        runCoarseDefaultExample("glint_unconverged_example", [&](nlohmann::json& scene) {
          scene["laser"]["power_w"] = power_w;
          scene["accuracy"]["max_evaluations"] = 100;
        });
    ASSERT_EQ(r.run.status, 0) << r.run.err;
    ASSERT_TRUE(r.summary.contains("unconverged")) << "the premise, at " << power_w << " W";
    const bool may = power_w > 1.0;
    const double upper = r.summary["unconverged"]["max_hazard_ratio_plus_error"].get<double>();
    EXPECT_EQ(r.summary["unconverged"]["may_be_hazardous"].get<bool>(), may) << upper;
    EXPECT_EQ(r.summary["hazard"]["unconverged_may_be_hazardous"].get<bool>(), may);
    EXPECT_EQ(upper >= 1.0, may) << power_w << " W";
    EXPECT_EQ(r.run.err.find("warning: ") != std::string::npos, may) << r.run.err;
    EXPECT_EQ(r.run.err.find("so none of them can be hazardous") != std::string::npos, !may)
        << r.run.err;
  }
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
