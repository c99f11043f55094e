#include "pipeline/input/scene.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "pipeline/base/input_error.h"
#include "pipeline/base/memory_budget.h"
#include "pipeline/report/run_report.h"
#include "pipeline/setup/target_builder.h"
#include "support/cli.h"
#include "support/files.h"
#include "support/refusal.h"

namespace glint {
namespace {

using nlohmann::json;

// The minimal scene of docs/physics.md.
json minimal() {
  return json::parse(R"({
    "laser": {"position": [-100, 0, 0], "direction": [1, 0, 0], "power_w": 1000.0,
              "wavelength_nm": 1064, "exposure_s": 0.25,
              "beam": {"profile": "flat_top", "radius_m": 2.0}},
    "materials": {"polished": {"specular_reflectance": 0.9, "sigma": 0.003,
                               "diffuse_reflectance": 0.0}},
    "objects": [{"shape": "cylinder", "center": [0, 0, 0], "axis": [0, 0, 1],
                 "radius": 0.5, "length": 2.0, "material": "polished"}]
  })");
}

// The message parseScene refuses `scene` with.
std::string refusal(const std::string& text) {
  return test::refusalOf([&] { parseScene(text, "scene.json"); });
}
std::string refusal(const json& scene) { return refusal(scene.dump()); }

TEST(Scene, MinimalSceneLoadsWithDefaults) {
  json j = minimal();
  j["laser"].erase("exposure_s");
  j["materials"]["polished"].erase("diffuse_reflectance");
  const Scene s = parseScene(j.dump(), "scene.json");
  EXPECT_TRUE(s.hazard.exposure_default);
  EXPECT_EQ(s.materials.at(0).diffuse_reflectance, 0.0);
  EXPECT_EQ(s.laser.divergence_rad, 0.0);
  EXPECT_EQ(s.objects.at(0).segments, 16);
  EXPECT_EQ(s.accuracy.tolerance, 1e-3);
  EXPECT_EQ(s.accuracy.normals, NormalModel::Surface);
  // The floor defaults to 1e-9 of the beam's peak irradiance P / (π a²).
  EXPECT_NEAR(s.accuracy.floor_w_m2, 1e-9 * 1000.0 / (kPi * 4.0), 1e-20);
}

TEST(Scene, AMaterialOfSeveralLobesListsThemInOrder) {
  json j = minimal();
  j["materials"]["polished"] = {
      {"lobes", {{{"reflectance", 0.5}, {"sigma", 0.01}}, {{"reflectance", 0.3}, {"sigma", 0.1}}}},
      {"diffuse_reflectance", 0.05}};
  const Scene s = parseScene(j.dump(), "scene.json");
  const Material& m = s.materials.at(0);
  EXPECT_EQ(m.specular_reflectance, 0.5) << "the first lobe is the material's own";
  EXPECT_EQ(m.lobe.sigma, 0.01);
  ASSERT_EQ(m.more_lobes.size(), 1u);
  EXPECT_EQ(m.more_lobes[0].reflectance, 0.3);
  EXPECT_EQ(m.more_lobes[0].shape.sigma, 0.1);
  EXPECT_EQ(m.diffuse_reflectance, 0.05);
  // summary.json names the model.
  const nlohmann::json summary = materialsJson(s);
  EXPECT_EQ(summary.at("polished").at("model"), "2 Beckmann lobes + Lambertian") << summary;
  EXPECT_EQ(summary.at("polished").at("lobes").at(1).at("sigma"), 0.1) << summary;
  j = minimal();
  EXPECT_EQ(materialsJson(parseScene(j.dump(), "scene.json")).at("polished").at("model"),
            "Beckmann lobe");
}

// ABg and a measured table beside two lobes: each read, the table from a CSV beside the scene
// (rows in any order, comments skipped), and summary.json naming the model and its figures.
TEST(Scene, AMaterialTakesAbgScatterAndAMeasuredTable) {
  const std::filesystem::path dir = test::freshTestFolder("scene_table");
  {
    std::ofstream csv(dir / "paint.csv");
    csv << "# a flat table: f = 0.05/sr everywhere\n"
           "theta_i_deg, theta_o_deg, delta_phi_deg, brdf_per_sr\n";
    for (double p : {180.0, 0.0})
      for (double to = 0.0; to <= 90.0; to += 15.0)
        for (double ti = 0.0; ti <= 90.0; ti += 15.0)
          csv << ti << "," << to << "," << p << ",0.05\n";
  }
  json j = minimal();
  j["materials"]["paint"] = {
      {"lobes", {{{"reflectance", 0.05}, {"sigma", 0.01}}, {{"reflectance", 0.1}, {"sigma", 0.1}}}},
      {"abg", {{"a_per_sr", 0.002}, {"b", 1e-3}, {"g", 2.0}}},
      {"table", "paint.csv"},
      {"diffuse_reflectance", 0.3}};
  const Scene s = parseScene(j.dump(), (dir / "scene.json").string());
  const std::size_t paint_at = static_cast<std::size_t>(
      std::find(s.material_names.begin(), s.material_names.end(), "paint") -
      s.material_names.begin());
  const Material& m = s.materials.at(paint_at);
  ASSERT_TRUE(m.abg.has_value());
  EXPECT_EQ(m.abg->b, 1e-3);
  ASSERT_NE(m.table, nullptr);
  EXPECT_NEAR(m.table->brdf(30 * kPi / 180, 60 * kPi / 180, 1.0), 0.05, 1e-12) << "at a node";
  EXPECT_EQ(m.terms().size(), 4u) << "the first lobe with the floor, the haze, ABg, the table";
  const nlohmann::json summary = materialsJson(s);
  const nlohmann::json& paint = summary.at("paint");
  EXPECT_EQ(paint.at("model"), "2 Beckmann lobes + ABg + measured table + Lambertian") << paint;
  // TIS = π A ln(1 + 1/B); a constant f reflects π f at every incidence, to the monotone
  // cubic's error on cos θi cos θo between nodes 15° apart (its slopes are first order: ~h²/8
  // of the curvature, 2e-3 here).
  EXPECT_NEAR(paint.at("abg").at("total_integrated_scatter").get<double>(),
              kPi * 0.002 * std::log1p(1e3), 1e-9);
  EXPECT_NEAR(paint.at("table").at("max_hemispherical_reflectance").get<double>(), kPi * 0.05,
              5e-3 * kPi * 0.05);
  EXPECT_EQ(s.material_table_files.at(paint_at), dir / "paint.csv");
  std::filesystem::remove_all(dir);
}

// tests/data/abg_disk_table.csv (f = 0.05/sr on 5° steps) with one more θi node @p extra_deg,
// written with the disk scene that reads it into @p dir.
std::filesystem::path tableDiskWithExtraNode(const std::filesystem::path& dir, double extra_deg) {
  std::ifstream given(std::string(GLINT_TEST_DATA_DIR) + "/abg_disk_table.csv");
  std::ofstream csv(dir / "table.csv");
  csv << given.rdbuf();
  csv.precision(12);
  for (int to = 0; to <= 90; to += 5)
    for (int p = 0; p <= 180; p += 30) csv << extra_deg << "," << to << "," << p << ",0.05\n";
  json scene = json::parse(std::ifstream(std::string(GLINT_TEST_DATA_DIR) + "/table_disk.json"));
  scene["materials"]["measured"]["table"] = "table.csv";
  std::ofstream(dir / "scene.json") << scene.dump();
  return dir / "scene.json";
}

// A node a hair from another (a θi of 10.001° beside 10°) once made the table's light look
// 9e-6 rad wide: the integrator split a disk's facets on their bounds until it ran out of
// pieces, before a single evaluation, and glint points wrote 0 W/m² where the truth is twice the
// MPE. Such a table is refused, naming both nodes and their lines; 0.05° apart is integrated.
TEST(BrdfTableFile, NodesCloserThanItCanResolveAreRefusedWithTheirLines) {
  const std::filesystem::path dir = test::freshTestFolder("table_close_nodes");
  for (const double extra : {10.001, 10.00001, 10.0000000001}) {
    const std::filesystem::path scene = tableDiskWithExtraNode(dir, extra);
    const std::string message = test::refusalOf([&] { loadScene(scene); });
    EXPECT_NE(message.find("table.csv: line 2530: theta_i_deg "), std::string::npos) << message;
    EXPECT_NE(message.find("from 10° (line "), std::string::npos) << message;
    EXPECT_NE(message.find("closer than the 0.05° a table may resolve"), std::string::npos)
        << message;
  }
  std::filesystem::remove_all(dir);
}

// Along the disk's normal the table reflects I = E A f cos θi (E = P / (π a²), A the disk's
// area): 253.4 W/sr, twice the 50 W/m² MPE at 1.58 m. With a node 0.05° from another, glint
// points integrates it (to its 1 %) and converges.
TEST(BrdfTableFile, ANodeAtTheFinestStepIsIntegratedToTheClosedForm) {
  const std::filesystem::path dir = test::freshTestFolder("table_fine_node");
  const std::filesystem::path scene = tableDiskWithExtraNode(dir, 10.05);
  const Vec3 n = glm::normalize(Vec3(-1.0, 0.6, 0.4));
  std::ofstream(dir / "points.csv") << "x,y,z\n"
                                    << 1.58 * n.x << "," << 1.58 * n.y << "," << 1.58 * n.z << "\n";
  const test::Outcome o =
      test::glint({"points", scene.string(), "--points", (dir / "points.csv").string(), "--out",
                   (dir / "out.csv").string()});
  ASSERT_EQ(o.status, 0) << o.err;
  std::ifstream out(dir / "out.csv");
  std::string header, row;
  std::getline(out, header);
  std::getline(out, row);
  std::vector<double> v;
  std::stringstream cells(row);
  for (std::string cell; std::getline(cells, cell, ',');) v.push_back(std::stod(cell));
  ASSERT_GE(v.size(), 8u) << header;
  const double cos_i = glm::dot(n, Vec3(-1.0, 0.0, 0.0));  // toward the laser
  const double intensity_w_sr = 1e5 / (kPi * 0.04) * kPi * 0.0025 * 0.05 * cos_i;
  const double expected_w_m2 = intensity_w_sr / (1.58 * 1.58);
  EXPECT_NEAR(v[3], expected_w_m2, 1.5e-2 * expected_w_m2) << row;
  EXPECT_EQ(v[6], 1.0) << "converged: " << row;
  EXPECT_GT(v[5], 0.0) << "evaluated: " << row;
  std::filesystem::remove_all(dir);
}

// A table's text, rows and grid are counted against --memory before each is made (an 11.8 M
// node table under 200 MB once peaked at 1.73 GB), and what is not a regular file, whose size
// says nothing (a device, a pipe), is refused before it is opened (/dev/zero once read 1.09 GB).
TEST(BrdfTableFile, ItIsCountedAgainstTheMemoryBudgetAndMustBeARegularFile) {
  const std::filesystem::path dir = test::freshTestFolder("table_budget");
  {
    std::ofstream csv(dir / "fine.csv");
    csv << "theta_i_deg,theta_o_deg,delta_phi_deg,brdf_per_sr\n";
    for (int i = 0; i <= 180; ++i)
      for (int o = 0; o <= 180; ++o)
        for (int p = 0; p <= 180; p += 30)
          csv << 0.5 * i << "," << 0.5 * o << "," << p << ",0.05\n";
  }
  const auto scene = [&](const std::string& table) {
    json j = minimal();
    j["materials"]["polished"] = {{"table", table}};
    std::ofstream(dir / "scene.json") << j.dump();
    return dir / "scene.json";
  };
  const std::uint64_t held = residentBytes();
  const std::string refused =
      test::refusalOf([&] { loadScene(scene("fine.csv"), held + (std::uint64_t{4} << 20)); });
  EXPECT_NE(refused.find("/materials/polished/table: "), std::string::npos) << refused;
  EXPECT_NE(refused.find("the BRDF table "), std::string::npos) << refused;
  EXPECT_NE(refused.find("(--memory); resample the table coarser, or raise --memory"),
            std::string::npos)
      << refused;
  EXPECT_NO_THROW(loadScene(scene("fine.csv"), held + (std::uint64_t{1} << 30)))
      << "a budget that holds it reads it";

  ASSERT_EQ(mkfifo((dir / "pipe.csv").c_str(), 0600), 0) << "a FIFO in the test's own folder";
  const std::string pipe = test::refusalOf([&] { loadScene(scene("pipe.csv"), 0); });
  EXPECT_NE(pipe.find("pipe.csv: is not a regular file; a BRDF table must be one"),
            std::string::npos)
      << pipe;
  std::filesystem::remove_all(dir);
}

TEST(Scene, FlatNormalsWithoutASchemeSelectThePaperScheme) {
  json j = minimal();
  j["accuracy"] = {{"normals", "flat"}};
  EXPECT_EQ(parseScene(j.dump(), "scene.json").accuracy.scheme, IntegrationScheme::Paper)
      << "flat facets are the paper scheme's model: asking for them asks for that scheme";
  j["accuracy"] = {{"normals", "flat"}, {"scheme", "paper"}};
  EXPECT_EQ(parseScene(j.dump(), "scene.json").accuracy.normals, NormalModel::Flat);
}

TEST(Scene, DirectionsAreNormalised) {
  json j = minimal();
  j["laser"]["direction"] = {3, 0, 4};
  j["objects"][0]["axis"] = {0, 0, 7};
  const Scene s = parseScene(j.dump(), "scene.json");
  EXPECT_NEAR(s.laser.direction.x, 0.6, 1e-15);
  EXPECT_NEAR(s.laser.direction.z, 0.8, 1e-15);
  EXPECT_NEAR(axisOf(*s.objects[0].analytic())->z, 1.0, 1e-15);
}

// A cone is read by its name with its own keys, and one whose radii are equal (a cylinder, whose
// apex lies at infinity) is refused naming the key.
TEST(Scene, AConeIsReadByItsNameAndEqualRadiiAreRefused) {
  json j = minimal();
  j["objects"][0] = {{"shape", "cone"},     {"material", j["objects"][0]["material"]},
                     {"center", {0, 0, 1}}, {"axis", {0, 0, 2}},
                     {"radius", 0.4},       {"top_radius", 0.1},
                     {"length", 1.2}};
  const Scene s = parseScene(j.dump(), "scene.json");
  const auto* cone = std::get_if<ConeShape>(s.objects[0].analytic());
  ASSERT_NE(cone, nullptr) << "shape \"cone\" reads as a ConeShape";
  EXPECT_EQ(cone->centre_m, Vec3(0, 0, 1));
  EXPECT_NEAR(cone->axis.z, 1.0, 1e-15);
  EXPECT_EQ(cone->radius_m, 0.4);
  EXPECT_EQ(cone->top_radius_m, 0.1);
  EXPECT_EQ(cone->length_m, 1.2);
  j["objects"][0]["top_radius"] = 0.4;
  const std::string refusal = test::refusalOf([&] { parseScene(j.dump(), "scene.json"); });
  EXPECT_NE(refusal.find("/objects/0/top_radius"), std::string::npos) << refusal;
}

TEST(Scene, DirectionsOfAnyRepresentableLengthAreNormalised) {
  // |v|² of the first overflows a double and of the second underflows to 0; both are still
  // directions, and the laser's must not be refused as zero-length.
  json j = minimal();
  j["laser"]["direction"] = {1e300, 1e300, 0};
  j["objects"][0]["axis"] = {0, 1e-310, 1e-310};
  const Scene s = parseScene(j.dump(), "scene.json");
  EXPECT_NEAR(s.laser.direction.x, std::sqrt(0.5), 1e-15) << "(1e300, 1e300, 0) → (1, 1, 0)/√2";
  EXPECT_NEAR(s.laser.direction.y, std::sqrt(0.5), 1e-15);
  const Vec3 axis = *axisOf(*s.objects[0].analytic());
  EXPECT_NEAR(axis.y, std::sqrt(0.5), 1e-15) << "subnormal components";
  EXPECT_NEAR(axis.z, std::sqrt(0.5), 1e-15);
}

TEST(Scene, RefusesEachInvalidInputNamingFileAndPath) {
  struct Case {
    std::function<void(json&)> edit;
    std::string message;
  };
  const std::vector<Case> cases = {
      {[](json& j) { j["laser"]["colour"] = "green"; },
       "scene.json: /laser/colour: unknown key (expected one of: position, direction, power_w, "
       "wavelength_nm, exposure_s, pulse, beam)"},
      {[](json& j) { j["extra"] = 1; },
       "scene.json: /extra: unknown key (expected one of: description, hazard, laser, "
       "atmosphere, optical_aid, materials, objects, accuracy, observers, planes, far_field, "
       "reach, engagement, site, terrain)"},
      {[](json& j) {
         j["engagement"] = {{"start_s", 0}, {"end_s", 1}};
       },
       "scene.json: /engagement/target: missing (required)"},
      {[](json& j) {
         j["engagement"] = {{"target", {{"velocity_m_s", {1, 0, 0}}}}};
       },
       "scene.json: /engagement/target: a constant velocity needs the engagement's start_s and "
       "end_s"},
      {[](json& j) {
         j["engagement"] = {{"start_s", 0},
                            {"end_s", 1},
                            {"target", {{"velocity_m_s", {1, 0, 0}}, {"poses", json::array()}}}};
       },
       "scene.json: /engagement/target: needs either `poses` or `velocity_m_s` (with, optionally, "
       "`turn_deg_s`)"},
      {[](json& j) {
         j["engagement"] = {{"target", {{"poses", {{{"time_s", 1}}, {{"time_s", 1}}}}}}};
       },
       "scene.json: /engagement/target/poses: times must increase from pose to pose (pose 1)"},
      {[](json& j) {
         j["engagement"] = {
             {"start_s", 0}, {"end_s", 0}, {"target", {{"velocity_m_s", {1, 0, 0}}}}};
       },
       "scene.json: /engagement/end_s: must follow start_s by 1e-9 to 30000 s"},
      {[](json& j) {
         j["engagement"] = {{"start_s", 0},
                            {"end_s", 1},
                            {"target", {{"velocity_m_s", {1, 0, 0}}}},
                            {"laser",
                             {{"pointing", "keyed"},
                              {"directions",
                               {{{"time_s", 0}, {"direction", {1, 0, 0}}},
                                {{"time_s", 1}, {"direction", {-1, 1, 0}}}}}}}};
       },
       "scene.json: /engagement/laser/directions: consecutive directions must be at most 90 "
       "degrees apart (key 1)"},
      {[](json& j) {
         j["engagement"] = {{"start_s", 0},
                            {"end_s", 1},
                            {"target", {{"velocity_m_s", {1, 0, 0}}}},
                            {"time", {{"initial_intervals", 0}}}};
       },
       "scene.json: /engagement/time/initial_intervals: must be from 1 to 4096"},
      {[](json& j) { j["laser"].erase("power_w"); },
       "scene.json: /laser/power_w: missing (required)"},
      // Issue 67: a required key misspelt was reported as missing, the misspelling unnamed.
      {[](json& j) {
         j["laser"]["wavelenght_nm"] = j["laser"]["wavelength_nm"];
         j["laser"].erase("wavelength_nm");
       },
       "scene.json: /laser/wavelength_nm: missing (required); \"wavelenght_nm\" is given: a "
       "misspelling of \"wavelength_nm\"?"},
      {[](json& j) {
         j["far_field"] = {{"face_pixels", 1000}};
       },
       "scene.json: /far_field/face_pixels: must be a power of two from 16 to 8192"},
      {[](json& j) {
         j["far_field"] = {{"tolerance", 1.0}};
       },
       "scene.json: /far_field/tolerance: must be in (0, 1)"},
      {[](json& j) {
         j["far_field"] = {{"enabled", 1}};
       },
       "scene.json: /far_field/enabled: must be true or false"},
      {[](json& j) {
         j["far_field"] = {{"floor_w_sr", -1.0}};
       },
       "scene.json: /far_field/floor_w_sr: must be > 0"},
      {[](json& j) { j.erase("objects"); }, "scene.json: /objects: missing (required)"},
      {[](json& j) { j["laser"]["power_w"] = "1000"; },
       "scene.json: /laser/power_w: must be a number"},
      {[](json& j) {
         j["laser"]["position"] = {1, 2};
       },
       "scene.json: /laser/position: must be an array of 3 numbers"},
      {[](json& j) { j["laser"]["power_w"] = 0.0; }, "scene.json: /laser/power_w: must be > 0"},
      {[](json& j) { j["laser"]["power_w"] = -5.0; }, "scene.json: /laser/power_w: must be > 0"},
      {[](json& j) { j["materials"]["polished"]["sigma"] = 0.0; },
       "scene.json: /materials/polished/sigma: must be > 0"},
      {[](json& j) { j["materials"]["polished"]["specular_reflectance"] = 1.2; },
       "scene.json: /materials/polished/specular_reflectance: must be in [0, 1]"},
      {[](json& j) { j["materials"]["polished"]["diffuse_reflectance"] = -0.1; },
       "scene.json: /materials/polished/diffuse_reflectance: must be in [0, 1]"},
      {[](json& j) { j["materials"]["polished"]["diffuse_reflectance"] = 0.2; },
       "scene.json: /materials/polished: specular_reflectance + diffuse_reflectance must be ≤ 1"},
      {[](json& j) {
         j["laser"]["direction"] = {0, 0, 0};
       },
       "scene.json: /laser/direction: must not be zero-length (all three components are 0)"},
      {[](json& j) {
         j["objects"][0]["axis"] = {0, 0, 0};
       },
       "scene.json: /objects/0/axis: must not be zero-length (all three components are 0)"},
      {[](json& j) { j["objects"][0]["material"] = "chrome"; },
       "scene.json: /objects/0/material: no material named \"chrome\" (defined: \"polished\")"},
      {[](json& j) { j["objects"][0]["shape"] = "torus"; },
       "scene.json: /objects/0/shape: must be one of: cylinder, sphere, disk, cone, mesh"},
      {[](json& j) { j["objects"][0]["shape"] = "mesh"; },
       "scene.json: /objects/0/file: missing (required)"},
      {[](json& j) { j["objects"][0]["segments"] = 2; },
       "scene.json: /objects/0/segments: must be an integer in [3, 4096]"},
      {[](json& j) { j["objects"][0]["segments"] = 16.5; },
       "scene.json: /objects/0/segments: must be an integer"},
      {[](json& j) { j["objects"] = json::array(); },
       "scene.json: /objects: must be a non-empty array of objects"},
      {[](json& j) { j["laser"]["beam"]["profile"] = "tophat"; },
       "scene.json: /laser/beam/profile: must be one of: flat_top, gaussian"},
      {[](json& j) {
         j["laser"]["beam"] = {{"profile", "gaussian"}, {"radius_m", 1.0}};
       },
       "scene.json: /laser/beam/w_m: missing (required)"},
      {[](json& j) { j["laser"]["beam"]["divergence_rad"] = -0.001; },
       "scene.json: /laser/beam/divergence_rad: must be in [0, π)"},
      {[](json& j) {
         j["accuracy"] = {{"tolerance", 0.0}};
       },
       "scene.json: /accuracy/tolerance: must be in (0, 1)"},
      {[](json& j) {
         j["accuracy"] = {{"normals", "smooth"}};
       },
       "scene.json: /accuracy/normals: must be one of: surface, flat"},
      {[](json& j) {
         j["accuracy"] = {{"normals", "flat"}, {"scheme", "lobe"}};
       },
       "scene.json: /accuracy/scheme: flat normals (normals: flat) are the paper scheme's only"},
      {[](json& j) { j["materials"] = json::object(); },
       "scene.json: /materials: must define at least one material"},
      {[](json& j) {
         j["materials"]["polished"]["lobes"] = {{{"reflectance", 0.5}, {"sigma", 0.01}}};
       },
       "scene.json: /materials/polished/specular_reflectance: give the lobes either in `lobes` "
       "or as specular_reflectance and sigma"},
      {[](json& j) {
         j["materials"]["polished"] = {
             {"lobes", {{{"reflectance", 0.5}, {"sigma", 0.01}}, {{"reflectance", 0.3}}}}};
       },
       "scene.json: /materials/polished/lobes/1/sigma: missing (required)"},
      {[](json& j) {
         j["materials"]["polished"] = {{"lobes", json::array()}};
       },
       "scene.json: /materials/polished/lobes: must be a list of 1 to 8 lobes"},
      {[](json& j) {
         j["materials"]["polished"] = {
             {"lobes",
              {{{"reflectance", 0.5}, {"sigma", 0.01}}, {{"reflectance", 0.4}, {"sigma", -0.1}}}}};
       },
       "scene.json: /materials/polished/lobes/1/sigma: must be > 0"},
      {[](json& j) {
         j["materials"]["polished"] = {
             {"lobes",
              {{{"reflectance", 0.6}, {"sigma", 0.01}}, {{"reflectance", 0.35}, {"sigma", 0.1}}}},
             {"diffuse_reflectance", 0.1}};
       },
       "scene.json: /materials/polished: the lobes' reflectances + diffuse_reflectance must be ≤ 1 "
       "(energy conservation), not 1.05"},
      {[](json& j) {
         j["materials"]["polished"]["abg"] = {{"a_per_sr", 0.2}, {"b", 1e-3}, {"g", 2.0}};
       },
       "scene.json: /materials/polished: specular_reflectance + ABg's total integrated scatter "
       "(4.341) + diffuse_reflectance must be ≤ 1 (energy conservation), not 5.2409"},
      {[](json& j) {
         j["materials"]["polished"]["abg"] = {{"a_per_sr", 0.001}, {"b", 1e-3}, {"g", 5.0}};
       },
       "scene.json: /materials/polished/abg/g: must be in (0, 4]"},
      {[](json& j) { j["materials"]["polished"]["table"] = "no_such_table.csv"; },
       "scene.json: /materials/polished/table: no_such_table.csv: cannot open the BRDF table"},
      {[](json& j) { j["laser"]["wavelength_nm"] = 355.0; },
       "scene.json: /laser/wavelength_nm: must be in 400 nm to 1 mm, the range of the MPE table"},
      {[](json& j) { j["laser"]["exposure_s"] = 1e5; },
       "scene.json: /laser/exposure_s: must be in 1e-9 s to 3e4 s, the range of the MPE table"},
  };
  for (const Case& c : cases) {
    json j = minimal();
    c.edit(j);
    const std::string message = refusal(j);
    EXPECT_EQ(message.rfind(c.message, 0), 0u)
        << "got:      " << message << "\nexpected: " << c.message;
  }
}

TEST(Scene, RefusesNonFiniteNumbers) {
  // JSON has no NaN or Infinity; a number too large for a double is how a non-finite value
  // arrives.
  std::string text = minimal().dump();
  text.replace(text.find("1000.0"), 6, "1e999");
  EXPECT_EQ(refusal(text), "scene.json: /laser/power_w: must be finite");
  std::string in_array = minimal().dump();
  in_array.replace(in_array.find("[-100,0,0]"), 10, "[-100,0,-1e400]");
  EXPECT_EQ(refusal(in_array), "scene.json: /laser/position/2: must be finite");
}

// pipeline/base/limits.h: values past what double arithmetic carries from beam to summed
// irradiance are refused at the boundary; a finite but huge power once ran to a clean
// "no hazard" (the beam irradiance overflowed to infinity and every bound to NaN).
TEST(Scene, RefusesValuesWhosePhysicsWouldOverflow) {
  struct Case {
    std::function<void(json&)> edit;
    std::string message;
  };
  const std::vector<Case> cases = {
      {[](json& j) { j["laser"]["power_w"] = 1.7e308; },
       "scene.json: /laser/power_w: must be in [0, 1e+15] W"},
      {[](json& j) { j["laser"]["power_w"] = 2e15; },
       "scene.json: /laser/power_w: must be in [0, 1e+15] W"},
      {[](json& j) { j["laser"]["beam"]["radius_m"] = 1e-9; },
       "scene.json: /laser/beam/radius_m: must be in [1e-06, 100000] m"},
      {[](json& j) { j["materials"]["polished"]["sigma"] = 1e-9; },
       "scene.json: /materials/polished/sigma: must be in [1e-06, 1e+06]"},
      {[](json& j) { j["objects"][0]["radius"] = 1e300; },
       "scene.json: /objects/0/radius: must be in [1e-06, 100000] m"},
      {[](json& j) { j["objects"][0]["length"] = 1e-300; },
       "scene.json: /objects/0/length: must be in [1e-06, 100000] m"},
      {[](json& j) {
         j["objects"][0]["center"] = {0, 2e7, 0};
       },
       "scene.json: /objects/0/center: must lie within ±1e+07 m on every axis"},
      {[](json& j) {
         j["laser"]["position"] = {-1e300, 0, 0};
       },
       "scene.json: /laser/position: must lie within ±1e+07 m on every axis"},
      {[](json& j) {
         j["observers"] = {{"min", {-1e8, 0, 0}}, {"max", {1, 1, 1}}, {"voxel_m", 0.1}};
       },
       "scene.json: /observers/min: must lie within ±1e+07 m on every axis"},
      {[](json& j) {
         j["observers"] = {{"min", {0, 0, 0}}, {"max", {1, 1, 1}}, {"voxel_m", 1e-7}};
       },
       "scene.json: /observers/voxel_m: must be in [1e-06, 100000] m"},
  };
  for (const Case& c : cases) {
    json j = minimal();
    c.edit(j);
    EXPECT_EQ(refusal(j), c.message);
  }
  // The limits themselves are accepted: a 1 PW laser on a 1 µm-smooth target is a scene.
  json edge = minimal();
  edge["laser"]["power_w"] = 1e15;
  edge["materials"]["polished"]["sigma"] = 1e-6;
  EXPECT_NO_THROW(parseScene(edge.dump(), "scene.json"));
}

TEST(Scene, RefusesDuplicateKeys) {
  const std::string text = R"({"laser": {"position": [0,0,0], "power_w": 1, "power_w": 2}})";
  EXPECT_EQ(refusal(text), "scene.json: /laser/power_w: duplicate key");
  const std::string in_array = R"({"objects": [{}, {"radius": 1, "radius": 2}]})";
  EXPECT_EQ(refusal(in_array), "scene.json: /objects/1/radius: duplicate key");
}

TEST(Scene, RefusesMalformedJsonWithItsPosition) {
  const std::string message = refusal(std::string("{\n  \"laser\": {,\n}"));
  EXPECT_EQ(message.rfind("scene.json: invalid JSON: parse error at line 2, column 13", 0), 0u)
      << message;
}

TEST(Scene, LoadNamesAMissingFile) {
  try {
    loadScene("/nonexistent/scene.json");
    FAIL() << "a missing file was accepted";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "/nonexistent/scene.json: cannot open the scene file");
  }
}

}  // namespace
}  // namespace glint

