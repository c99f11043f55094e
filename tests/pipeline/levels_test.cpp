// Levels beside the MPE: the flight zones' visual-interference levels (ANSI Z136.6) with their
// photopic correction, the analyst's own levels, their refusals, and each level's reach.
#include "hazard/levels.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "export/exr_map.h"
#include "pipeline/input/scene.h"
#include "pipeline/setup/target_builder.h"
#include "support/cli.h"
#include "support/refusal.h"

namespace glint {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

TEST(PhotopicEfficiency, IsTheCieTableAtItsEntriesAndItsLargerNeighbourBetween) {
  EXPECT_DOUBLE_EQ(photopicEfficiency(555.0), 1.0) << "V(λ) peaks at 555 nm";
  EXPECT_DOUBLE_EQ(photopicEfficiency(400.0), 0.000396);
  EXPECT_DOUBLE_EQ(photopicEfficiency(650.0), 0.107);
  EXPECT_DOUBLE_EQ(photopicEfficiency(700.0), 0.004102);
  // Between entries, the larger neighbour: never below the CIE's own 1 nm values (532 nm:
  // 0.8849624; 633 nm: 0.2353344; 445.5 nm lies between 0.0298 and 0.0313108).
  EXPECT_DOUBLE_EQ(photopicEfficiency(532.0), 0.91485) << "530 nm 0.862, 535 nm 0.91485";
  EXPECT_GE(photopicEfficiency(532.0), 0.8849624);
  EXPECT_DOUBLE_EQ(photopicEfficiency(633.0), 0.265) << "630 nm 0.265, 635 nm 0.217";
  EXPECT_GE(photopicEfficiency(633.0), 0.2353344);
  EXPECT_DOUBLE_EQ(photopicEfficiency(557.0), 1.0) << "555 nm 1, 560 nm 0.995";
}

TEST(FlightZones, AreTheZ1366LevelsInWattsPerSquareMetre) {
  const std::vector<ExposureLevel> z = flightZoneLevels(true);
  ASSERT_EQ(z.size(), 3u);
  // 100 µW/cm², 5 µW/cm², 50 nW/cm²: 1 µW/cm² = 1e-2 W/m².
  EXPECT_EQ(z[0].name, "sensitive_zone");
  EXPECT_DOUBLE_EQ(z[0].level_w_m2, 1.0);
  EXPECT_EQ(z[1].name, "critical_zone");
  EXPECT_DOUBLE_EQ(z[1].level_w_m2, 0.05);
  EXPECT_EQ(z[2].name, "laser_free_zone");
  EXPECT_DOUBLE_EQ(z[2].level_w_m2, 5e-4);
  for (const ExposureLevel& l : z) {
    EXPECT_TRUE(l.visually_corrected) << l.name;
    EXPECT_NE(l.source.find("Z136.6"), std::string::npos) << l.source;
  }
  EXPECT_FALSE(flightZoneLevels(false)[0].visually_corrected);
}

// A 532 nm scene, continuous, for the naked eye.
json greenScene() {
  return json::parse(R"({
    "laser": {"position": [-50, 0, 0], "direction": [1, 0, 0], "power_w": 500.0,
              "wavelength_nm": 532, "beam": {"profile": "flat_top", "radius_m": 0.5}},
    "materials": {"mirror": {"specular_reflectance": 0.9, "sigma": 0.02}},
    "objects": [{"shape": "sphere", "center": [0, 0, 0], "radius": 0.2, "material": "mirror"}]
  })");
}

std::string refusal(const json& scene) {
  return test::refusalOf([&] { parseScene(scene.dump(), "scene.json"); });
}

