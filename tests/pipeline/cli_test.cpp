#include "pipeline/commands/cli.h"

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>
#include <vector>

#include "export/exr_map.h"
#include "facets/vec3.h"
#include "pipeline/base/number_format.h"
#include "pipeline/input/scene.h"
#include "support/cli.h"
#include "support/files.h"
#include "support/refusal.h"

namespace glint {
namespace {

namespace fs = std::filesystem;

using test::glint;
using test::Outcome;

// A fresh folder per test, removed afterwards.
class CliTest : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = test::freshTestFolder("glint_cli_"); }
  void TearDown() override { fs::remove_all(dir_); }

  std::string write(const std::string& name, const std::string& text) {
    std::ofstream(dir_ / name) << text;
    return (dir_ / name).string();
  }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  std::size_t filesInDir() const {
    return static_cast<std::size_t>(
        std::distance(fs::directory_iterator(dir_), fs::directory_iterator()));
  }
  static std::string example(const std::string& name) {
    return std::string(GLINT_EXAMPLES_DIR) + "/" + name;
  }

  fs::path dir_;
};

using test::readFile;

TEST_F(CliTest, VersionAndHelpSucceed) {
  const Outcome v = glint({"--version"});
  EXPECT_EQ(v.status, 0);
  EXPECT_NE(v.out.find("glint 0."), std::string::npos) << v.out;
  const Outcome h = glint({"--help"});
  EXPECT_EQ(h.status, 0);
  EXPECT_NE(h.out.find("points"), std::string::npos) << h.out;
  const Outcome ph = glint({"points", "--help"});
  EXPECT_EQ(ph.status, 0);
  EXPECT_NE(ph.out.find("--tolerance"), std::string::npos) << ph.out;
}

// glint fit on a table of a constant f = 0.05 /sr: a Lambertian part alone gives it back,
// ρd = π f, and the JSON it prints is a material a scene takes; a bad table is status 2.
TEST_F(CliTest, FitPrintsTheMaterialAndItsErrorAsJson) {
  const std::string table = std::string(GLINT_TEST_DATA_DIR) + "/abg_disk_table.csv";
  const Outcome o = glint({"fit", table, "--lobes", "0", "--no-abg"});
  ASSERT_EQ(o.status, 0) << o.err;
  const nlohmann::json j = nlohmann::json::parse(o.out);
  EXPECT_NEAR(j.at("material").at("diffuse_reflectance").get<double>(), kPi * 0.05, 1e-6) << o.out;
  EXPECT_LT(j.at("fit").at("max_relative_error").get<double>(), 1e-6) << o.out;
  EXPECT_EQ(j.at("fit").at("nodes").get<int>(), 18 * 18 * 7) << "the nodes below 89.5°";
  EXPECT_FALSE(j.at("material").contains("abg"));
  const Outcome bad = glint(
      {"fit", write("bad.csv", "theta_i_deg,theta_o_deg,delta_phi_deg,brdf_per_sr\n0,0,0,-1\n")});
  EXPECT_EQ(bad.status, 2);
  EXPECT_NE(bad.err.find("bad.csv: line 2: brdf_per_sr must be ≥ 0"), std::string::npos) << bad.err;
  EXPECT_EQ(glint({"fit", table, "--lobes", "7"}).status, 2) << "at most 4 lobes";
}

// Whatever the model, glint fit prints a material a scene takes, or refuses: on the constant
// table the default model (two lobes, ABg, Lambert) once printed "b": null, A 8.75e42 and σ 0,
// each refused by the reader (issue 64); one node was "fitted" to the starting guesses, and a
// spike the fit cannot follow passed without a word.
TEST_F(CliTest, FitPrintsOnlyAMaterialASceneTakesAndWarnsWhereItMissesTheTable) {
  const std::string table = std::string(GLINT_TEST_DATA_DIR) + "/abg_disk_table.csv";
  const auto sceneTakes = [](const nlohmann::json& material) {
    const nlohmann::json scene = {
        {"laser",
         {{"position", {-10, 0, 0}},
          {"direction", {1, 0, 0}},
          {"power_w", 1.0},
          {"wavelength_nm", 532},
          {"beam", {{"profile", "flat_top"}, {"radius_m", 1.0}}}}},
        {"materials", {{"fitted", material}}},
        {"objects",
         {{{"shape", "sphere"}, {"center", {0, 0, 0}}, {"radius", 0.5}, {"material", "fitted"}}}}};
    return test::refusalOf([&] { (void)parseScene(scene.dump(), "scene.json"); });
  };
  for (const std::vector<std::string>& model :
       {std::vector<std::string>{}, {"--lobes", "1"}, {"--lobes", "0", "--no-abg"}}) {
    std::vector<std::string> args = {"fit", table};
    args.insert(args.end(), model.begin(), model.end());
    const Outcome o = glint(args);
    ASSERT_EQ(o.status, 0) << args.size() << " arguments: " << o.err;
    const nlohmann::json j = nlohmann::json::parse(o.out);
    EXPECT_EQ(o.out.find("null"), std::string::npos) << o.out;
    EXPECT_EQ(sceneTakes(j.at("material")), "(accepted)") << o.out;
    // The table is a constant: any model that holds a Lambertian part matches it, and the
    // terms it has no use for are dropped.
    EXPECT_LT(j.at("fit").at("max_relative_error").get<double>(), 0.1) << o.out;
    EXPECT_EQ(o.err.find("warning"), std::string::npos) << o.err;
  }

  const Outcome one = glint({"fit", write("one.csv",
                                          "theta_i_deg,theta_o_deg,delta_phi_deg,brdf_per_sr\n"
                                          "10,10,0,0.05\n")});
  EXPECT_EQ(one.status, 2) << one.out;
  EXPECT_NE(one.err.find("one.csv: 1 node(s) below 89.5° of θ cannot settle the fit's 8 "
                         "parameters"),
            std::string::npos)
      << one.err;
  EXPECT_EQ(one.out, "") << "nothing printed as a material";

  // The constant table with one node 100 times brighter: no model of the fit follows a spike
  // one node wide, and it must say so.
  std::ifstream in(table);
  std::string spiked, line;
  while (std::getline(in, line)) {
    spiked += (line == "10,10,0,0.05" ? "10,10,0,5" : line) + "\n";
  }
  ASSERT_NE(spiked.find("10,10,0,5\n"), std::string::npos) << "premise: the node is in the table";
  const Outcome spike = glint({"fit", write("spiked.csv", spiked)});
  ASSERT_EQ(spike.status, 0) << spike.err;
  const double missed =
      nlohmann::json::parse(spike.out).at("fit").at("max_relative_error").get<double>();
  EXPECT_GT(missed, 0.1) << spike.out;
  EXPECT_NE(spike.err.find("glint fit: warning: the fit is up to"), std::string::npos) << spike.err;
}

