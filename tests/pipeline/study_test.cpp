// Study files: expansion into scenarios, the pose and jitter they apply, and refusals.
#include "pipeline/input/study.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <set>
#include <string>

#include "pipeline/base/input_error.h"
#include "pipeline/input/scene.h"
#include "support/refusal.h"

namespace glint {
namespace {

// The batch tests' base scene: one vertical cylinder at the origin, material "polished".
const std::filesystem::path kDataDir = GLINT_TEST_DATA_DIR;

Study study(const std::string& body) {
  return parseStudy("{\"scene\": \"study_scene.json\"" + (body.empty() ? "" : ", " + body) + "}",
                    "study.json", kDataDir);
}

std::string refusal(const std::string& body) {
  return test::refusalOf([&] { study(body); });
}

// A scene of one mesh of examples/targets (@p glb) placed by @p transform (its JSON), lit from
// −y, with one small plane: what a study of a mesh needs.
void writeMeshScene(const std::string& path, const std::string& glb, const std::string& transform) {
  std::ofstream(path) << R"({
    "laser": {"position": [0, -100, 3], "direction": [0, 1, 0], "power_w": 1, "wavelength_nm": 532,
              "beam": {"profile": "flat_top", "radius_m": 1}},
    "materials": {"m": {"specular_reflectance": 0.5, "sigma": 0.1}},
    "objects": [{"shape": "mesh", "file": ")" GLINT_EXAMPLES_DIR R"(/targets/)"
                      << glb << R"(", "transform": )" << transform << R"(, "material": "m"}],
    "planes": [{"name": "p", "origin": [-5, -1, 0], "u_axis": [1, 0, 0], "v_axis": [0, 1, 0],
                "size_m": [1, 1], "pixel_m": 0.5}]})";
}

void expectNear(const Vec3& a, const Vec3& b, double tol, const std::string& what) {
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(a[i], b[i], tol) << what << " component " << i;
}

TEST(Study, WithoutSweepsIsTheBaseSceneOnce) {
  const Study s = study("");
  ASSERT_EQ(s.scenarios.size(), 1u);
  const Scene scene = scenarioScene(s, s.scenarios[0]);
  expectNear(scene.objects[0].centre_m(), s.base.objects[0].centre_m(), 0.0, "centre");
  expectNear(scene.laser.direction, s.base.laser.direction, 0.0, "laser direction");
  EXPECT_EQ(scene.materials[0].lobe.sigma, s.base.materials[0].lobe.sigma) << "σ as in the scene";
}

TEST(Study, SweepsMultiplyInNestedOrderWithJitterInnermost) {
  const Study s = study(
      R"("sweep": {"yaw_deg": [0, 10, 20], "sigma": {"from": 0.01, "to": 0.03, "count": 3}},
         "pointing_jitter": {"sigma_rad": 1e-3, "samples": 2})");
  ASSERT_EQ(s.scenarios.size(), 3u * 3u * 2u);
  for (std::size_t i = 0; i < s.scenarios.size(); ++i) {
    const Scenario& c = s.scenarios[i];
    EXPECT_EQ(c.index, i);
    EXPECT_EQ(c.jitter_sample, static_cast<int>(i % 2)) << "scenario " << i;
    ASSERT_TRUE(c.sigma.has_value());
    EXPECT_NEAR(*c.sigma, 0.01 + 0.01 * static_cast<double>((i / 2) % 3), 1e-15)
        << "scenario " << i;
    EXPECT_EQ(c.yaw_deg, 10.0 * static_cast<double>(i / 6)) << "scenario " << i;
  }
  // Common random numbers: sample k has the same pointing error for every other parameter.
  EXPECT_EQ(s.scenarios[0].jitter_u_rad, s.scenarios[16].jitter_u_rad);
  EXPECT_EQ(s.scenarios[1].jitter_v_rad, s.scenarios[17].jitter_v_rad);
  EXPECT_NE(s.scenarios[0].jitter_u_rad, s.scenarios[1].jitter_u_rad);
}