TEST(FlightZones, AtGreenTheThresholdsAreTheLevelsOverTheVisualCorrection) {
  json j = greenScene();
  j["hazard"] = {{"flight_zones", true}};
  const Scene s = parseScene(j.dump(), "scene.json");
  ASSERT_EQ(s.hazard.levels.size(), 3u);
  const double vcf = 0.91485;  // V(535 nm), the larger neighbour of 532 nm
  EXPECT_DOUBLE_EQ(s.hazard.levels[0].visual_correction, vcf);
  EXPECT_NEAR(s.hazard.levels[2].thresholdW_m2(), 5e-4 / vcf, 1e-18);
  // The thresholds follow the MPE in the outputs' order, and the floors scale from the lowest.
  const std::vector<double> t = s.hazard.thresholdsW_m2();
  ASSERT_EQ(t.size(), 4u);
  EXPECT_DOUBLE_EQ(t[0], s.hazard.mpe_w_m2);
  EXPECT_EQ(s.hazard.firstLevelThreshold(), 1u);
  EXPECT_DOUBLE_EQ(s.hazard.lowestHazardousW_m2(), 5e-4 / vcf);
  EXPECT_DOUBLE_EQ(s.hazard.negligibleW_m2(), 1e-3 * 5e-4 / vcf)
      << "a floor blind to the laser-free level would read its zone as none";

  j["hazard"] = {{"flight_zones", {{"visual_correction", false}}}};
  EXPECT_DOUBLE_EQ(parseScene(j.dump(), "scene.json").hazard.levels[0].thresholdW_m2(), 1.0);
  j["hazard"] = {{"flight_zones", false}};
  EXPECT_TRUE(parseScene(j.dump(), "scene.json").hazard.levels.empty());
}

TEST(FlightZones, AreRefusedWhereTheStandardDoesNotApplyThemWithTheReason) {
  json j = greenScene();
  j["hazard"] = {{"flight_zones", true}};
  j["laser"]["wavelength_nm"] = 1064;
  std::string m = refusal(j);
  EXPECT_NE(m.find("/hazard/flight_zones"), std::string::npos) << m;
  EXPECT_NE(m.find("400 nm to 700 nm"), std::string::npos) << m;
  EXPECT_NE(m.find("1064 nm"), std::string::npos) << m;

  j = greenScene();
  j["hazard"] = {{"flight_zones", true}, {"tissue", "skin"}};
  m = refusal(j);
  EXPECT_NE(m.find("pilot's eye"), std::string::npos) << m;
}

// The most pulses of a train at f that any window of T_w (its ends included) holds, counted by
// sliding the window over one period in fine steps: an independent count of ⌊f T_w⌋ + 1.
double mostPulsesInAWindow(double f_hz, double window_s) {
  const double period_s = 1.0 / f_hz;
  double most = 0.0;
  for (int s = 0; s <= 1000; ++s) {
    const double start = -period_s * s / 1000.0;  // the window starts up to a period early
    const double end = start + window_s;
    // Pulses at k / f, k ≥ 0 (start ≤ 0): those with start ≤ k / f ≤ end.
    double n = 0.0;
    for (int k = 0; k / f_hz <= end + 1e-12; ++k) n += k / f_hz >= start - 1e-12 ? 1.0 : 0.0;
    most = std::max(most, n);
  }
  return most;
}