// An observer cut short by accuracy.max_evaluations is an estimate, not a value: where it may
// be hazardous (here, in the cylinder's fan 2 m toward the laser, about 5 × the MPE) glint
// points says so with what value plus error reaches, whatever its estimate reads (issue 64:
// "peak hazard ratio 0" was the summary of observers never evaluated).
TEST_F(CliTest, PointsCutShortSayWhatTheirBoundReaches) {
  nlohmann::json scene = nlohmann::json::parse(std::ifstream(example("cylinder.json")));
  scene.erase("observers");
  scene.erase("reach");
  scene["accuracy"] = {{"max_evaluations", 16}};
  const std::string points = write("fan.csv", "x,y,z\n-2,0,0\n");
  const Outcome o = glint({"points", write("short.json", scene.dump()), "--points", points, "--out",
                           path("short.csv")});
  ASSERT_EQ(o.status, 0) << o.err;
  EXPECT_NE(o.err.find("1 of 1 observers did not reach the tolerance"), std::string::npos) << o.err;
  EXPECT_NE(o.err.find("they may be hazardous, whatever the peak above says"), std::string::npos)
      << o.err;
  // The same observer converged: its truth is within what the cut-short one claimed.
  scene.erase("accuracy");
  const Outcome full = glint(
      {"points", write("full.json", scene.dump()), "--points", points, "--out", path("full.csv")});
  ASSERT_EQ(full.status, 0) << full.err;
  const auto row = [](const std::string& csv) {
    std::ifstream in(csv);
    std::string header, line;
    std::getline(in, header);
    std::getline(in, line);
    std::vector<double> v;
    std::stringstream cells(line);
    for (std::string c; std::getline(cells, c, ',');) v.push_back(std::atof(c.c_str()));
    return v;
  };
  const std::vector<double> cut = row(path("short.csv")), truth = row(path("full.csv"));
  ASSERT_GE(cut.size(), 5u);
  EXPECT_GE(cut[3] + cut[4], truth[3] * (1.0 - 1e-3))
      << "irradiance + error of the cut-short observer against the converged irradiance";
  EXPECT_GT(truth[7], 1.0) << "premise: the observer is in the hazardous fan";
}

// Issue 67: nothing echoed the laser, so a 5 mW laser written as "power_w": 5 ran without a
// word. The terminal states the laser and its limits before the work, summary.json the laser as
// read, glint points the same line in its summary.
TEST_F(CliTest, TheLaserAsReadIsEchoedBeforeTheWorkAndRecorded) {
  const std::string scene = write("echo.json", R"({
    "laser": {"position": [-100, 0, 0], "direction": [2, 0, 0], "power_w": 5,
              "wavelength_nm": 532, "beam": {"profile": "gaussian", "w_m": 0.001,
                                              "divergence_rad": 0.001}},
    "materials": {"mirror": {"specular_reflectance": 0.9, "sigma": 0.01}},
    "objects": [{"shape": "disk", "center": [0, 0, 0], "normal": [-1, 1, 0], "radius": 0.1,
                 "material": "mirror", "segments": 8}],
    "far_field": {"enabled": false},
    "optical_aid": {"aperture_m": 0.05, "magnification": 7, "transmission": 0.7},
    "planes": [{"name": "floor", "origin": [-2, -2, -1], "u_axis": [1, 0, 0],
                "v_axis": [0, 1, 0], "size_m": [4, 4], "pixel_m": 0.5}]})");
  const std::string line =
      "5 W at 532 nm; Gaussian beam, w 0.001 m, divergence 1 mrad; from (-100, 0, 0) m toward "
      "(1, 0, 0)";
  const Outcome r = glint({"run", scene, "-o", path("echo")});
  ASSERT_EQ(r.status, 0) << r.err;
  const std::size_t laser_at = r.err.find("glint run: laser " + line + "\n");
  EXPECT_NE(laser_at, std::string::npos) << r.err;
  EXPECT_NE(r.err.find("glint run: limits ANSI Z136.1-2014, eye: MPE "), std::string::npos)
      << r.err;
  EXPECT_LT(laser_at, r.err.find("plane floor")) << "before the work: " << r.err;
  const auto summary = nlohmann::json::parse(readFile(path("echo/summary.json")));
  // The aided verdict beside the naked eye's on the terminal (issue 67: only summary.json had
  // it): 0.7 × 7² = 34.3.
  const auto& floor = summary.at("planes").at(0);
  EXPECT_NE(
      r.err.find("  through the optical aid (gain 34.3): peak hazard ratio " +
                 formatNumber("%.3g", floor.at("aided_peak_hazard_ratio").get<double>()) +
                 ", hazardous area " +
                 formatNumber("%.4g", floor.at("aided_hazardous_area_m2").get<double>()) + " m²\n"),
      std::string::npos)
      << r.err;
  const auto& laser = summary.at("laser");
  EXPECT_EQ(laser.at("power_w").get<double>(), 5.0);
  EXPECT_EQ(laser.at("wavelength_nm").get<double>(), 532.0);
  EXPECT_EQ(laser.at("beam").at("profile"), "gaussian");
  EXPECT_EQ(laser.at("beam").at("w_m").get<double>(), 0.001);
  EXPECT_EQ(laser.at("direction"), nlohmann::json::parse("[1.0, 0.0, 0.0]"));
  const Outcome p = glint({"points", scene, "--points", write("one.csv", "x,y,z\n-1,1,0\n"),
                           "--out", path("one_out.csv")});
  ASSERT_EQ(p.status, 0) << p.err;
  EXPECT_NE(p.err.find("  laser: " + line + "\n"), std::string::npos) << p.err;
}