TEST(Study, TurnsTheTargetAboutThePivotYawThenPitch) {
  // Yaw 90° about z carries x to y; pitch 90° about y carries z to x (R = Rz Ry Rx).
  expectNear(rotateYawPitchRoll(Vec3(1, 0, 0), 90, 0, 0), Vec3(0, 1, 0), 1e-15, "yaw");
  expectNear(rotateYawPitchRoll(Vec3(0, 0, 1), 0, 90, 0), Vec3(1, 0, 0), 1e-15, "pitch");
  expectNear(rotateYawPitchRoll(Vec3(0, 1, 0), 0, 0, 90), Vec3(0, 0, 1), 1e-15, "roll");
  expectNear(rotateYawPitchRoll(Vec3(0, 0, 1), 90, 90, 0), Vec3(0, 1, 0), 1e-15,
             "pitch first, then yaw");

  const Study s = study(R"("pivot": [0, 0, -1], "sweep": {"pitch_deg": [90]})");
  const Scene scene = scenarioScene(s, s.scenarios[0]);
  // The centre (0, 0, 0) is 1 m above the pivot: the pitch swings it to (1, 0, -1).
  expectNear(scene.objects[0].centre_m(), Vec3(1, 0, -1), 1e-12, "centre");
  expectNear(*axisOf(*scene.objects[0].analytic()), Vec3(1, 0, 0), 1e-12, "axis");
}

TEST(Study, TurnsAMeshAboutThePivotWithItsOwnRotation) {
  // The finned missile (axis along the model's +x, turned 90° about x to stand its fins up) in
  // a study that yaws it 90°: its nose, 1.5 m along the model's +x, must point along +y.
  const std::string dir = ::testing::TempDir();
  writeMeshScene(dir + "/mesh_scene.json", "finned_missile.glb",
                 R"({"translation": [2, 0, 3], "yaw_pitch_roll_deg": [0, 0, 90]})");
  const Study s =
      parseStudy(R"({"scene": "mesh_scene.json", "pivot": [0, 0, 3], "sweep": {"yaw_deg": [90]}})",
                 "study.json", dir);
  const Scene scene = scenarioScene(s, s.scenarios[0]);
  ASSERT_TRUE(scene.objects[0].mesh());
  expectNear(scene.objects[0].centre_m(), Vec3(0, 2, 3), 1e-12, "the translation about the pivot");
  double nose_x = 0.0, nose_y = -1e9;
  for (const Vec3& p : scene.objects[0].mesh()->mesh->positions_m) {
    if (p.y > nose_y) nose_y = p.y, nose_x = p.x;
  }
  EXPECT_NEAR(nose_y, 1.5, 1e-6) << "the nose tip, turned from +x to +y";
  EXPECT_NEAR(nose_x, 0.0, 1e-6);
}