TEST(FlightZones, APulsedLaserReachesEachLevelWhereItsBrightestQuarterSecondDoes) {
  json j = greenScene();
  j["hazard"] = {{"flight_zones", true},
                 {"levels", {{{"name", "site_glare"}, {"irradiance_w_m2", 2.0}}}}};
  j["laser"].erase("power_w");
  j["laser"]["exposure_s"] = 10.0;  // long enough to hold a pulse of the slowest train
  const double vcf = 0.91485;
  for (const double f_hz : {0.5, 1.0, 3.0, 4.0, 10.0, 1000.0}) {
    j["laser"]["pulse"] = {{"energy_j", 0.1}, {"duration_s", 1e-8}, {"repetition_rate_hz", f_hz}};
    const Scene s = parseScene(j.dump(), "scene.json");
    ASSERT_EQ(s.hazard.levels.size(), 4u);
    const ExposureLevel& sensitive = s.hazard.levels[0];
    // At the threshold, the brightest window's mean effective irradiance is the level itself:
    // the most pulses it holds, each E / f, over T_w.
    const double e = sensitive.thresholdW_m2();
    const double brightest_w_m2 = mostPulsesInAWindow(f_hz, 0.25) * (e / f_hz) / 0.25;
    EXPECT_NEAR(brightest_w_m2 * vcf, 1.0, 1e-9)
        << f_hz << " Hz: the sensitive zone's 100 µW/cm² over its 0.25 s";
    EXPECT_LE(sensitive.pulse_factor, 1.0)
        << f_hz << " Hz: never above the mean-irradiance reading, which a fast train approaches";
    if (f_hz <= 1.0) {
      // One flash per window: the Z136.6 pulsed form, 25 µJ/cm² = 0.25 J/m² per pulse.
      EXPECT_NEAR(s.hazard.pulseRadiantExposureJ_m2(e) * vcf, 0.25, 1e-12) << f_hz << " Hz";
    }
    EXPECT_DOUBLE_EQ(s.hazard.levels[3].thresholdW_m2(), 2.0)
        << "a site's own level is judged on the mean irradiance over the exposure";
  }
  // A single pulse puts all its light in one window: 25 µJ/cm² effective per pulse, whatever
  // its duration up to the window; a longer one is a steady light over every window it fills.
  j["laser"].erase("exposure_s");  // a single pulse's exposure is its duration
  j["laser"]["pulse"] = {{"energy_j", 0.1}, {"duration_s", 1e-8}};
  Scene s = parseScene(j.dump(), "scene.json");
  const double single_e = s.hazard.levels[0].thresholdW_m2();
  EXPECT_NEAR(s.hazard.pulseRadiantExposureJ_m2(single_e) * vcf, 0.25, 1e-12);
  EXPECT_DOUBLE_EQ(s.hazard.levels[0].pulse_factor, 0.25 / 1e-8);
  j["laser"]["pulse"] = {{"energy_j", 0.1}, {"duration_s", 1.0}};
  s = parseScene(j.dump(), "scene.json");
  EXPECT_DOUBLE_EQ(s.hazard.levels[0].pulse_factor, 1.0);
  EXPECT_DOUBLE_EQ(s.hazard.levels[0].thresholdW_m2(), 1.0 / vcf);
}

TEST(Levels, AnAnalystsOwnLevelIsPlainIrradianceUnlessCorrected) {
  json j = greenScene();
  j["laser"]["wavelength_nm"] = 1064;
  j["hazard"] = {{"levels", {{{"name", "camera_damage"}, {"irradiance_w_m2", 2.5}}}}};
  const Scene s = parseScene(j.dump(), "scene.json");
  ASSERT_EQ(s.hazard.levels.size(), 1u);
  EXPECT_DOUBLE_EQ(s.hazard.levels[0].thresholdW_m2(), 2.5) << "no correction outside 400-700 nm";
  EXPECT_EQ(s.hazard.levels[0].source, "the scene's own level");

  j["hazard"]["levels"][0]["visual_correction"] = true;
  std::string m = refusal(j);
  EXPECT_NE(m.find("/hazard/levels"), std::string::npos) << m;
  EXPECT_NE(m.find("visual_correction to false"), std::string::npos) << m;

  j = greenScene();
  j["hazard"] = {{"flight_zones", true},
                 {"levels", {{{"name", "critical_zone"}, {"irradiance_w_m2", 0.1}}}}};
  m = refusal(j);
  EXPECT_NE(m.find("named twice"), std::string::npos) << m;
  j["hazard"]["levels"][0]["name"] = "Glare level";
  m = refusal(j);
  EXPECT_NE(m.find("/hazard/levels/0/name"), std::string::npos) << m;
  j["hazard"]["levels"][0]["name"] = "aided";
  m = refusal(j);
  EXPECT_NE(m.find("MPE's own entries"), std::string::npos) << m;
}

// @p scene written to a folder of its own under the temporary directory and run there by
// `glint run` into its `out` (with @p more arguments): the folder, to read the outputs from and
// remove, and what the run said.
struct SceneRun {
  fs::path dir;
  test::Outcome outcome;
};
SceneRun runInFolder(const json& scene, const std::string& folder,
                     const std::vector<std::string>& more = {}) {
  const fs::path dir = fs::temp_directory_path() / folder;
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream(dir / "scene.json") << scene.dump();
  std::vector<std::string> args = {"run", (dir / "scene.json").string(), "-o",
                                   (dir / "out").string()};
  args.insert(args.end(), more.begin(), more.end());
  return {dir, test::glint(args)};
}