// A plane's map says, point by point, what its zone counts a point by: irradiance_upper_w_m2 is
// the value where it converged and the value plus error where it was cut short, so that a map
// whose hazard_ratio reads below 1 everywhere still shows where the hazard may be (issue 64).
TEST_F(CliTest, APlanesUpperChannelHoldsWhatItsZoneCountsEachPointBy) {
  nlohmann::json scene = nlohmann::json::parse(std::ifstream(example("cylinder.json")));
  scene.erase("observers");
  scene.erase("reach");
  scene["far_field"] = {{"enabled", false}};
  scene["accuracy"] = {{"max_evaluations", 16}};
  scene["planes"] = {{{"name", "fan"},
                      {"origin", {-4, -2, 0}},
                      {"u_axis", {1, 0, 0}},
                      {"v_axis", {0, 1, 0}},
                      {"size_m", {3.2, 4}},
                      {"pixel_m", 0.1}}};
  const Outcome o = glint({"run", write("fan.json", scene.dump()), "-o", path("fan"), "--quiet"});
  ASSERT_EQ(o.status, 0) << o.err;
  const auto summary = nlohmann::json::parse(readFile(path("fan/summary.json")));
  const double mpe = summary.at("hazard").at("mpe_w_m2").get<double>();
  const std::string exr = path("fan/fan.exr");
  int w = 0, h = 0;
  const std::vector<float> e = glint::readExrChannel(exr, "irradiance_w_m2", w, h);
  const std::vector<float> upper = glint::readExrChannel(exr, "irradiance_upper_w_m2", w, h);
  const std::vector<float> status = glint::readExrChannel(exr, "status", w, h);
  ASSERT_EQ(upper.size(), e.size());
  std::size_t cut = 0, counted = 0, counted_by_error = 0;
  for (std::size_t k = 0; k < e.size(); ++k) {
    if (status[k] == 5.0f) {
      ++cut;
      EXPECT_GE(upper[k], e[k]) << "pixel " << k << ": value plus error";
    } else if (status[k] != 6.0f) {
      EXPECT_EQ(upper[k], e[k]) << "pixel " << k << " (status " << status[k] << ")";
    }
    if (static_cast<double>(upper[k]) >= mpe) {
      ++counted;
      counted_by_error += static_cast<double>(e[k]) >= mpe ? 0 : 1;
    }
  }
  ASSERT_GT(cut, 0u) << "the premise: points cut short";
  ASSERT_GT(counted_by_error, 0u) << "the premise: points whose value alone reads safe";
  const auto& plane = summary.at("planes").at(0);
  EXPECT_NEAR(plane.at("hazardous_area_m2").get<double>(), 0.01 * static_cast<double>(counted),
              1e-9)
      << "the zone is the pixels whose upper irradiance reaches the MPE";
}

// From a point on a disk, or a nanometre above it, a piece of the disk has no finite bound:
// glint points once stopped there with "internal error" (status 1). The observer is refused
// with its position, status 2, and one a millimetre up is integrated.
TEST_F(CliTest, PointsOnTheTargetsSurfaceAreRefusedWithTheirPosition) {
  const std::string scene = write("disk.json", R"({
    "laser": {"position": [-100, 0, 60], "direction": [1, 0, -0.6], "power_w": 200.0,
              "wavelength_nm": 532, "beam": {"profile": "flat_top", "radius_m": 0.3}},
    "materials": {"m": {"specular_reflectance": 0.5, "sigma": 0.02, "diffuse_reflectance": 0.3}},
    "objects": [{"shape": "disk", "center": [0, 0, 0], "normal": [0, 0, 1], "radius": 0.1,
                 "segments": 8, "material": "m"}]})");
  for (const char* on : {"0,0,0", "0,0,1e-9", "-0.1,0,1e-9"}) {
    const Outcome o = glint({"points", scene, "--points",
                             write("on.csv", std::string("x,y,z\n1,1,1\n") + on + "\n"), "--out",
                             path("on_out.csv"), "--quiet"});
    EXPECT_EQ(o.status, 2) << on << ": " << o.err;
    EXPECT_NE(o.err.find("observer 2 ("), std::string::npos) << on << ": " << o.err;
    EXPECT_NE(o.err.find("its irradiance has no finite bound"), std::string::npos) << o.err;
    EXPECT_FALSE(fs::exists(path("on_out.csv"))) << "nothing written";
  }
  const Outcome above = glint({"points", scene, "--points", write("up.csv", "x,y,z\n0,0,1e-3\n"),
                               "--out", path("up_out.csv"), "--quiet"});
  EXPECT_EQ(above.status, 0) << above.err;
}

TEST_F(CliTest, UsageErrorsExitWithStatusTwo) {
  EXPECT_EQ(glint({}).status, 2) << "no command";
  EXPECT_EQ(glint({"paint"}).status, 2) << "unknown command";
  // A misspelt command is named, with the command it is nearest (issue 67: "glint rn x.json"
  // said only that a subcommand is required).
  const Outcome misspelt = glint({"rn", "x.json"});
  EXPECT_EQ(misspelt.status, 2) << misspelt.err;
  EXPECT_NE(misspelt.err.find("glint: error: unknown command \"rn\" (did you mean \"run\"?); the "
                              "commands are points, run, batch or fit"),
            std::string::npos)
      << misspelt.err;
  EXPECT_EQ(glint({"--version"}).status, 0) << "an option is no command";
  EXPECT_EQ(glint({"points", example("cylinder.json")}).status, 2) << "--points missing";
  EXPECT_EQ(glint({"points", example("cylinder.json"), "--points", example("cylinder_186.csv"),
                   "--tolerance", "5"})
                .status,
            2)
      << "tolerance out of range";
  EXPECT_EQ(glint({"points", example("cylinder.json"), "--points", example("cylinder_186.csv"),
                   "--normals", "bent"})
                .status,
            2)
      << "unknown normal model";
  // Flat facets are the paper scheme's model only: with another scheme they would be ignored.
  const Outcome flat_lobe =
      glint({"points", example("cylinder.json"), "--points", example("cylinder_186.csv"),
             "--normals", "flat", "--scheme", "lobe", "--quiet"});
  EXPECT_EQ(flat_lobe.status, 2) << flat_lobe.err;
  EXPECT_NE(flat_lobe.err.find("--scheme paper"), std::string::npos) << flat_lobe.err;
}