TEST(Study, ScenarioMadeInMemoryIsTheSceneItsFileDescribes) {
  // Every change a study makes, to every kind of object: the scene made from the base scene in
  // memory must be the scene its record scene.json parses to, to the last bit (so `glint run`
  // of that file repeats the scenario exactly), but for a turned mesh's vertices: turned once
  // more rather than with the product of the turns, they agree to rounding (a few ulps).
  const std::string dir = ::testing::TempDir();
  std::ofstream(dir + "/mixed_scene.json") << R"({
    "description": "four shapes",
    "laser": {"position": [0, -100, 3], "direction": [0, 1, 0.1], "power_w": 1,
              "wavelength_nm": 532, "beam": {"profile": "flat_top", "radius_m": 1}},
    "materials": {"m": {"specular_reflectance": 0.5, "sigma": 0.1},
                  "n": {"specular_reflectance": 0.3, "diffuse_reflectance": 0.1, "sigma": 0.2}},
    "objects": [{"shape": "mesh", "file": ")" GLINT_EXAMPLES_DIR R"(/targets/finned_missile.glb",
                 "transform": {"translation": [2, 0, 3], "yaw_pitch_roll_deg": [10, 0, 90],
                               "scale": [1, 1, 2]},
                 "crease_angle_deg": 40, "material": "m"},
                {"shape": "cylinder", "center": [0, 1, 2], "axis": [0, 0, 2], "radius": 0.3,
                 "length": 2, "material": "n"},
                {"shape": "disk", "center": [1, 1, 1], "normal": [1, 1, 0], "radius": 0.2,
                 "material": "m"},
                {"shape": "sphere", "center": [-1, 0, 4], "radius": 0.5, "material": "n"}],
    "planes": [{"name": "p", "origin": [-5, -1, 0], "u_axis": [1, 0, 0], "v_axis": [0, 1, 0],
                "size_m": [1, 1], "pixel_m": 0.5}]})";
  const Study s = parseStudy(
      R"({"scene": "mixed_scene.json", "sweep": {"yaw_deg": [0, 35], "pitch_deg": [-20],
          "sigma": [0.05], "specular_reflectance": [0.6], "material": "m"},
          "pointing_jitter": {"sigma_rad": 1e-3, "samples": 2, "seed": 3},
          "trajectory": {"poses": [{"time_s": 0, "offset_m": [0, 0, 0], "roll_deg": 0},
                                   {"time_s": 1, "offset_m": [3, -1, 2], "roll_deg": 15}]}})",
      "study.json", dir);
  ASSERT_EQ(s.scenarios.size(), 2u * 2u * 2u);
  const double tol = 1e-12;  // mesh vertices (metres, of order 1..10) and their normals
  for (const Scenario& c : s.scenarios) {
    const std::string what = "scenario " + std::to_string(c.index);
    const Scene memory = scenarioScene(s, c);
    const Scene file = parseScene(scenarioSceneJson(s, c), "scene.json", dir);
    EXPECT_EQ(memory.description, file.description) << what;
    expectNear(memory.laser.direction, file.laser.direction, 0.0, what + " laser");
    ASSERT_EQ(memory.materials.size(), file.materials.size());
    for (std::size_t m = 0; m < file.materials.size(); ++m) {
      EXPECT_EQ(memory.material_names[m], file.material_names[m]) << what;
      EXPECT_EQ(memory.materials[m].lobe.sigma, file.materials[m].lobe.sigma) << what;
      EXPECT_EQ(memory.materials[m].specular_reflectance, file.materials[m].specular_reflectance)
          << what;
      EXPECT_EQ(memory.materials[m].diffuse_reflectance, file.materials[m].diffuse_reflectance)
          << what;
    }
    ASSERT_EQ(memory.objects.size(), file.objects.size());
    for (std::size_t i = 0; i < file.objects.size(); ++i) {
      const ObjectSpec& a = memory.objects[i];
      const ObjectSpec& b = file.objects[i];
      const std::string obj = what + " object " + std::to_string(i);
      expectNear(a.centre_m(), b.centre_m(), 0.0, obj + " centre");
      if (!b.mesh()) {
        ASSERT_TRUE(a.analytic()) << obj;
        expectNear(axisOf(*a.analytic()).value_or(Vec3(0.0)),
                   axisOf(*b.analytic()).value_or(Vec3(0.0)), 0.0, obj + " axis");
        continue;
      }
      ASSERT_TRUE(a.mesh()) << obj;
      const TriangleMesh& ma = *a.mesh()->mesh;
      const TriangleMesh& mb = *b.mesh()->mesh;
      ASSERT_EQ(ma.positions_m.size(), mb.positions_m.size()) << obj;
      ASSERT_EQ(ma.triangles, mb.triangles) << obj << ": the same normals filled in";
      double worst_p = 0.0, worst_n = 0.0;
      for (std::size_t v = 0; v < mb.positions_m.size(); ++v) {
        worst_p = std::max(worst_p, glm::length(ma.positions_m[v] - mb.positions_m[v]));
        worst_n = std::max(worst_n, glm::length(ma.normals[v] - mb.normals[v]));
      }
      EXPECT_LT(worst_p, tol) << obj << " vertex positions";
      EXPECT_LT(worst_n, tol) << obj << " vertex normals";
    }
  }
}

TEST(Study, TrajectoryIsSampledEveryStepBetweenItsPoses) {
  const Study s = study(R"("trajectory": {"step_s": 0.5, "poses": [
      {"time_s": 0, "offset_m": [0, 0, 0], "yaw_deg": 0},
      {"time_s": 1, "offset_m": [2, 0, 0], "yaw_deg": 30},
      {"time_s": 2.25, "offset_m": [2, 5, 0], "yaw_deg": 30}]})");
  // t = 0, 0.5, 1, 1.5, 2 and the last pose at 2.25.
  ASSERT_EQ(s.scenarios.size(), 6u);
  const Scenario& half = s.scenarios[1];
  EXPECT_DOUBLE_EQ(half.pose.time_s, 0.5);
  expectNear(half.pose.offset_m, Vec3(1, 0, 0), 1e-15, "linear offset at 0.5 s");
  EXPECT_DOUBLE_EQ(half.pose.yaw_deg, 15.0);
  expectNear(s.scenarios[3].pose.offset_m, Vec3(2, 2, 0), 1e-12, "offset at 1.5 s");
  EXPECT_DOUBLE_EQ(s.scenarios[5].pose.time_s, 2.25);
  const Scene moved = scenarioScene(s, s.scenarios[3]);
  expectNear(moved.objects[0].centre_m(), Vec3(2, 2, 0), 1e-12, "the target moves with its pose");
}