// A mirror ball of radius R in a uniform beam E0 sends I = ρ E0 R² / 4 into every direction
// it reflects into (away from the beam's forward cone), so a level of threshold T is reached out
// to √(I / T) from the virtual sources, which lie within R / 2 of the ball's centre. The reach
// per level (the lattice out to the far radius, the far field beyond) holds that, never short,
// and exceeds it by no more than its steps: the accuracy (a point counts hazardous at 0.99 T and
// is integrated to 1 %: 1 % in distance), one layer (5 %), and a cell's obliquity (the farthest
// layer plane of a cell's four rays is taken along its most oblique corner: at most
// √3 / √(1 + 2 (1 − 2/16)²) = 1.0887 at 16 rays an edge), with R for where the lit centre and
// the virtual sources lie.
TEST(LevelReach, AMirrorBallsLevelsReachTheClosedFormsDistanceNeverShort) {
  json j = greenScene();
  j["hazard"] = {{"flight_zones", true}};
  // With a site, the footprint at eye height and at a flight altitude of 50 m above the ground
  // (the ellipsoid at the site's height, through the ball's centre).
  j["site"] = {{"latitude_deg", 32.9}, {"longitude_deg", -106.4}, {"height_m", 1200.0}};
  j["reach"] = {{"face_cells", 16},
                {"layer_ratio", 1.05},
                {"footprint", {{"radius_m", 150}, {"pixel_m", 2}, {"flight_altitudes_m", {50}}}}};
  j["far_field"] = {{"face_pixels", 64}};
  const auto [dir, o] = runInFolder(j, "glint_level_reach");
  ASSERT_EQ(o.status, 0) << o.err;
  const json summary = json::parse(std::ifstream(dir / "out" / "summary.json"));
  const json& reach = summary.at("hazard_reach");
  const double radius_m = 0.2;
  const double e0_w_m2 = 500.0 / (kPi * 0.25);
  const double intensity_w_sr = 0.9 * e0_w_m2 * radius_m * radius_m / 4.0;
  int w = 0, h = 0;
  for (const char* name : {"sensitive_zone", "critical_zone", "laser_free_zone"}) {
    const json& level = reach.at("levels").at(name);
    const double threshold = level.at("threshold_w_m2").get<double>();
    const double closed_m = std::sqrt(intensity_w_sr / threshold);
    const double d = level.at("distance_m").get<double>();
    EXPECT_GE(d, closed_m * (1.0 - 0.005) - radius_m) << name << ": never short of the closed form";
    const double obliquity = std::sqrt(3.0 / (1.0 + 2.0 * 0.875 * 0.875));
    EXPECT_LE(d, closed_m * 1.01 * 1.05 * obliquity + radius_m) << name;
    EXPECT_TRUE(level.at("closed").get<bool>()) << name;
    // The map samples directions inside the cells: never beyond the summary's distance, and
    // within a cell's obliquity of it.
    const std::vector<float> map =
        readExrChannel((dir / "out" / "reach.exr").string(), std::string(name) + "_reach_m", w, h);
    ASSERT_FALSE(map.empty()) << name << ": reach.exr has its channel";
    const double map_max = *std::max_element(map.begin(), map.end());
    EXPECT_LE(map_max, d * (1.0 + 1e-6)) << name << ": the summary holds the map's farthest";
    EXPECT_GE(map_max, d / obliquity) << name;
  }
  EXPECT_NE(o.err.find("laser-free flight zone (50 nW/cm²): "), std::string::npos) << o.err;

  // The laser-free zone 50 m up: every point within √(I / T) − R / 2 of the centre reaches the
  // level (the virtual sources lie within R / 2 of it), at least in the half of the sky the
  // beam comes from; the footprint holds that disk's half, and is smaller than at eye height.
  // No pixel lies beyond the level's distance d (plus R for the lit centre) at that height but
  // for its corners: the area stays within the disk of radius √((d + R)² − 50²) + √2 pixels.
  const json& footprint = reach.at("footprint");
  ASSERT_EQ(footprint.at("altitudes").size(), 1u) << footprint.dump();
  const json& up = footprint.at("altitudes").at(0);
  EXPECT_EQ(up.at("reference"), "ground");
  const double threshold =
      reach.at("levels").at("laser_free_zone").at("threshold_w_m2").get<double>();
  const double inner_m = std::sqrt(intensity_w_sr / threshold) - radius_m / 2.0;
  const double disk_m2 = kPi * (inner_m * inner_m - 50.0 * 50.0);
  const double at_50_m2 = up.at("levels").at("laser_free_zone").at("area_m2").get<double>();
  EXPECT_GE(at_50_m2, 0.5 * disk_m2) << up.dump();
  EXPECT_LT(at_50_m2, footprint.at("levels").at("laser_free_zone").at("area_m2").get<double>())
      << footprint.dump();
  const double d_m = reach.at("levels").at("laser_free_zone").at("distance_m").get<double>();
  const double outer_m =
      std::sqrt((d_m + radius_m) * (d_m + radius_m) - 50.0 * 50.0) + std::sqrt(2.0) * 2.0;
  EXPECT_LE(at_50_m2, kPi * outer_m * outer_m) << up.dump();
  std::printf(
      "[ levels ] laser-free footprint at 50 m: %.4g m² (the half disk %.4g m², the outer "
      "disk %.4g m²)\n",
      at_50_m2, 0.5 * disk_m2, kPi * outer_m * outer_m);
  fs::remove_all(dir);
}