namespace glint {
namespace {

TEST(SceneHazard, ExposureDefaultsToTheAversionResponseInTheVisibleAndTenSecondsBeyond) {
  json j = minimal();
  j["laser"].erase("exposure_s");
  j["laser"]["wavelength_nm"] = 532;
  Scene s = parseScene(j.dump(), "scene.json");
  EXPECT_TRUE(s.hazard.exposure_default);
  EXPECT_EQ(s.hazard.exposure_s, 0.25) << "the aversion response";
  EXPECT_NEAR(s.hazard.mpe_w_m2, 18.0 * std::pow(0.25, -0.25), 1e-9) << "25.46 W/m²";
  j["laser"]["wavelength_nm"] = 1064;
  s = parseScene(j.dump(), "scene.json");
  EXPECT_EQ(s.hazard.exposure_s, 10.0) << "no aversion response beyond 700 nm";
  EXPECT_NEAR(s.hazard.mpe_w_m2, 50.0, 1e-9) << "1064 nm from 10 s: 50 C_C W/m²";
  j["laser"]["exposure_s"] = 1.0;
  s = parseScene(j.dump(), "scene.json");
  EXPECT_FALSE(s.hazard.exposure_default);
  EXPECT_EQ(s.hazard.exposure_s, 1.0) << "the file's value";
}

TEST(ScenePlanes, PlaneLoadsWithDefaultsAndRefusesBadValues) {
  json j = minimal();
  j["planes"] = json::parse(R"([{"name": "ground", "origin": [-5, -5, -1.5],
      "u_axis": [2, 0, 0], "v_axis": [0, 3, 0], "size_m": [10, 8], "pixel_m": 0.1}])");
  const Scene scene = parseScene(j.dump(), "scene.json");
  ASSERT_EQ(scene.planes.size(), 1u);
  const PlaneSpec& p = scene.planes[0];
  EXPECT_EQ(p.name, "ground");
  EXPECT_EQ(p.u_axis, Vec3(1, 0, 0)) << "normalised";
  EXPECT_EQ(p.v_axis, Vec3(0, 1, 0));
  EXPECT_NEAR(p.block_m, 1.6, 1e-12) << "16 pixels by default";
  EXPECT_EQ(p.tolerance, 0.01);
  const FieldSpec spec = planeFieldSpec(scene, p);
  EXPECT_TRUE(spec.plane);
  // 10 m and 8 m at 0.1 m: 100 and 80 pixels, rounded up to whole 16-pixel blocks; one layer.
  EXPECT_EQ(spec.nodes(), (std::array<int, 3>{113, 81, 1}));
  EXPECT_EQ(spec.axes[2], Vec3(0, 0, 1)) << "u × v";
  EXPECT_NEAR(spec.floor_w_m2, 1e-3 * 90.0 * std::pow(0.25, -0.25), 1e-12) << "1e-3 × MPE";