TEST_F(CliTest, EveryOptionValueIsCheckedAtTheBoundaryAndNamed) {
  // `--tolerance nan` once passed CLI11's range check (every comparison with NaN is false) and
  // ended as an internal error (status 1) deep in the integrator.
  const std::vector<std::pair<std::string, std::string>> bad = {
      {"--tolerance", "nan"}, {"--tolerance", "inf"},   {"--tolerance", "-1e-3"},
      {"--tolerance", "0"},   {"--tolerance", "1e-3x"}, {"--tolerance", ""},
      {"--threads", "0"},     {"--threads", "nan"},     {"--threads", "1.5"},
      {"--uniform", "13"},    {"--uniform", "-1"},      {"--normals", "bent"},
      {"--memory", "0"},      {"--memory", "12Q"},      {"--memory", "-4G"},
      {"--scheme", "fast"}};
  for (const auto& [option, value] : bad) {
    const Outcome r = glint({"points", example("cylinder.json"), "--points",
                             example("cylinder_186.csv"), option, value, "--quiet"});
    EXPECT_EQ(r.status, 2) << option << " " << value << ": " << r.err;
    EXPECT_NE(r.err.find(option), std::string::npos) << option << " " << value << ": " << r.err;
  }
  const Outcome run = glint({"run", example("disk_glint.json"), "--threads", "-2", "--quiet"});
  EXPECT_EQ(run.status, 2) << run.err;
  EXPECT_NE(run.err.find("--threads"), std::string::npos) << run.err;
}

TEST_F(CliTest, BadSceneExitsTwoWithItsPathAndWritesNothing) {
  std::string scene = readFile(example("cylinder.json"));
  scene.replace(scene.find("\"sigma\": 0.003"), 14, "\"sigma\": 0");
  const std::string scene_path = write("scene.json", scene);
  const std::string points = write("p.csv", "x,y,z\n1,2,3\n");
  const Outcome r = glint({"points", scene_path, "--points", points, "--out", path("out.csv")});
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find(scene_path + ": /materials/polished/sigma: must be > 0"), std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(path("out.csv")));
  EXPECT_EQ(filesInDir(), 2u) << "no temporary file left behind";
}

TEST_F(CliTest, BadPointsFileExitsTwoWithItsLineAndWritesNothing) {
  const std::string points = write("p.csv", "x,y,z\n1,2,3\n4,five,6\n");
  const Outcome r =
      glint({"points", example("cylinder.json"), "--points", points, "--out", path("out.csv")});
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find(points + ":3: column 2 (y): \"five\" is not a number"), std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(path("out.csv")));
}

TEST_F(CliTest, MissingOutputFolderIsRefusedBeforeTheWork) {
  const std::string points = write("p.csv", "x,y,z\n1,2,3\n");
  const Outcome r = glint({"points", example("cylinder.json"), "--points", points, "--out",
                           path("no/such/folder/out.csv"), "--quiet"});
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("cannot create"), std::string::npos) << r.err;
}

TEST_F(CliTest, PointsWritesOneRowPerObserverInInputOrder) {
  const std::string points = write("p.csv", "x,y,z\n-3,0,0.1\n0.1,-7.25,0.5\n2.5e1,3,-0.25\n");
  const Outcome r =
      glint({"points", example("cylinder.json"), "--points", points, "--out", path("out.csv")});
  ASSERT_EQ(r.status, 0) << r.err;
  std::istringstream csv(readFile(path("out.csv")));
  std::string line;
  std::getline(csv, line);
  EXPECT_EQ(line, "x,y,z,irradiance_w_m2,error_estimate_w_m2,evaluations,converged,hazard_ratio");
  std::vector<std::string> rows;
  while (std::getline(csv, line)) rows.push_back(line);
  ASSERT_EQ(rows.size(), 3u);
  EXPECT_EQ(rows[0].rfind("-3,0,0.1,", 0), 0u) << rows[0];
  EXPECT_EQ(rows[1].rfind("0.1,-7.25,0.5,", 0), 0u) << rows[1];
  EXPECT_EQ(rows[2].rfind("25,3,-0.25,", 0), 0u) << rows[2];
  for (const auto& row : rows) {
    std::vector<std::string> cells;
    std::stringstream cs(row);
    for (std::string c; std::getline(cs, c, ',');) cells.push_back(c);
    ASSERT_EQ(cells.size(), 8u) << row;
    EXPECT_EQ(cells[6], "1") << "converged: " << row;
    // 1064 nm for 10 s: MPE 50 W/m² (ANSI Z136.1-2014 Table 5a, 50 C_C W/m²).
    EXPECT_DOUBLE_EQ(std::stod(cells[7]), std::stod(cells[3]) / 50.0) << row;
  }
  EXPECT_NE(r.err.find("glint points: 3 observers"), std::string::npos) << "summary: " << r.err;
}