// A flat mirror square to a collimated Gaussian beam sends it back as a Beckmann lobe about the
// beam: on the axis f_r = ρ Ξ(0) / 4, Ξ(0) = 1 / (2π σ²), so the intensity is
// I = ρ P / (8π σ²) and a level of threshold T is reached out to √(I / T) along the axis, far
// beyond the lattice (the beam's 5 mm against a spread of 2σ). Each level's reach comes from the
// far field there: never short of the closed form, and within its tolerance (1 %) of it.
TEST(LevelReach, AFlatMirrorsLevelsReachTheLobesClosedFormAlongTheBeam) {
  const json scene = json::parse(R"({
    "laser": {"position": [-10, 0, 0], "direction": [1, 0, 0], "power_w": 1.0,
              "wavelength_nm": 532, "beam": {"profile": "gaussian", "w_m": 0.005}},
    "hazard": {"flight_zones": true},
    "materials": {"mirror": {"specular_reflectance": 0.9, "sigma": 0.03}},
    "objects": [{"shape": "disk", "center": [0, 0, 0], "normal": [-1, 0, 0], "radius": 0.05,
                 "material": "mirror"}],
    "reach": {"face_cells": 16, "layer_ratio": 1.05},
    "far_field": {"face_pixels": 64}
  })");
  const auto [dir, o] = runInFolder(scene, "glint_level_flat_mirror", {"--quiet"});
  ASSERT_EQ(o.status, 0) << o.err;
  const json summary = json::parse(std::ifstream(dir / "out" / "summary.json"));
  const double sigma = 0.03;
  const double intensity_w_sr = 0.9 * 1.0 / (8.0 * kPi * sigma * sigma);
  EXPECT_NEAR(summary.at("far_field").at("peak_intensity_w_sr").get<double>(), intensity_w_sr,
              1e-2 * intensity_w_sr)
      << "premise: the far field's peak is the lobe's";
  const json& reach = summary.at("hazard_reach");
  for (const char* name : {"sensitive_zone", "critical_zone", "laser_free_zone"}) {
    const json& level = reach.at("levels").at(name);
    const double closed_m = std::sqrt(intensity_w_sr / level.at("threshold_w_m2").get<double>());
    const double d = level.at("distance_m").get<double>();
    EXPECT_GE(d, closed_m) << name << ": never short";
    EXPECT_LE(d, 1.01 * closed_m) << name;
    EXPECT_EQ(level.at("from"), "far field") << name;
    EXPECT_TRUE(level.at("closed").get<bool>()) << name;
    EXPECT_LT(level.at("direction").at(0).get<double>(), -0.999) << name << ": back along the beam";
    std::printf("[ levels ] flat mirror, %s: %.5g m, closed form %.5g m (%+.2f %%)\n", name, d,
                closed_m, 100.0 * (d / closed_m - 1.0));
  }
  fs::remove_all(dir);
}