  auto refused = [&](const char* key, const json& value) {
    json bad = j;
    bad["planes"][0][key] = value;
    return refusal(bad);
  };
  EXPECT_EQ(refused("name", "a/b").rfind("scene.json: /planes/0/name: must be 1 to 64 letters", 0),
            0u)
      << refused("name", "a/b");
  EXPECT_EQ(refused("v_axis", json::array({1, 1, 0})),
            "scene.json: /planes/0/v_axis: must be perpendicular to u_axis");
  EXPECT_EQ(refused("size_m", json::array({10})).rfind("scene.json: /planes/0/size_m: must be", 0),
            0u);
  EXPECT_EQ(refused("size_m", json::array({10, -1})),
            "scene.json: /planes/0/size_m: must be > 0 and at most 2e7 m");
  EXPECT_EQ(refused("block_m", 0.3),
            "scene.json: /planes/0/block_m: must be pixel_m times a power of two (1, 2, 4, ..., "
            "4096)");
  json twice = j;
  twice["planes"].push_back(twice["planes"][0]);
  EXPECT_EQ(refusal(twice), "scene.json: /planes/1/name: \"ground\" names two planes");
}

TEST(SceneObservers, BoxLoadsWithDefaultsAndRefusesBadValues) {
  json j = minimal();
  j["observers"] = json::parse(R"({"min": [-1, -1, -1], "max": [1, 2, 3], "voxel_m": 0.1})");
  const Scene scene = parseScene(j.dump(), "scene.json");
  ASSERT_TRUE(scene.observers.has_value()) << "the section was read";
  EXPECT_NEAR(scene.observers->block_m, 1.6, 1e-12) << "16 voxels by default";
  EXPECT_EQ(scene.observers->tolerance, 0.01) << "the documented default";
  const FieldSpec spec = fieldSpec(scene);
  EXPECT_EQ(spec.block_voxels, 16);
  // 2 m, 3 m, 4 m at 0.1 m: 20, 30, 40 voxels, rounded up to whole 16-voxel blocks.
  EXPECT_EQ(spec.nodes(), (std::array<int, 3>{33, 33, 49})) << "box extended to whole blocks";
  // 1064 nm for 0.25 s: 90 C_C t^0.75 J/m² over t = 90 × 0.25^-0.25 = 127.28 W/m².
  EXPECT_NEAR(spec.floor_w_m2, 1e-3 * 90.0 * std::pow(0.25, -0.25), 1e-12) << "1e-3 × MPE";

  auto refused = [&](const char* key, const json& value) {
    json bad = j;
    bad["observers"][key] = value;
    return refusal(bad);
  };
  EXPECT_EQ(refused("voxel_m", 0.0),
            "scene.json: /observers/voxel_m: must be in [1e-06, 100000] m");
  EXPECT_EQ(refused("block_m", 0.3),
            "scene.json: /observers/block_m: must be voxel_m times a power of two (1, 2, 4, "
            "..., 4096)");
  EXPECT_EQ(refused("max", json::array({1, -2, 3})),
            "scene.json: /observers/max: must exceed min on every axis");
  EXPECT_EQ(refused("tolerance", 1.5), "scene.json: /observers/tolerance: must be in (0, 1)");
  EXPECT_EQ(refused("floor_w_m2", 0.0), "scene.json: /observers/floor_w_m2: must be > 0");
  EXPECT_EQ(refused("spacing", 1.0).rfind("scene.json: /observers/spacing: unknown key", 0), 0u)
      << refused("spacing", 1.0);
  EXPECT_THROW(fieldSpec(parseScene(minimal().dump(), "scene.json")), InputError)
      << "glint run needs the section";
}

}  // namespace
}  // namespace glint