TEST_F(CliTest, WritesToStandardOutputWithoutAnOutputFile) {
  const std::string points = write("p.csv", "x,y,z\n-3,0,0.1\n");
  const Outcome r = glint({"points", example("cylinder.json"), "--points", points, "--quiet"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(r.out.rfind("x,y,z,irradiance_w_m2", 0), 0u) << r.out;
  EXPECT_EQ(r.err, "") << "--quiet";
}

TEST_F(CliTest, UniformOptionRunsTheUniformTwin) {
  const std::string points = write("p.csv", "x,y,z\n-3,0,0.1\n");
  const Outcome r =
      glint({"points", example("cylinder.json"), "--points", points, "--uniform", "2", "--quiet"});
  ASSERT_EQ(r.status, 0) << r.err;
  std::istringstream csv(r.out);
  std::string line;
  std::getline(csv, line);
  std::getline(csv, line);
  // Columns: x,y,z,E,err,evaluations,converged,hazard_ratio — 4² sub-facets per facet seen.
  std::vector<std::string> cells;
  std::stringstream cs(line);
  for (std::string c; std::getline(cs, c, ',');) cells.push_back(c);
  ASSERT_EQ(cells.size(), 8u) << line;
  EXPECT_EQ(std::stol(cells[5]) % 16, 0) << line;
}

TEST_F(CliTest, RunWritesEachPlaneAsAnExrMapAndSummarisesIt) {
  // Planes only: a tilted wall across the narrow pencil of examples/disk_glint.json.
  const std::string scene = write("wall.json", R"({
    "laser": {"position": [-100, 0, 0], "direction": [1, 0, 0], "power_w": 1000.0,
              "wavelength_nm": 1064, "exposure_s": 0.25,
              "beam": {"profile": "flat_top", "radius_m": 0.5}},
    "materials": {"mirror": {"specular_reflectance": 0.9, "sigma": 0.001}},
    "objects": [{"shape": "disk", "center": [0.3, 0, 0.3], "normal": [-1, 1, 0], "radius": 0.05,
                 "material": "mirror", "segments": 8}],
    "planes": [{"name": "wall", "origin": [-1, 1.7, -0.6], "u_axis": [1, 0, 0],
                "v_axis": [0, 0.6, 0.8], "size_m": [2, 2], "pixel_m": 0.0625, "block_m": 0.5,
                "floor_w_m2": 1e-3}]})");
  const Outcome r = glint({"run", scene, "-o", path("out"), "--quiet"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_FALSE(fs::exists(path("out/irradiance.vdb"))) << "no box, no volume";
  const auto summary = nlohmann::json::parse(readFile(path("out/summary.json")));
  const auto& plane = summary.at("planes").at(0);
  EXPECT_EQ(plane.at("file"), "wall.exr");
  const double mpe = summary.at("hazard").at("mpe_w_m2").get<double>();

  Imf::InputFile file(path("out/wall.exr").c_str());
  const Imath::Box2i w = file.header().dataWindow();
  const int width = w.max.x - w.min.x + 1, height = w.max.y - w.min.y + 1;
  ASSERT_EQ(width, 33);
  ASSERT_EQ(height, 33);
  std::vector<float> e(static_cast<std::size_t>(width * height)), ratio(e.size()), status(e.size());
  Imf::FrameBuffer frame;
  const std::size_t row = sizeof(float) * static_cast<std::size_t>(width);
  frame.insert("irradiance_w_m2",
               Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(e.data()), sizeof(float), row));
  frame.insert("hazard_ratio",
               Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(ratio.data()), sizeof(float), row));
  frame.insert("status",
               Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(status.data()), sizeof(float), row));
  file.setFrameBuffer(frame);
  file.readPixels(w.min.y, w.max.y);
  const double peak = static_cast<double>(*std::max_element(e.begin(), e.end()));
  EXPECT_NEAR(peak, plane.at("peak_irradiance_w_m2").get<double>(), 1e-6 * peak)
      << "the map holds the summary's peak";
  EXPECT_NEAR(*std::max_element(ratio.begin(), ratio.end()), peak / mpe, 1e-6 * peak / mpe);
  EXPECT_GT(plane.at("peak_hazard_ratio").get<double>(), 1.0) << "the pencil is hazardous";
  EXPECT_GT(plane.at("hazardous_area_m2").get<double>(), 0.0);
  const auto below = std::count(status.begin(), status.end(), 3.0f);
  EXPECT_GT(below, width * height / 2) << "most of the wall proven below the floor, and marked";

  // --scheme overrides the scene's accuracy.scheme, and the summary says which ran (the lobe
  // scheme by default); both schemes meet the default tolerance of 1e-3, so their peaks agree
  // within 2e-3.
  const Outcome paper = glint({"run", scene, "-o", path("paper"), "--scheme", "paper", "--quiet"});
  ASSERT_EQ(paper.status, 0) << paper.err;
  const auto paper_summary = nlohmann::json::parse(readFile(path("paper/summary.json")));
  EXPECT_EQ(summary.at("integration_scheme"), "lobe");
  EXPECT_EQ(paper_summary.at("integration_scheme"), "paper");
  const double paper_peak =
      paper_summary.at("planes").at(0).at("peak_irradiance_w_m2").get<double>();
  EXPECT_NEAR(paper_peak, peak, 2e-3 * peak) << "the paper scheme's peak on the wall";
}