// A plane beside the ball: each level's channel in its map is the irradiance over the level's
// threshold, the summary's area counts its pixels at 1 or more, and the terminal gives a line
// per level; glint points gives a column per level.
TEST(Levels, APlanesMapAndThePointsTableCarryEachLevelsRatio) {
  json j = greenScene();
  j["hazard"] = {{"flight_zones", true}};
  j["far_field"] = {{"enabled", false}};
  j["planes"] = {{{"name", "side"},
                  {"origin", {-20, -20, -1}},
                  {"u_axis", {1, 0, 0}},
                  {"v_axis", {0, 1, 0}},
                  {"size_m", {40, 40}},
                  {"pixel_m", 0.5},
                  {"block_m", 8}}};
  const auto [dir, o] = runInFolder(j, "glint_level_plane");
  ASSERT_EQ(o.status, 0) << o.err;
  const json summary = json::parse(std::ifstream(dir / "out" / "summary.json"));
  const json& levels = summary.at("hazard").at("levels");
  int w = 0, h = 0;
  const std::string exr = (dir / "out" / "side.exr").string();
  const std::vector<float> e = readExrChannel(exr, "irradiance_w_m2", w, h);
  ASSERT_EQ(e.size(), 81u * 81u);
  for (const char* name : {"sensitive_zone", "critical_zone", "laser_free_zone"}) {
    const double threshold = levels.at(name).at("threshold_w_m2").get<double>();
    const std::vector<float> ratio = readExrChannel(exr, std::string(name) + "_ratio", w, h);
    ASSERT_EQ(ratio.size(), e.size()) << name;
    std::size_t reached = 0;
    for (std::size_t k = 0; k < e.size(); ++k) {
      const double expected = static_cast<double>(e[k]) / threshold;
      EXPECT_NEAR(static_cast<double>(ratio[k]), expected, 1e-6 * expected + 1e-30) << name << k;
      reached += ratio[k] >= 1.0F ? 1 : 0;
    }
    const json& plane = summary.at("planes").at(0).at("levels").at(name);
    EXPECT_DOUBLE_EQ(plane.at("area_m2").get<double>(), 0.25 * static_cast<double>(reached))
        << name;
    EXPECT_GT(reached, 0u) << name << ": the ball's glint reaches every level on this plane";
  }
  EXPECT_NE(o.err.find("critical flight zone (5 µW/cm²): 0.05465 W/m²"), std::string::npos)
      << o.err;

  std::ofstream(dir / "points.csv") << "x,y,z\n-5,0,0\n0,5,0\n";
  const test::Outcome p = test::glint(
      {"points", (dir / "scene.json").string(), "--points", (dir / "points.csv").string()});
  ASSERT_EQ(p.status, 0) << p.err;
  std::istringstream table(p.out);
  std::string header, row;
  std::getline(table, header);
  EXPECT_NE(header.find(",sensitive_zone_ratio,critical_zone_ratio,laser_free_zone_ratio"),
            std::string::npos)
      << header;
  std::getline(table, row);
  std::vector<double> cells;
  std::istringstream cols(row);
  for (std::string cell; std::getline(cols, cell, ',');) cells.push_back(std::stod(cell));
  ASSERT_EQ(cells.size(), 11u) << row;
  const double laser_free = levels.at("laser_free_zone").at("threshold_w_m2").get<double>();
  EXPECT_NEAR(cells[10], cells[3] / laser_free, 1e-12 * cells[10]) << row;
  fs::remove_all(dir);
}