TEST(Study, PointingJitterIsSeededGaussianAndReproducible) {
  const double sigma = 2e-3;
  const int n = 4000;
  const Study s = study(R"("pointing_jitter": {"sigma_rad": 2e-3, "samples": 4000, "seed": 11})");
  const Study again =
      study(R"("pointing_jitter": {"sigma_rad": 2e-3, "samples": 4000, "seed": 11})");
  const Study other =
      study(R"("pointing_jitter": {"sigma_rad": 2e-3, "samples": 4000, "seed": 12})");
  double sum = 0.0, sum2 = 0.0;
  int differ = 0;
  for (int k = 0; k < n; ++k) {
    const Scenario& c = s.scenarios[static_cast<std::size_t>(k)];
    EXPECT_EQ(c.jitter_u_rad, again.scenarios[static_cast<std::size_t>(k)].jitter_u_rad);
    differ += c.jitter_u_rad != other.scenarios[static_cast<std::size_t>(k)].jitter_u_rad ? 1 : 0;
    for (double a : {c.jitter_u_rad, c.jitter_v_rad}) {
      sum += a;
      sum2 += a * a;
    }
  }
  EXPECT_EQ(differ, n) << "another seed gives other samples";
  const double m = 2.0 * n;
  const double mean = sum / m, sd = std::sqrt(sum2 / m - mean * mean);
  // Five standard errors: σ/√m for the mean, σ/√(2m) for the standard deviation.
  EXPECT_NEAR(mean, 0.0, 5.0 * sigma / std::sqrt(m)) << "unbiased";
  EXPECT_NEAR(sd, sigma, 5.0 * sigma / std::sqrt(2.0 * m)) << "the requested spread";

  // The laser turns by the angle of the two jitter components.
  const Scenario& c = s.scenarios[3];
  const Scene scene = scenarioScene(s, c);
  const double expected = std::atan(std::hypot(std::tan(c.jitter_u_rad), std::tan(c.jitter_v_rad)));
  EXPECT_NEAR(angleBetween(scene.laser.direction, s.base.laser.direction), expected, 1e-12);
}

TEST(Study, MaterialSweepChangesOnlyTheNamedMaterial) {
  const Study s = study(R"("sweep": {"specular_reflectance": [0.5, 0.7], "material": "polished"})");
  ASSERT_EQ(s.scenarios.size(), 2u);
  EXPECT_DOUBLE_EQ(scenarioScene(s, s.scenarios[1]).materials[0].specular_reflectance, 0.7);
  EXPECT_NE(refusal(R"("sweep": {"sigma": [0.1], "material": "matte"})")
                .find("/sweep/material: the scene has no material \"matte\""),
            std::string::npos);
}