// Issue 34: a pencil 9 times the MPE crosses a 10 m box at 0.5 m between every lattice point
// (tests/data/subvoxel_pencil.json). glint run once said "none in the box" and, for the far
// field, "peak intensity 0 W/sr". Now the terminal and the summary say that a glint narrower
// than the lattice may pass, with its bound and the voxel that would resolve it, and the far
// field reports its floor, flagged as a bound.
TEST_F(CliTest, RunReportsAGlintBetweenTheLatticePointsWithItsBound) {
  const Outcome r =
      glint({"run", std::string(GLINT_TEST_DATA_DIR) + "/subvoxel_pencil.json", "-o", path("out")});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.err.find("nominal hazard zone (ratio ≥ 1): none at the lattice points, but not "
                       "proven"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(r.err.find("none in the box"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("warning: a glint narrower than the lattice may pass unseen"),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("voxel_m ≤ "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("peak intensity at most the floor"), std::string::npos) << r.err;
  const auto summary = nlohmann::json::parse(readFile(path("out/summary.json")));
  EXPECT_EQ(summary.at("hazard").at("nominal_hazard_zone").at("points").get<int>(), 0);
  EXPECT_TRUE(summary.at("hazard").at("narrow_glint_may_be_hazardous").get<bool>());
  const auto& narrow = summary.at("narrow_glints");
  EXPECT_GT(narrow.at("points").get<int>(), 0);
  EXPECT_EQ(narrow.at("points"), summary.at("points").at("narrow_glint_unresolved"));
  // The pencil carries about 9 × the MPE: the bound holds at least that.
  EXPECT_GE(narrow.at("max_bound_hazard_ratio").get<double>(), 8.0) << narrow.dump();
  EXPECT_GT(narrow.at("resolving_voxel_m").get<double>(), 0.0) << narrow.dump();
  EXPECT_LT(narrow.at("resolving_voxel_m").get<double>(), 0.5) << narrow.dump();
  const auto& far = summary.at("far_field");
  EXPECT_EQ(far.at("peak_intensity_basis"), "floor") << far.dump();
  EXPECT_TRUE(far.at("peak_intensity_is_bound").get<bool>());
  EXPECT_EQ(far.at("peak_intensity_w_sr").get<double>(), far.at("floor_w_sr").get<double>());
}

// issue 15: `glint run /dev/zero` once grew by 250 MB/s; a box of 64 000 voxels a side
// climbed to 6 GB showing "0/0 points". Now the inputs are capped, a region is refused before
// it starts with what it needs, and a run that passes the budget stops with nothing written.
TEST_F(CliTest, MemoryIsBudgetedFromTheFirstByte) {
  const Outcome zero = glint({"run", "/dev/zero", "-o", path("out"), "--quiet"});
  EXPECT_EQ(zero.status, 2) << zero.err;
  EXPECT_NE(zero.err.find("/dev/zero: longer than 64 MiB, more than a scene file may be"),
            std::string::npos)
      << zero.err;
  const Outcome points = glint({"points", example("disk_glint.json"), "--points", "/dev/zero",
                                "--memory", "64M", "--quiet"});
  EXPECT_EQ(points.status, 2) << points.err;
  EXPECT_NE(points.err.find("longer than 16 MiB, more than a points file may be"),
            std::string::npos)
      << points.err;

  nlohmann::json scene = nlohmann::json::parse(readFile(example("disk_glint.json")));
  scene["observers"] = {
      {"min", {-2000, -2000, -2000}}, {"max", {2000, 2000, 2000}}, {"voxel_m", 0.0625}};
  const std::string huge = write("huge.json", scene.dump());
  const Outcome refused = glint({"run", huge, "-o", path("huge"), "--memory", "16G"});
  EXPECT_EQ(refused.status, 2) << refused.err;
  // 87.3 TB of blocks, and 1.4 TB to resample the box at every 16th point for irradiance.vti.
  EXPECT_NE(refused.err.find("observer box (64001×64001×64001 lattice points at 0.0625 m) needs "
                             "at least 88.7 TB of memory, more than the budget of 16 GB"),
            std::string::npos)
      << refused.err;

  // 125 000 coarse blocks with nothing to evaluate: a floor of 179 MB, and 186 MB to write
  // irradiance.vti (the box resampled at every 4th point), starts; the run itself needs about
  // 430 MB, so at 380 MB it is stopped by the watch, in the built program (this test process's
  // own memory must not count). Without the far field, whose floor alone (its 2049² directions
  // a face) is over 250 MB.
  scene["observers"] = {
      {"min", {-50, -110, -50}}, {"max", {50, -10, 50}}, {"voxel_m", 0.125}, {"block_m", 2.0}};
  scene["far_field"] = {{"enabled", false}};
  const std::string big = write("big.json", scene.dump());
  const std::string cmd = std::string(GLINT_EXE) + " run " + big + " -o " + path("big") +
                          " --memory 380M 2> " + path("err.txt");
  const int status = std::system(cmd.c_str());
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 2) << readFile(path("err.txt"));
  const std::string err = readFile(path("err.txt"));
  EXPECT_NE(err.find("memory: at least 365 MB of the 380 MB budget"), std::string::npos) << err;
  EXPECT_NE(err.find("stopped when the resident memory reached"), std::string::npos) << err;
  EXPECT_NE(err.find("nothing was written"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(path("big")))
      << "the failed run left the folder it made (or an output or a temporary in it)";
}

// Issue 64: 3 M observers under --memory 200M ran to 247 MB and blamed "the objects' segments":
// the estimate left out the program's own resident memory (over 100 MB of libraries). They are
// refused before the work, as what they are.
TEST_F(CliTest, ObserversBeyondTheBudgetAreRefusedAsThePointsTheyAre) {
  std::string rows = "x,y,z\n";
  rows.reserve(rows.size() + 3'000'000 * 6);
  for (int i = 0; i < 3'000'000; ++i) rows += "1,2,3\n";
  const Outcome o =
      glint({"points", example("disk_glint.json"), "--points", write("many.csv", rows), "--out",
             path("many_out.csv"), "--memory", "200M", "--quiet"});
  EXPECT_EQ(o.status, 2) << o.err;
  EXPECT_NE(o.err.find("3000000 observer points and their results, beside the "), std::string::npos)
      << o.err;
  EXPECT_NE(o.err.find("split the points file or raise --memory"), std::string::npos) << o.err;
  EXPECT_EQ(o.err.find("segments"), std::string::npos) << o.err;
  EXPECT_FALSE(fs::exists(path("many_out.csv"))) << "nothing written";
}

// issue 35 (3): the target was built whatever it took. A disk of 4096 segments makes 5 337 088
// facets: `points --memory 1G` ran 227 s to 8.9 GB and exited 0; `run --memory 1G` grew for
// 157 s to 13 GB before the watch stopped it. Both are refused now before a facet is made.
TEST_F(CliTest, ATargetBeyondTheBudgetIsRefusedBeforeItIsBuilt) {
  nlohmann::json disk = nlohmann::json::parse(readFile(example("disk.json")));
  disk["objects"][0]["segments"] = 4096;
  const std::string disk_file = write("disk.json", disk.dump());
  const Outcome points = glint({"points", disk_file, "--points", example("disk_points.csv"), "-o",
                                path("e.csv"), "--memory", "1G", "--quiet"});
  EXPECT_EQ(points.status, 2) << points.err;
  EXPECT_NE(points.err.find("the target (5337088 coarse facets, with 42 observer points) needs "
                            "at least 2."),
            std::string::npos)
      << points.err;
  EXPECT_NE(points.err.find(" GB of memory, more than the budget of 1 GB (--memory); lower the "
                            "objects' segments, decimate the meshes, or raise --memory"),
            std::string::npos)
      << points.err;
  EXPECT_EQ(filesInDir(), 1u) << "an output or a temporary was left beside the scene";

  nlohmann::json run = nlohmann::json::parse(readFile(example("disk_glint.json")));
  run["objects"][0]["segments"] = 4096;
  const Outcome refused = glint(
      {"run", write("glint.json", run.dump()), "-o", path("run"), "--memory", "1G", "--quiet"});
  EXPECT_EQ(refused.status, 2) << refused.err;
  // Before the target itself, its tessellation for target.vtp: 16 pieces of each facet.
  EXPECT_NE(refused.err.find("observer box (33×65×33 lattice points at 0.0625 m, 9.23 GB of it "
                             "to write target.vtp) needs at least 9.23 GB of memory, more than "
                             "the budget of 1 GB (--memory); lower the objects' segments or "
                             "decimate the meshes (target.vtp holds 16 pieces of every facet), "
                             "or raise --memory"),
            std::string::npos)
      << refused.err;
  EXPECT_FALSE(fs::exists(path("run"))) << "the refused run left the folder it made";
}

// issue 35 (3): a mesh was decoded and built whatever its size (2 M triangles, `points --memory
// 2G`: exit 0 at 7.8 GB). Its triangles are counted from the file's accessors and refused before
// any is decoded. Here a primitive of 1000 triangles over three vertices, instanced by 1000
// nodes: a million triangles from a 6 KB buffer, whose vertices are NaN, which decoding would
// refuse: the memory's refusal shows that nothing was decoded.
TEST_F(CliTest, AMeshBeyondTheBudgetIsRefusedBeforeItIsDecoded) {
  std::vector<float> positions(9, std::numeric_limits<float>::quiet_NaN());
  std::vector<std::uint16_t> indices(3000);
  for (std::size_t i = 0; i < indices.size(); ++i) indices[i] = static_cast<std::uint16_t>(i % 3);
  std::string bin(positions.size() * 4 + indices.size() * 2, '\0');
  std::memcpy(bin.data(), positions.data(), positions.size() * 4);
  std::memcpy(bin.data() + positions.size() * 4, indices.data(), indices.size() * 2);
  write("model.bin", bin);
  const nlohmann::json model = {
      {"asset", {{"version", "2.0"}}},
      {"scene", 0},
      {"scenes", {{{"nodes", {0}}}}},
      {"nodes", {{{"children", std::vector<int>(1000, 1)}}, {{"mesh", 0}}}},
      {"meshes", {{{"primitives", {{{"attributes", {{"POSITION", 0}}}, {"indices", 1}}}}}}},
      {"buffers", {{{"uri", "model.bin"}, {"byteLength", bin.size()}}}},
      {"bufferViews",
       {{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", 36}},
        {{"buffer", 0}, {"byteOffset", 36}, {"byteLength", 6000}}}},
      {"accessors",
       {{{"bufferView", 0}, {"componentType", 5126}, {"count", 3}, {"type", "VEC3"}},
        {{"bufferView", 1}, {"componentType", 5123}, {"count", 3000}, {"type", "SCALAR"}}}}};
  write("model.gltf", model.dump());
  nlohmann::json scene = nlohmann::json::parse(readFile(example("disk.json")));
  scene["objects"] = {{{"shape", "mesh"}, {"file", "model.gltf"}, {"material", "glass"}}};
  const Outcome refused = glint({"points", write("mesh.json", scene.dump()), "--points",
                                 example("disk_points.csv"), "--memory", "1G", "--quiet"});
  EXPECT_EQ(refused.status, 2) << refused.err;
  // Each triangle a PN facet in the occluder: about 2 KB.
  EXPECT_NE(refused.err.find("/objects/0/file: model.gltf (1000000 triangles, as a target) needs "
                             "at least 1.8"),
            std::string::npos)
      << refused.err;
  EXPECT_NE(refused.err.find("more than the budget of 1 GB (--memory); decimate the mesh"),
            std::string::npos)
      << refused.err;
  EXPECT_EQ(refused.err.find("not finite"), std::string::npos) << "it was decoded: " << refused.err;
}

// issue 35 (3): `run --memory 2G` with far_field.face_pixels 8192 passed a floor of 2.3 MB and
// grew for 18 s to 4.6 GB, in its first face. Its six lattices and a face's grids are counted
// now: refused before the target is built.
TEST_F(CliTest, AFarFieldBeyondTheBudgetIsRefusedBeforeItsFirstFace) {
  nlohmann::json scene = nlohmann::json::parse(readFile(example("disk_glint.json")));
  scene["far_field"] = {{"face_pixels", 8192}};
  const Outcome refused = glint(
      {"run", write("far.json", scene.dump()), "-o", path("far"), "--memory", "2G", "--quiet"});
  EXPECT_EQ(refused.status, 2) << refused.err;
  EXPECT_NE(refused.err.find("the far field (6 × 8193² directions) needs at least 5.51 GB of "
                             "memory, more than the budget of 2 GB (--memory); lower "
                             "far_field.face_pixels, or raise --memory"),
            std::string::npos)
      << refused.err;
  EXPECT_FALSE(fs::exists(path("far"))) << "the refused run left the folder it made";
}

// What passes the estimate and still outgrows the budget stops, as glint run does: a disk of
// 256 segments, lit whole, has a floor of 19 MB, and each observer's workspace then takes about
// 70 MB (it bounds every facet), so at 100 MB the points stop, in the built program (this test
// process's own memory must not count). Before, glint points had no watch: it ran 114 s.
TEST_F(CliTest, PointsThatOutgrowTheBudgetStopAndWriteNothing) {
  nlohmann::json scene = nlohmann::json::parse(readFile(example("disk.json")));
  scene["objects"][0]["segments"] = 256;
  scene["laser"]["beam"] = {{"profile", "flat_top"}, {"radius_m", 1.0}};
  const std::string cmd = std::string(GLINT_EXE) + " points " + write("disk.json", scene.dump()) +
                          " --points " + example("disk_points.csv") + " -o " + path("e.csv") +
                          " --memory 100M --threads 1 2> " + path("err.txt");
  const int status = std::system(cmd.c_str());
  ASSERT_TRUE(WIFEXITED(status));
  const std::string err = readFile(path("err.txt"));
  EXPECT_EQ(WEXITSTATUS(status), 2) << err;
  EXPECT_NE(err.find("the observer points: stopped when the resident memory reached"),
            std::string::npos)
      << err;
  EXPECT_NE(err.find("beyond the budget of 100 MB (--memory); nothing was written"),
            std::string::npos)
      << err;
  EXPECT_FALSE(fs::exists(path("e.csv")));
  EXPECT_EQ(filesInDir(), 2u) << "the scene and err.txt; no output, no temporary";
}

// Issue 67: with a laser that lights nothing, the reach's line read "nothing is hazardous outside
// the target … closed", a verdict of safety where there is none. The warning comes before any
// verdict, and the reach says it has none.
TEST_F(CliTest, AReachOfATargetTheBeamDoesNotLightGivesNoVerdict) {
  const std::string scene = write("miss.json", R"({
    "laser": {"position": [-100, 5, 0], "direction": [1, 0, 0], "power_w": 200.0,
              "wavelength_nm": 532, "beam": {"profile": "flat_top", "radius_m": 0.2}},
    "materials": {"m": {"specular_reflectance": 0.5, "sigma": 0.02}},
    "objects": [{"shape": "disk", "center": [0, 0, 0], "normal": [-1, 0.6, 0.4], "radius": 0.1,
                 "material": "m", "segments": 8}]})");
  const Outcome r = glint({"run", scene, "-o", path("miss")});
  ASSERT_EQ(r.status, 0) << r.err;
  const std::size_t warning = r.err.find("glint run: warning: no facet of the target is lit");
  const std::size_t verdict = r.err.find(
      "hazard reach: no verdict: the beam lights no facet of the target, so this empty reach is "
      "not a safe one (see the warning)\n");
  EXPECT_NE(verdict, std::string::npos) << r.err;
  EXPECT_LT(warning, verdict) << "the warning first: " << r.err;
  EXPECT_EQ(r.err.find("nothing is hazardous"), std::string::npos) << r.err;
}

// issue 50 (6.4): a target the beam does not light reflects nothing, and its empty result read
// "nothing is hazardous" with no word that nothing was lit. Now run, points and batch warn on
// the terminal (even with --quiet), run in summary.json's `warnings`, batch in each scenario's
// result.json and in the study's summary.json, counted.
TEST_F(CliTest, ATargetTheBeamDoesNotLightIsWarnedOfAndNotPassedAsSafe) {
  const fs::path data = GLINT_TEST_DATA_DIR;
  nlohmann::json scene = nlohmann::json::parse(readFile(data / "study_scene.json"));
  scene["far_field"] = {{"enabled", false}};
  const std::string lit = write("lit.json", scene.dump());
  // The laser at x = −100 m turned round: the cylinder at the origin lies behind it.
  scene["laser"]["direction"] = {-1, 0, 0};
  const std::string unlit = write("study_scene.json", scene.dump());
  const std::string kWarning =
      "no facet of the target is lit: 192 of its 192 coarse facets lie "
      "behind the laser";

  const Outcome run = glint({"run", unlit, "-o", path("run"), "--quiet"});
  ASSERT_EQ(run.status, 0) << run.err;
  EXPECT_NE(run.err.find("glint run: warning: " + kWarning), std::string::npos) << run.err;
  const nlohmann::json summary = nlohmann::json::parse(readFile(path("run/summary.json")));
  ASSERT_EQ(summary.at("warnings").size(), 1u) << summary.dump(2);
  EXPECT_NE(summary["warnings"][0].get<std::string>().find(kWarning), std::string::npos);
  EXPECT_NE(summary["warnings"][0].get<std::string>().find("not a safe one"), std::string::npos);
  const Outcome lit_run = glint({"run", lit, "-o", path("lit"), "--quiet"});
  ASSERT_EQ(lit_run.status, 0) << lit_run.err;
  EXPECT_EQ(lit_run.err, "") << "a lit target: no warning";
  EXPECT_TRUE(nlohmann::json::parse(readFile(path("lit/summary.json"))).at("warnings").empty());

  const std::string points = write("p.csv", "x,y,z\n-3,0,0.1\n");
  const Outcome p = glint({"points", unlit, "--points", points, "--quiet"});
  ASSERT_EQ(p.status, 0) << p.err;
  EXPECT_NE(p.err.find("glint points: warning: " + kWarning), std::string::npos) << p.err;

  fs::copy_file(data / "study.json", dir_ / "study.json");
  const Outcome batch = glint({"batch", path("study.json"), "-o", path("batch"), "--quiet"});
  ASSERT_EQ(batch.status, 0) << batch.err;
  EXPECT_NE(batch.err.find("glint batch: warning: no facet of the target is lit in 4 of 4 "
                           "scenarios (0, 1, 2, 3)"),
            std::string::npos)
      << batch.err;
  const nlohmann::json study = nlohmann::json::parse(readFile(path("batch/summary.json")));
  EXPECT_EQ(study.at("scenarios").at("unlit"), 4) << study.at("scenarios").dump();
  EXPECT_EQ(study.at("warnings").size(), 1u) << study.at("warnings").dump();
  const nlohmann::json record =
      nlohmann::json::parse(readFile(path("batch/scenarios/s000000/result.json")));
  ASSERT_EQ(record.at("warnings").size(), 1u) << record.dump(2);
  EXPECT_NE(record["warnings"][0].get<std::string>().find("behind the laser"), std::string::npos);
}

TEST_F(CliTest, TheBuiltCommandExitsTwoOnBadInput) {
  const std::string cmd = std::string(GLINT_EXE) + " points " + path("missing.json") +
                          " --points " + path("missing.csv") + " 2> " + path("err.txt");
  const int status = std::system(cmd.c_str());
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 2);
  EXPECT_NE(readFile(path("err.txt")).find("missing.json: cannot open the scene file"),
            std::string::npos);
}

}  // namespace
}  // namespace glint