// examples/pilot_crossing.json: nothing moves but the observers, so an observer's history is the
// static field along its path, E(p0 + v t). Each observer sits on the reflected beam's axis at
// t = 0 and crosses the spot, where E(t) rises and falls once: the time above a level is the
// span between the two instants where E crosses it, found here by bisection on the static field
// to 1 µs. The engagement's time sampling reads it from its samples, within its tolerance of the
// crossing's length (a percent) and two of its finest steps.
TEST(Levels, ThePilotsTimeAboveEachLevelIsThePathsLengthAboveItOverItsSpeed) {
  const std::string scene_file = std::string(GLINT_EXAMPLES_DIR) + "/pilot_crossing.json";
  const std::string points_file = std::string(GLINT_EXAMPLES_DIR) + "/pilot_crossing_points.csv";
  const test::Outcome o = test::glint({"points", scene_file, "--points", points_file});
  ASSERT_EQ(o.status, 0) << o.err;
  std::istringstream table(o.out);
  std::string line;
  std::getline(table, line);
  std::vector<std::string> names;
  std::istringstream header(line);
  for (std::string cell; std::getline(header, cell, ',');) names.push_back(cell);
  const auto column = [&](const std::string& name) {
    return static_cast<std::size_t>(std::find(names.begin(), names.end(), name) - names.begin());
  };
  std::vector<std::vector<double>> rows;
  while (std::getline(table, line)) {
    std::vector<double> row;
    std::istringstream cols(line);
    for (std::string cell; std::getline(cols, cell, ',');) row.push_back(std::stod(cell));
    rows.push_back(row);
  }
  ASSERT_EQ(rows.size(), 6u);

  const Scene scene = loadScene(scene_file);
  const FacetIntegrator fi(buildTarget(scene), scene.laser, scene.accuracy);
  IntegratorWorkspace ws;
  const Vec3 v = scene.engagement->motion.observer_velocity_m_s;
  double worst_s = 0.0;
  for (std::size_t r = 0; r < rows.size(); ++r) {
    const Vec3 p0(rows[r][0], rows[r][1], rows[r][2]);
    const auto e = [&](double t) { return fi.adaptive(p0 + t * v, ws).irradiance_w_m2; };
    // The instant in [inside, outside] where E falls through the threshold.
    const auto crossing = [&](double threshold, double inside, double outside) {
      while (std::abs(outside - inside) > 1e-6) {
        const double mid = 0.5 * (inside + outside);
        (e(mid) >= threshold ? inside : outside) = mid;
      }
      return 0.5 * (inside + outside);
    };
    // The spot is at most 2 × 0.002 × 8 km wide: the crossing lies within a second of t = 0.
    ASSERT_LT(std::max(e(-1.0), e(1.0)), scene.hazard.levels[2].thresholdW_m2()) << "row " << r;
    for (const ExposureLevel& l : scene.hazard.levels) {
      const double threshold = l.thresholdW_m2();
      const double above_s = e(0.0) >= threshold
                                 ? crossing(threshold, 0.0, 1.0) - crossing(threshold, 0.0, -1.0)
                                 : 0.0;
      const double reported = rows[r].at(column("time_above_" + l.name + "_s"));
      EXPECT_NEAR(reported, above_s, 0.01 * above_s + 2e-3) << "row " << r << ", " << l.name;
      worst_s = std::max(worst_s, std::abs(reported - above_s));
    }
    EXPECT_LT(rows[r].at(column("hazard_ratio")), 1.0) << "eye-safe everywhere, row " << r;
  }
  std::printf("[ levels ] pilot crossing: time above a level within %.3g s of the static field's\n",
              worst_s);
  // What the example's description says: the sensitive zone only at 250 m, the laser-free zone
  // at 8 km.
  EXPECT_GT(rows[0].at(column("time_above_sensitive_zone_s")), 0.0);
  EXPECT_EQ(rows[1].at(column("time_above_sensitive_zone_s")), 0.0);
  EXPECT_GT(rows[5].at(column("time_above_laser_free_zone_s")), 1.0);
}

}  // namespace
}  // namespace glint