// A surface-state sweep puts each named material of the scene in the swept one's place, lobes,
// ABg and measured table with it; the scenario's scene.json stands on its own (the table named
// absolutely) and parses, from another folder, to the same material.
TEST(Study, ASurfaceStateSweepPutsEachNamedMaterialInTheSweptOnesPlace) {
  const std::filesystem::path dir = ::testing::TempDir() + "/surface_state";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  {
    std::ofstream csv(dir / "weathered.csv");
    csv << "theta_i_deg,theta_o_deg,delta_phi_deg,brdf_per_sr\n";
    for (int ti : {0, 90})
      for (int to : {0, 90})
        for (int p : {0, 180}) csv << ti << "," << to << "," << p << ",0.02\n";
  }
  std::ofstream(dir / "scene.json") << R"({
    "laser": {"position": [0, -100, 3], "direction": [0, 1, 0], "power_w": 1, "wavelength_nm": 532,
              "beam": {"profile": "flat_top", "radius_m": 1}},
    "materials": {"hull": {"specular_reflectance": 0.5, "sigma": 0.1},
                  "new": {"specular_reflectance": 0.9, "sigma": 0.005},
                  "weathered": {"lobes": [{"reflectance": 0.1, "sigma": 0.01},
                                          {"reflectance": 0.2, "sigma": 0.1}],
                                "abg": {"a_per_sr": 0.001, "b": 0.001, "g": 2},
                                "table": "weathered.csv", "diffuse_reflectance": 0.2}},
    "objects": [{"shape": "disk", "center": [0, 0, 3], "normal": [0, -1, 0], "radius": 0.2,
                 "material": "hull"}],
    "planes": [{"name": "p", "origin": [-5, -1, 0], "u_axis": [1, 0, 0], "v_axis": [0, 1, 0],
                "size_m": [1, 1], "pixel_m": 0.5}]})";
  const Study st = parseStudy(
      R"({"scene": "scene.json", "sweep": {"surface_state": ["new", "weathered"], "sigma": [0.02, 0.03], "material": "hull"}})",
      "study.json", dir);
  ASSERT_EQ(st.scenarios.size(), 4u) << "two states, each with two σ";
  const auto hull = [](const Scene& scene) {
    const auto& names = scene.material_names;
    return scene.materials.at(
        static_cast<std::size_t>(std::find(names.begin(), names.end(), "hull") - names.begin()));
  };
  const Scene first = scenarioScene(st, st.scenarios[0]);
  EXPECT_EQ(hull(first).specular_reflectance, 0.9) << "the state \"new\"";
  EXPECT_EQ(hull(first).lobe.sigma, 0.02) << "σ swept on top of the state";
  const Scene last = scenarioScene(st, st.scenarios[3]);
  const Material& m = hull(last);
  ASSERT_TRUE(m.abg.has_value() && m.table != nullptr) << "the state \"weathered\"";
  EXPECT_EQ(m.more_lobes.size(), 1u);
  EXPECT_EQ(m.lobe.sigma, 0.03);
  // Its scene.json, read from elsewhere, holds the same material.
  const Scene again = parseScene(scenarioSceneJson(st, st.scenarios[3]), "elsewhere/scene.json");
  const Material& a = hull(again);
  ASSERT_TRUE(a.abg.has_value() && a.table != nullptr);
  EXPECT_EQ(a.abg->b, m.abg->b);
  EXPECT_EQ(a.lobe.sigma, 0.03);
  EXPECT_EQ(a.table->brdf(0.3, 0.4, 1.0), m.table->brdf(0.3, 0.4, 1.0));
  EXPECT_NE(test::refusalOf([&] {
              parseStudy(R"({"scene": "scene.json", "sweep": {"surface_state": ["rusty"]}})",
                         "study.json", dir);
            }).find("/sweep/surface_state: each must name a material of the scene, not \"rusty\""),
            std::string::npos);
  std::filesystem::remove_all(dir);
}

TEST(Study, RefusesBadStudiesNamingThePlace) {
  const auto expectRefused = [](const std::string& body, const std::string& part) {
    const std::string message = refusal(body);
    EXPECT_NE(message.find(part), std::string::npos) << body << "\n gave: " << message;
  };
  expectRefused(R"("sweeps": {})", "study.json: /sweeps: unknown key");
  expectRefused(R"("sweep": {"yaw_deg": []})", "/sweep/yaw_deg: must hold at least one value");
  expectRefused(R"("sweep": {"yaw_deg": {"from": 0, "to": 1, "count": 0}})",
                "/sweep/yaw_deg/count: must be an integer in [1, 100000]");
  expectRefused(R"("sweep": {"sigma": [0.1, -1]})", "/sweep/sigma: values must be > 0");
  expectRefused(R"("pointing_jitter": {"sigma_rad": 1e-3})",
                "/pointing_jitter/samples: give either `samples` or a `precision` to stop at");
  expectRefused(R"("pointing_jitter": {"sigma_rad": 1e-3, "samples": 0})",
                "/pointing_jitter/samples: must be an integer in [1, 100000]");
  expectRefused(R"("pointing_jitter": {"sigma_rad": 1e-3, "samples": 8, "precision": 0.1})",
                "/pointing_jitter/samples: give either `samples` or a `precision` to stop at");
  expectRefused(R"("pointing_jitter": {"sigma_rad": 1e-3, "precision": 0.001})",
                "/pointing_jitter/precision: must be in [0.005, 0.5]");
  expectRefused(R"("trajectory": {"poses": [{"time_s": 1}, {"time_s": 1}]})",
                "/trajectory/poses: times must increase");
  expectRefused(R"("sweep": {"yaw_deg": {"from": 0, "to": 1, "count": 100000},
                             "pitch_deg": {"from": 0, "to": 1, "count": 100}})",
                "scenarios: at most 1 000 000");
  // A key said twice never silently means the second.
  EXPECT_NE(refusal(R"("sweep": {"specular_reflectance": [0.5, 1.0]}, "scene": "x")")
                .find("duplicate key"),
            std::string::npos);
  try {
    parseStudy(R"({"scene": "no_such_scene.json"})", "study.json", kDataDir);
    ADD_FAILURE() << "a missing scene was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("study.json: /scene:"), std::string::npos) << e.what();
  }
}

TEST(Study, ScenarioThatBreaksTheSceneIsRefusedByNumber) {
  // Diffuse 0.2 + specular 0.9 exceeds 1 only in the second scenario.
  const std::string dir = ::testing::TempDir();
  std::ofstream(dir + "/scene_diffuse.json") << R"({
    "laser": {"position": [-100, 0, 0], "direction": [1, 0, 0], "power_w": 1, "wavelength_nm": 532,
              "beam": {"profile": "flat_top", "radius_m": 1}},
    "materials": {"m": {"specular_reflectance": 0.5, "diffuse_reflectance": 0.2, "sigma": 0.1}},
    "objects": [{"shape": "sphere", "center": [0, 0, 0], "radius": 0.5, "material": "m"}],
    "planes": [{"name": "p", "origin": [-5, -1, 0], "u_axis": [1, 0, 0], "v_axis": [0, 1, 0],
                "size_m": [1, 1], "pixel_m": 0.5}]})";
  try {
    parseStudy(R"({"scene": "scene_diffuse.json", "sweep": {"specular_reflectance": [0.5, 0.9]}})",
               "study.json", dir);
    ADD_FAILURE() << "an invalid scenario was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("study.json scenario 1: /materials/m: "
                                         "specular_reflectance + diffuse_reflectance must be ≤ 1"),
              std::string::npos)
        << e.what();
  }
}

// A pose can carry an object beyond the coordinates the scene file allows: refused with the
// pointer of the key that file would have had (a shape's centre, a mesh's translation).
TEST(Study, ScenarioThatMovesAnObjectOutOfRangeIsRefusedAtItsKey) {
  EXPECT_EQ(
      refusal(
          R"("trajectory": {"poses": [{"time_s": 0}, {"time_s": 1, "offset_m": [2e7, 0, 0]}]})"),
      "study.json scenario 1: /objects/0/center: must lie within ±1e+07 m on every axis");
  const std::string dir = ::testing::TempDir();
  writeMeshScene(dir + "/far_mesh_scene.json", "capsule.glb", R"({"translation": [9.9e6, 0, 3]})");
  EXPECT_EQ(test::refusalOf([&] {
              parseStudy(R"({"scene": "far_mesh_scene.json", "pivot": [0, 0, 3],
                             "trajectory": {"poses": [{"time_s": 0, "offset_m": [2e5, 0, 0]}]}})",
                         "study.json", dir);
            }),
            "study.json scenario 0: /objects/0/transform/translation: must lie within ±1e+07 m on "
            "every axis")
      << "9.9e6 m + 2e5 m is beyond 1e7 m";
}

TEST(Study, ExampleStudyHasTwentyValidScenarios) {
  const Study s = loadStudy(std::string(GLINT_EXAMPLES_DIR) + "/cylinder_study.json");
  ASSERT_EQ(s.scenarios.size(), 20u) << "5 pitches × 4 jitter samples";
  std::set<double> pitches;
  for (const Scenario& c : s.scenarios) pitches.insert(c.pitch_deg);
  EXPECT_EQ(pitches, (std::set<double>{-6.0, -3.0, 0.0, 3.0, 6.0}));
  ASSERT_EQ(s.base.planes.size(), 1u);
  EXPECT_EQ(s.base.planes[0].name, "eye_level");
  // The pivot is the cylinder's centre, 3 m up: tipping it does not move it.
  expectNear(s.pivot_m, Vec3(0, 0, 3), 0.0, "pivot");
  expectNear(scenarioScene(s, s.scenarios[0]).objects[0].centre_m(), Vec3(0, 0, 3), 1e-12,
             "centre of a tipped cylinder");
}

}  // namespace
}  // namespace glint
