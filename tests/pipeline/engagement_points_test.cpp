// `glint points` over an engagement: the table's columns, the time series, and the commands
// that refuse an engagement they cannot integrate.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "export/exr_map.h"
#include "export/lattice_vdb.h"
#include "observers/field.h"
#include "support/cli.h"
#include "support/files.h"

namespace glint {
namespace {

namespace fs = std::filesystem;
using test::glint;

// The turning mirror of exposure_test.cpp: a 0.3 m disk turning at 20 deg/s in a 1 kW beam.
constexpr const char* kScene = R"({
  "laser": {"position": [-100, 0, 0], "direction": [1, 0, 0], "power_w": 1000,
            "wavelength_nm": 1064, "exposure_s": 10, "beam": {"profile": "gaussian", "w_m": 1.0}},
  "materials": {"m": {"specular_reflectance": 0.9, "sigma": 0.002}},
  "objects": [{"shape": "disk", "center": [0, 0, 0], "normal": [-1, 0, 0], "radius": 0.3,
               "material": "m", "segments": 8}],
  "engagement": {"start_s": -0.5, "end_s": 0.5, "target": {"turn_deg_s": [20, 0, 0]}}
})";

// The turning mirror's scene with more top-level keys (@p keys: `"name": value, ...`).
std::string sceneWith(const std::string& keys) {
  std::string scene = kScene;
  scene.replace(scene.rfind('}'), 1, ",\n  " + keys + "}");
  return scene;
}

// A wall 50 m back across the glint's path, 1 m pixels.
constexpr const char* kWall = R"("planes": [{"name": "wall", "origin": [-50, -20, -1],
  "u_axis": [0, 1, 0], "v_axis": [0, 0, 1], "size_m": [40, 2], "pixel_m": 1.0, "block_m": 4}])";

struct Folder {
  fs::path dir;
  explicit Folder(const std::string& name) : dir(fs::temp_directory_path() / name) {
    fs::remove_all(dir);
    fs::create_directories(dir);
  }
  ~Folder() { fs::remove_all(dir); }
  fs::path write(const std::string& name, const std::string& text) const {
    std::ofstream(dir / name) << text;
    return dir / name;
  }
};

std::vector<std::vector<std::string>> csv(const std::string& text) {
  std::vector<std::vector<std::string>> rows;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    std::vector<std::string> row;
    std::istringstream cells(line);
    for (std::string cell; std::getline(cells, cell, ',');) row.push_back(cell);
    rows.push_back(row);
  }
  return rows;
}

// The table holds each observer's exposure, and the time series the samples it was summed
// from: trapezoids through them give the table's exposure, and the peak is their largest.
TEST(EngagementPoints, TheTableAndTheTimeSeriesTellTheSameExposure) {
  const Folder f("glint_engagement_points");
  const fs::path scene = f.write("scene.json", kScene);
  const fs::path points = f.write("points.csv", "x,y,z\n-50,-6,0.5\n-50,0,0.5\n30,0,0\n");
  const test::Outcome o =
      glint({"points", scene.string(), "--points", points.string(), "--out",
             (f.dir / "out.csv").string(), "--time-series", (f.dir / "series.csv").string()});
  ASSERT_EQ(o.status, 0) << o.err;
  const auto table = csv(test::readFile(f.dir / "out.csv"));
  ASSERT_EQ(table.size(), 4u);
  const std::vector<std::string> header = table[0];
  std::map<std::string, std::size_t> column;
  for (std::size_t i = 0; i < header.size(); ++i) column[header[i]] = i;
  for (const char* name : {"exposure_j_m2", "peak_irradiance_w_m2", "time_above_mpe_s",
                           "hazard_ratio", "worst_window_s", "stare_hazard_ratio", "converged"}) {
    ASSERT_TRUE(column.count(name)) << "no column " << name;
  }
  const auto series = csv(test::readFile(f.dir / "series.csv"));
  ASSERT_EQ(series[0],
            (std::vector<std::string>{"observer", "time_s", "irradiance_w_m2", "pulse"}));
  for (int observer = 1; observer <= 3; ++observer) {
    std::vector<double> t, e;
    for (std::size_t i = 1; i < series.size(); ++i) {
      if (std::stoi(series[i][0]) != observer) continue;
      t.push_back(std::stod(series[i][1]));
      e.push_back(std::stod(series[i][2]));
    }
    ASSERT_GE(t.size(), 2u);
    EXPECT_EQ(t.front(), -0.5);
    EXPECT_EQ(t.back(), 0.5);
    double exposure = 0.0, peak = 0.0;
    for (std::size_t i = 1; i < t.size(); ++i) {
      ASSERT_GT(t[i], t[i - 1]) << "times increase";
      exposure += 0.5 * (e[i] + e[i - 1]) * (t[i] - t[i - 1]);
    }
    for (double v : e) peak = std::max(peak, v);
    const std::vector<std::string>& row = table[static_cast<std::size_t>(observer)];
    EXPECT_NEAR(std::stod(row[column["exposure_j_m2"]]), exposure, 1e-12 + 1e-12 * exposure)
        << "observer " << observer;
    EXPECT_EQ(std::stod(row[column["peak_irradiance_w_m2"]]), peak) << "observer " << observer;
    EXPECT_EQ(std::stoul(row[column["time_samples"]]), t.size());
  }
  // The glint crosses the first two in about 13 ms: above the 10 s stare's MPE of 50 W/m² at
  // its peak, far below the MPE of its own few milliseconds.
  const std::vector<std::string>& lit = table[1];
  EXPECT_GT(std::stod(lit[column["stare_hazard_ratio"]]), 1.0);
  EXPECT_LT(std::stod(lit[column["hazard_ratio"]]), 0.3);
  EXPECT_LT(std::stod(lit[column["worst_window_s"]]), 0.05);
  EXPECT_EQ(std::stod(table[3][column["exposure_j_m2"]]), 0.0) << "behind the mirror";
  EXPECT_NE(o.err.find("judged pose by pose as a 10 s stare"), std::string::npos) << o.err;
}

// examples/missile_crossing.json: the fin's glint passes an observer under the flight path in
// about 3.5 ms. Its peak, stared at for 10 s, would be hazardous; the worst window, the glint's
// own few milliseconds, collects less than the MPE for them.
TEST(EngagementPoints, TheCrossingMissilesStareAndEngagementVerdictsDiffer) {
  const Folder f("glint_engagement_missile");
  const fs::path points = f.write("points.csv", "x,y,z\n0,-2.5,1.7\n100,-2.5,1.7\n");
  const test::Outcome o =
      glint({"points", std::string(GLINT_EXAMPLES_DIR) + "/missile_crossing.json", "--points",
             points.string(), "--out", (f.dir / "out.csv").string()});
  ASSERT_EQ(o.status, 0) << o.err;
  const auto table = csv(test::readFile(f.dir / "out.csv"));
  std::map<std::string, std::size_t> column;
  for (std::size_t i = 0; i < table[0].size(); ++i) column[table[0][i]] = i;
  for (std::size_t row = 1; row < table.size(); ++row) {
    const auto value = [&](const char* name) { return std::stod(table[row][column[name]]); };
    EXPECT_GT(value("stare_hazard_ratio"), 2.0) << "row " << row;
    EXPECT_LT(value("hazard_ratio"), 1.0) << "row " << row;
    EXPECT_LT(value("worst_window_s"), 0.01) << "row " << row;
    EXPECT_GT(value("time_above_mpe_s"), 0.0) << "row " << row;
    EXPECT_EQ(value("converged"), 1.0) << "row " << row;
  }
}

// The observers' first samples alone (4 097 each here) would outgrow the budget: refused before
// the target is built, naming what to change.
TEST(EngagementPoints, ObserversWhoseFirstSamplesOutgrowTheBudgetAreRefusedBeforeTheWork) {
  const Folder f("glint_engagement_memory");
  std::string scene = kScene;
  scene.replace(scene.find(R"("target": {"turn_deg_s")"), 0,
                R"("time": {"initial_intervals": 4096}, )");
  const fs::path scene_path = f.write("scene.json", scene);
  std::string points = "x,y,z\n";
  for (int i = 0; i < 20000; ++i) points += "-50," + std::to_string(i * 1e-3) + ",0.5\n";
  const fs::path points_path = f.write("points.csv", points);
  const test::Outcome o = glint({"points", scene_path.string(), "--points", points_path.string(),
                                 "--out", (f.dir / "out.csv").string(), "--memory", "256M"});
  EXPECT_EQ(o.status, 2) << o.err;
  EXPECT_NE(o.err.find("20000 observers' first time samples"), std::string::npos) << o.err;
  EXPECT_NE(o.err.find("engagement.time.initial_intervals"), std::string::npos) << o.err;
  EXPECT_FALSE(fs::exists(f.dir / "out.csv"));
}

// An engagement's maps are arrays over the box's whole lattice, not an adaptive field's blocks:
// a box whose maps alone pass the budget is refused before the target is built (its adaptive
// field would have been allowed: 1 500 bytes per 16³ block, 0.05 MB here).
TEST(EngagementRun, ABoxWhoseMapsOutgrowTheBudgetIsRefusedBeforeTheWork) {
  const Folder f("glint_engagement_box_memory");
  const std::string scene =
      sceneWith(R"("observers": {"min": [-60, -10, -5], "max": [-40, 10, 5], "voxel_m": 0.1})");
  const test::Outcome o = glint({"run", f.write("scene.json", scene).string(), "-o",
                                 (f.dir / "out").string(), "--memory", "100M"});
  EXPECT_EQ(o.status, 2) << o.err;
  // The maps themselves (40 bytes a point) and as much again for engagement.vdb's grids, a
  // float of each of its ten channels a point.
  EXPECT_NE(o.err.find("observer box (209×209×113 lattice points at 0.1 m, dense, 188 MB of it to "
                       "write engagement.vdb) needs at least 377 MB"),
            std::string::npos)
      << o.err;
  EXPECT_FALSE(fs::exists(f.dir / "out"));
}

// A region's maps of glint run over an engagement, per lattice point.
struct RegionMaps {
  const std::vector<float>& status;
  const std::vector<float>& exposure_j_m2;
  const std::vector<float>& hazard_ratio;
};

// The maps against glint points at up to @p per_kind of the region's dark points and of its
// integrated ones (every @p stride-th point, placed by @p position): a point the bound proved
// dark reads at most the floor at every sample, and an integrated point's map values are the
// table's (floats of its doubles).
void expectMapsAreGlintPoints(const Folder& f, const fs::path& scene, const RegionMaps& maps,
                              int per_kind, std::size_t stride,
                              const std::function<Vec3(std::size_t)>& position) {
  std::string points = "x,y,z\n";
  std::vector<std::size_t> chosen;
  int dark_chosen = 0, lit_chosen = 0;
  for (std::size_t p = 0; p < maps.status.size(); p += stride) {
    int& kind = maps.status[p] == 3.0f ? dark_chosen : lit_chosen;
    if (kind == per_kind) continue;
    ++kind;
    chosen.push_back(p);
    const Vec3 x = position(p);
    points += std::to_string(x.x) + "," + std::to_string(x.y) + "," + std::to_string(x.z) + "\n";
  }
  EXPECT_GT(dark_chosen, 0);
  EXPECT_GT(lit_chosen, 0);
  const test::Outcome o =
      glint({"points", scene.string(), "--points", f.write("points.csv", points).string(), "--out",
             (f.dir / "table.csv").string()});
  ASSERT_EQ(o.status, 0) << o.err;
  const auto table = csv(test::readFile(f.dir / "table.csv"));
  std::map<std::string, std::size_t> column;
  for (std::size_t c = 0; c < table[0].size(); ++c) column[table[0][c]] = c;
  for (std::size_t r = 0; r < chosen.size(); ++r) {
    const std::size_t p = chosen[r];
    const std::vector<std::string>& row = table[r + 1];
    const double h = std::stod(row[column["exposure_j_m2"]]);
    if (maps.status[p] == 3.0f) {
      // Dark by the bound: below the floor (a thousandth of the 50 W/m² MPE) at every instant.
      EXPECT_LE(std::stod(row[column["peak_irradiance_w_m2"]]), 0.05) << "point " << p;
      EXPECT_EQ(maps.exposure_j_m2[p], 0.0f) << "point " << p;
    } else {
      EXPECT_EQ(maps.status[p], 1.0f) << "point " << p;
      EXPECT_NEAR(maps.exposure_j_m2[p], h, 1e-6 * h + 1e-30) << "point " << p;
      EXPECT_NEAR(maps.hazard_ratio[p], std::stod(row[column["hazard_ratio"]]), 1e-6)
          << "point " << p;
    }
  }
}

// glint run over an engagement maps its planes: a point the bound proves dark over the whole
// span is dark at every instant glint points samples, and an integrated point's map values are
// the table's for the same point.
TEST(EngagementRun, APlanesMapsAreWhatGlintPointsGivesAtItsPoints) {
  const Folder f("glint_engagement_run");
  const std::string scene = sceneWith(kWall);
  const fs::path scene_path = f.write("scene.json", scene);
  const test::Outcome run = glint({"run", scene_path.string(), "-o", (f.dir / "out").string()});
  ASSERT_EQ(run.status, 0) << run.err;
  const auto summary = nlohmann::json::parse(std::ifstream(f.dir / "out" / "summary.json"));
  EXPECT_EQ(summary["files"], (nlohmann::json{"summary.json", "wall.exr"}));
  ASSERT_TRUE(summary.contains("engagement"));
  const nlohmann::json& wall = summary["planes"][0];
  EXPECT_GT(wall["points"]["integrated"].get<std::int64_t>(), 0);
  EXPECT_GT(wall["points"]["dark_by_bound"].get<std::int64_t>(), 0)
      << "the glint's path is a band of the wall";
  int width = 0, height = 0;
  const std::string exr = (f.dir / "out" / "wall.exr").string();
  const std::vector<float> status = readExrChannel(exr, "status", width, height);
  const std::vector<float> exposure = readExrChannel(exr, "exposure_j_m2", width, height);
  const std::vector<float> ratio = readExrChannel(exr, "hazard_ratio", width, height);
  expectMapsAreGlintPoints(f, scene_path, {status, exposure, ratio}, 15, 1, [&](std::size_t p) {
    const auto i = static_cast<double>(p % static_cast<std::size_t>(width));
    const auto j = static_cast<double>(p / static_cast<std::size_t>(width));
    return Vec3(-50.0, -20.0 + i, -1.0 + j);
  });
  EXPECT_NE(run.err.find("plane wall:"), std::string::npos) << run.err;
}

// Over a box, engagement.vdb holds at each lattice point what glint points gives there, the
// points the bound proves dark read below the floor at every sample, and the summary's hazardous
// volume counts the voxels whose worst window reaches the MPE.
TEST(EngagementRun, ABoxsGridsAreWhatGlintPointsGivesAtItsPoints) {
  const Folder f("glint_engagement_box");
  // Across the glint's path 50 m back, and above it: some points dark by the bound.
  const std::string scene = sceneWith(
      R"("observers": {"min": [-50.5, -2, -1], "max": [-49.5, 2, 5], "voxel_m": 0.5, "block_m": 2})");
  const fs::path scene_path = f.write("scene.json", scene);
  const test::Outcome run = glint({"run", scene_path.string(), "-o", (f.dir / "out").string()});
  ASSERT_EQ(run.status, 0) << run.err;
  const auto summary = nlohmann::json::parse(std::ifstream(f.dir / "out" / "summary.json"));
  EXPECT_EQ(summary["files"], (nlohmann::json{"summary.json", "engagement.vdb"}));
  const nlohmann::json& box = summary.at("box");
  FieldSpec spec;
  spec.min_m = Vec3(-50.5, -2, -1);
  spec.max_m = Vec3(-49.5, 2, 5);
  spec.voxel_m = 0.5;
  spec.block_voxels = 4;
  const std::array<int, 3> n = spec.nodes();
  ASSERT_EQ(box.at("lattice"), (nlohmann::json{n[0], n[1], n[2]}));
  const std::string vdb = (f.dir / "out" / "engagement.vdb").string();
  const std::vector<float> status = readLatticeVdb(vdb, "status", spec);
  const std::vector<float> exposure = readLatticeVdb(vdb, "exposure_j_m2", spec);
  const std::vector<float> ratio = readLatticeVdb(vdb, "hazard_ratio", spec);
  const std::int64_t integrated = box.at("points").at("integrated").get<std::int64_t>();
  EXPECT_GT(integrated, 0);
  EXPECT_LT(integrated, static_cast<std::int64_t>(status.size())) << "some points are dark";
  std::int64_t hazardous = 0;
  for (float r : ratio) hazardous += r >= 1.0f ? 1 : 0;
  EXPECT_GT(hazardous, 0);
  // Float ratios a rounding from 1 may count apart from the doubles the summary counted.
  EXPECT_NEAR(box.at("hazard_volume_m3").get<double>(), static_cast<double>(hazardous) * 0.125,
              0.125);
  expectMapsAreGlintPoints(f, scene_path, {status, exposure, ratio}, 10, 7, [&](std::size_t p) {
    const std::size_t row = static_cast<std::size_t>(n[0]);
    const std::size_t layer = row * static_cast<std::size_t>(n[1]);
    return spec.position(static_cast<int>(p % row), static_cast<int>(p / row % n[1]),
                         static_cast<int>(p / layer));
  });
}

// tests/data/engagement_mpi.json's mirror turning at @p turn_deg_s over [@p start_s, @p end_s]
// in a @p power_w beam, with the observer regions @p regions (JSON keys `observers` or
// `planes`; none: only the scene).
std::string turningMirror(double turn_deg_s, double start_s, double end_s, double power_w,
                          const nlohmann::json& regions = nlohmann::json::object()) {
  nlohmann::json scene =
      nlohmann::json::parse(test::readFile(fs::path(GLINT_TEST_DATA_DIR) / "engagement_mpi.json"));
  scene["engagement"]["start_s"] = start_s;
  scene["engagement"]["end_s"] = end_s;
  scene["engagement"]["target"]["turn_deg_s"] = {turn_deg_s, 0, 0};
  scene["laser"]["power_w"] = power_w;
  scene.erase("observers");
  scene.erase("planes");
  scene.update(regions);
  return scene.dump(2);
}

// The table's columns by name.
std::map<std::string, std::size_t> columnsOf(const std::vector<std::vector<std::string>>& table) {
  std::map<std::string, std::size_t> column;
  for (std::size_t i = 0; i < table[0].size(); ++i) column[table[0][i]] = i;
  return column;
}

// The turning mirror of engagement_mpi.json turning at 3600°/s for 10 s: its reflection turns
// at twice that, so its glint crosses an observer at (−50, 0, 0) ten times a second, 101 times
// from −5 s to 5 s (half a glint at each end). Each crossing's worst window (77 µs, 0.024 J/m²)
// is a third of its MPE, 90 t^0.75 J/m² at 1064 nm: the windows alone say 0.33. Read as the
// standard reads a pulse, all of a crossing's energy against the MPE for its time above half
// its peak, it is 0.42. To the eye it is a train of 101 pulses, and ANSI Z136.1-2014's rule 3
// holds each to the single-pulse MPE times C_P = 101^-0.25: 0.42 × 101^0.25 = 1.33, hazardous
// (1.04 by the windows alone). The two half crossings at the ends count for less than whole
// ones (glint weighs each pulse by its share of the strongest to the fourth power), so the
// count that sets C_P lies between 99 and 101. The expected ratio is worked here from the
// crossings the time series shows, the crossing's energy and half-peak time, and the row's
// formula.
TEST(EngagementPoints, ATurningTargetsGlintsAreJudgedAsAPulseTrain) {
  const Folder f("glint_engagement_train");
  const fs::path scene = f.write("scene.json", turningMirror(3600.0, -5.0, 5.0, 1000.0));
  const fs::path points = f.write("points.csv", "x,y,z\n-50,0,0\n");
  const test::Outcome o =
      glint({"points", scene.string(), "--points", points.string(), "--out",
             (f.dir / "out.csv").string(), "--time-series", (f.dir / "series.csv").string()});
  ASSERT_EQ(o.status, 0) << o.err;
  const auto table = csv(test::readFile(f.dir / "out.csv"));
  ASSERT_EQ(table.size(), 2u);
  std::map<std::string, std::size_t> column = columnsOf(table);
  for (const char* name : {"hazard_rule", "pulses", "worst_window_ratio", "pulse_train_ratio",
                           "pulse_reduction", "pulse_exposure_j_m2"}) {
    ASSERT_TRUE(column.count(name)) << "no column " << name;
  }
  const auto value = [&](const char* name) { return std::stod(table[1][column[name]]); };
  // The crossings: where the irradiance rises above the floor, a thousandth of the 50 W/m²
  // MPE, and the energy of the one about t = 0 by trapezoids through its samples.
  const auto series = csv(test::readFile(f.dir / "series.csv"));
  ASSERT_EQ(series[0],
            (std::vector<std::string>{"observer", "time_s", "irradiance_w_m2", "pulse"}));
  const double floor_w_m2 = 0.05;
  int crossings = 0, last_pulse = 0;
  double previous_e = 0.0, previous_t = 0.0, crossing_at_0_j_m2 = 0.0;
  std::vector<std::array<double, 2>> crossing_at_0;  // (t, E) of its samples
  for (std::size_t i = 1; i < series.size(); ++i) {
    const double t = std::stod(series[i][1]), e = std::stod(series[i][2]);
    crossings += (i == 1 || previous_e <= floor_w_m2) && e > floor_w_m2 ? 1 : 0;
    if (std::abs(t) < 0.05) crossing_at_0.push_back({t, e});
    if (i > 1 && std::abs(t) < 0.05 && std::abs(previous_t) < 0.05)
      crossing_at_0_j_m2 += 0.5 * (e + previous_e) * (t - previous_t);
    const int pulse = std::stoi(series[i][3]);
    if (e > 2.0 * floor_w_m2) {
      EXPECT_GT(pulse, 0) << "t = " << t << ": in a crossing";
    }
    if (pulse > 0) {
      EXPECT_GE(pulse, last_pulse) << "t = " << t;
      last_pulse = pulse;
    }
    previous_e = e;
    previous_t = t;
  }
  EXPECT_EQ(crossings, 101);
  EXPECT_EQ(last_pulse, 101) << "the series numbers the pulses counted";
  EXPECT_EQ(value("pulses"), 101.0);
  EXPECT_EQ(value("hazard_rule"), 3.0);
  const double window_j_m2 = value("worst_window_exposure_j_m2"),
               window_s = value("worst_window_s");
  const double window_mpe_j_m2 = 90.0 * std::pow(window_s, 0.75);  // 1064 nm, 13 µs to 10 s
  EXPECT_NEAR(value("worst_window_mpe_j_m2"), window_mpe_j_m2, 1e-12 * window_mpe_j_m2);
  EXPECT_NEAR(window_s, 77e-6, 2e-6);
  EXPECT_LT(window_j_m2 / window_mpe_j_m2, 0.35) << "the windows alone";
  // The crossing's time at or above half its peak, the samples joined by straight lines.
  double peak_at_0 = 0.0, half_peak_s = 0.0;
  for (const auto& [t, e] : crossing_at_0) peak_at_0 = std::max(peak_at_0, e);
  for (std::size_t i = 1; i < crossing_at_0.size(); ++i) {
    const double t0 = crossing_at_0[i - 1][0], e0 = crossing_at_0[i - 1][1];
    const double t1 = crossing_at_0[i][0], e1 = crossing_at_0[i][1], half = 0.5 * peak_at_0;
    if (e0 >= half && e1 >= half)
      half_peak_s += t1 - t0;
    else if ((e0 >= half) != (e1 >= half)) {
      const double cross = (half - e0) / (e1 - e0);
      half_peak_s += (e0 >= half ? cross : 1.0 - cross) * (t1 - t0);
    }
  }
  const double half_peak_ratio = crossing_at_0_j_m2 / (90.0 * std::pow(half_peak_s, 0.75));
  EXPECT_GT(half_peak_ratio, window_j_m2 / window_mpe_j_m2) << "a smooth crossing";
  EXPECT_NEAR(value("pulse_ratio"), half_peak_ratio, 2e-3 * half_peak_ratio);
  EXPECT_EQ(value("pulse_by_half_peak"), 1.0);
  const double effective = value("effective_pulses");
  EXPECT_GE(effective, 99.0);
  EXPECT_LE(effective, 101.0);
  EXPECT_NEAR(value("pulse_reduction"), std::pow(effective, -0.25), 1e-12);
  const double want = half_peak_ratio * std::pow(effective, 0.25);
  EXPECT_GT(want, 1.3);
  // The crossing that sets the ratio is another than the one at 0, whose samples differ.
  EXPECT_NEAR(value("hazard_ratio"), want, 2e-3 * want);
  EXPECT_EQ(value("hazard_ratio"), value("pulse_train_ratio"));
  // Every crossing delivers the same light: the one that sets the ratio as much as the one at 0.
  EXPECT_NEAR(value("pulse_exposure_j_m2"), crossing_at_0_j_m2, 2e-3 * crossing_at_0_j_m2);
  char said[160];
  std::snprintf(said, sizeof said,
                "hazard ratio %.3g by rule 3, a train of 101 pulses, %.4g as strong as its "
                "strongest: C_P %.3g",
                value("hazard_ratio"), effective, value("pulse_reduction"));
  EXPECT_NE(o.err.find(said), std::string::npos) << o.err;
}

// A 2 × 2 plane where the turning mirror's glint crosses it 5 times (the mirror at 3600°/s in
// a 2.5 kW beam from −0.25 to 0.25 s): each crossing's worst window is 0.82 of its MPE (its
// half-peak reading more), the train of 5 makes it at least 0.82 × 5^0.25 = 1.23, while the
// windows alone stay below 1. glint run's map holds at each point the verdict
// glint points gives there, rule 3 with its 5 pulses, and the summary and the terminal say the
// train sets it. A study of the same engagement counts those points hazardous: its coverage
// follows the train too.
TEST(EngagementRun, ATrainOfGlintsSetsThePlanesMapsAndTheStudysCoverage) {
  const Folder f("glint_engagement_train_map");
  const nlohmann::json plane = nlohmann::json::parse(R"({"planes": [{"name": "eye",
    "origin": [-50, -0.1, -0.1], "u_axis": [0, 1, 0], "v_axis": [0, 0, 1], "size_m": [0.1, 0.1],
    "pixel_m": 0.1, "block_m": 0.1}]})");
  const fs::path scene = f.write("scene.json", turningMirror(3600.0, -0.25, 0.25, 2500.0, plane));
  const test::Outcome run = glint({"run", scene.string(), "-o", (f.dir / "out").string()});
  ASSERT_EQ(run.status, 0) << run.err;
  int width = 0, height = 0;
  const std::string exr = (f.dir / "out" / "eye.exr").string();
  const std::vector<float> ratio = readExrChannel(exr, "hazard_ratio", width, height);
  const std::vector<float> rule = readExrChannel(exr, "hazard_rule", width, height);
  const std::vector<float> pulses = readExrChannel(exr, "pulses", width, height);
  ASSERT_EQ(ratio.size(), 4u);
  std::string points = "x,y,z\n";
  for (int j = 0; j < 2; ++j)
    for (int i = 0; i < 2; ++i)
      points +=
          "-50," + std::to_string(-0.1 + 0.1 * i) + "," + std::to_string(-0.1 + 0.1 * j) + "\n";
  const test::Outcome o =
      glint({"points", scene.string(), "--points", f.write("points.csv", points).string(), "--out",
             (f.dir / "table.csv").string()});
  ASSERT_EQ(o.status, 0) << o.err;
  const auto table = csv(test::readFile(f.dir / "table.csv"));
  std::map<std::string, std::size_t> column = columnsOf(table);
  for (std::size_t p = 0; p < 4; ++p) {
    const auto value = [&](const char* name) { return std::stod(table[p + 1][column[name]]); };
    EXPECT_NEAR(ratio[p], value("hazard_ratio"), 1e-6) << "point " << p;
    EXPECT_GE(ratio[p], 1.0f) << "point " << p;
    EXPECT_LT(value("worst_window_ratio"), 1.0) << "point " << p << ": hazardous by the train";
    EXPECT_EQ(rule[p], 3.0f) << "point " << p;
    EXPECT_EQ(pulses[p], 5.0f) << "point " << p;
    EXPECT_EQ(value("pulses"), 5.0) << "point " << p;
  }
  const auto summary = nlohmann::json::parse(std::ifstream(f.dir / "out" / "summary.json"));
  const nlohmann::json& eye = summary.at("planes").at(0);
  EXPECT_EQ(eye.at("points").at("decided_by_pulse_train"), 4);
  EXPECT_NEAR(eye.at("hazardous_area_m2").get<double>(), 0.04, 1e-12);
  EXPECT_EQ(eye.at("worst").at("hazard_rule"), "rule 3");
  EXPECT_EQ(eye.at("worst").at("pulse_train").at("pulses"), 5);
  EXPECT_NE(eye.at("worst").at("decided_by").get<std::string>().find("a train of 5 pulses"),
            std::string::npos);
  EXPECT_NE(run.err.find("by rule 3, a train of 5 pulses"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("the pulse train sets the verdict at 4 points"), std::string::npos)
      << run.err;

  // A study of one scenario (pointing jitter too small to move the glint), hazardous at every
  // point by the train alone.
  const fs::path study = f.write("study.json", R"({"scene": "scene.json",
    "pointing_jitter": {"sigma_rad": 1e-6, "samples": 1, "seed": 1}})");
  const test::Outcome batch = glint({"batch", study.string(), "-o", (f.dir / "study").string()});
  ASSERT_EQ(batch.status, 0) << batch.err;
  const std::string map = (f.dir / "study" / "eye.exr").string();
  const std::vector<float> cover = readExrChannel(map, "coverage_probability", width, height);
  const std::vector<float> max_ratio = readExrChannel(map, "max_hazard_ratio", width, height);
  for (std::size_t p = 0; p < 4; ++p) {
    EXPECT_EQ(cover[p], 1.0f) << "point " << p;
    EXPECT_NEAR(max_ratio[p], ratio[p], 1e-3 * static_cast<double>(ratio[p])) << "point " << p;
  }
  const auto result = nlohmann::json::parse(
      std::ifstream(f.dir / "study" / "scenarios" / "s000000" / "result.json"));
  const nlohmann::json& region = result.at("regions").at(0);
  EXPECT_EQ(region.at("hazardous_points"), 4);
  EXPECT_EQ(region.at("worst").at("hazard_rule"), "rule 3");
  EXPECT_LT(region.at("worst").at("window_ratio").get<double>(), 1.0);
}

TEST(EngagementPoints, CommandsThatCannotIntegrateAnEngagementRefuseIt) {
  const Folder f("glint_engagement_refused");
  const fs::path scene = f.write("scene.json", kScene);
  const fs::path points = f.write("points.csv", "x,y,z\n-50,0,0.5\n");
  const test::Outcome run = glint({"run", scene.string(), "--out", (f.dir / "run").string()});
  EXPECT_EQ(run.status, 2);
  EXPECT_NE(run.err.find("/engagement: glint run integrates an engagement over `observers` (a "
                         "box) or `planes`"),
            std::string::npos)
      << run.err;
  const test::Outcome uniform =
      glint({"points", scene.string(), "--points", points.string(), "--uniform", "2"});
  EXPECT_EQ(uniform.status, 2) << uniform.err;
  const fs::path plain = f.write("plain.json", R"({
    "laser": {"position": [-100, 0, 0], "direction": [1, 0, 0], "power_w": 1000,
              "wavelength_nm": 1064, "beam": {"profile": "gaussian", "w_m": 1.0}},
    "materials": {"m": {"specular_reflectance": 0.9, "sigma": 0.002}},
    "objects": [{"shape": "disk", "center": [0, 0, 0], "normal": [-1, 0, 0], "radius": 0.3,
                 "material": "m"}]})");
  const test::Outcome series = glint({"points", plain.string(), "--points", points.string(),
                                      "--time-series", (f.dir / "s.csv").string()});
  EXPECT_EQ(series.status, 2);
  EXPECT_NE(series.err.find("has no engagement"), std::string::npos) << series.err;
  EXPECT_FALSE(fs::exists(f.dir / "s.csv"));
}

// A study of an engagement: each scenario's map is what glint run writes of its scene, the study
// keeps each point's largest worst-window ratio and counts the scenarios whose worst window
// reaches the MPE there, and a second run resumes every scenario to the same bytes.
TEST(EngagementStudy, ItsMapsAddUpTheScenariosWorstWindowsAsGlintRunGivesThem) {
  const Folder f("glint_engagement_study");
  const std::string scene = sceneWith(kWall);
  f.write("scene.json", scene);
  // 3 mrad of jitter moves the glint's path across the wall by about 0.3 m at 50 m: some
  // scenarios' worst windows reach the MPE somewhere, others nowhere.
  constexpr int kScenarios = 4;
  const fs::path study = f.write("study.json", R"({"scene": "scene.json",
    "pointing_jitter": {"sigma_rad": 0.003, "samples": 4, "seed": 3}})");
  const fs::path out = f.dir / "out";
  const test::Outcome batch = glint({"batch", study.string(), "-o", out.string()});
  ASSERT_EQ(batch.status, 0) << batch.err;
  int width = 0, height = 0;
  const std::string map = (out / "wall.exr").string();
  const std::vector<float> max_ratio = readExrChannel(map, "max_hazard_ratio", width, height);
  const std::vector<float> cover = readExrChannel(map, "coverage_probability", width, height);
  const std::vector<float> max_e = readExrChannel(map, "max_irradiance_w_m2", width, height);
  std::vector<float> want_ratio(max_ratio.size(), 0.0f), want_e(max_ratio.size(), 0.0f);
  std::vector<int> hazardous(max_ratio.size(), 0);
  int scenarios_with_hazard = 0;
  for (int k = 0; k < kScenarios; ++k) {
    const fs::path dir = out / "scenarios" / ("s00000" + std::to_string(k));
    int w = 0, h = 0;
    const std::vector<float> ratio =
        readExrChannel((dir / "wall.exr").string(), "hazard_ratio", w, h);
    const std::vector<float> peak =
        readExrChannel((dir / "wall.exr").string(), "peak_irradiance_w_m2", w, h);
    ASSERT_EQ(ratio.size(), max_ratio.size()) << dir;
    bool any = false;
    for (std::size_t p = 0; p < ratio.size(); ++p) {
      want_ratio[p] = std::max(want_ratio[p], ratio[p]);
      want_e[p] = std::max(want_e[p], peak[p]);
      hazardous[p] += ratio[p] >= 1.0f ? 1 : 0;
      any = any || ratio[p] >= 1.0f;
    }
    scenarios_with_hazard += any ? 1 : 0;
  }
  EXPECT_GT(scenarios_with_hazard, 0) << "the jitter must give a hazard somewhere";
  EXPECT_LT(scenarios_with_hazard, kScenarios) << "and leave some scenarios safe";
  for (std::size_t p = 0; p < max_ratio.size(); ++p) {
    EXPECT_EQ(max_ratio[p], want_ratio[p]) << "pixel " << p;
    EXPECT_EQ(max_e[p], want_e[p]) << "pixel " << p;
    EXPECT_EQ(cover[p], static_cast<float>(hazardous[p] / static_cast<double>(kScenarios)))
        << "pixel " << p;
  }
  // A scenario's map is glint run's of its scene.json, to the byte.
  const fs::path one = out / "scenarios" / "s000001";
  const test::Outcome run =
      glint({"run", (one / "scene.json").string(), "-o", (f.dir / "run").string(), "-q"});
  ASSERT_EQ(run.status, 0) << run.err;
  EXPECT_EQ(test::readFile(f.dir / "run" / "wall.exr"), test::readFile(one / "wall.exr"));
  // Resumed, every scenario is read back into the same study map.
  const std::string first = test::readFile(out / "wall.exr");
  const test::Outcome again = glint({"batch", study.string(), "-o", out.string()});
  ASSERT_EQ(again.status, 0) << again.err;
  EXPECT_NE(again.err.find("(4 done before, 0 to run)"), std::string::npos) << again.err;
  EXPECT_EQ(test::readFile(out / "wall.exr"), first);
}

// A study over a box: box.vdb keeps each lattice point's largest worst-window ratio over the
// scenarios' engagement.vdb, and a resumed study reads them back into the same map.
TEST(EngagementStudy, ABoxStudyKeepsEachPointsWorstWindowAndResumesFromItsScenarios) {
  const Folder f("glint_engagement_box_study");
  const std::string scene = sceneWith(
      R"("observers": {"min": [-50.5, -2, -1], "max": [-49.5, 2, 3], "voxel_m": 1, "block_m": 2})");
  f.write("scene.json", scene);
  const fs::path study = f.write("study.json", R"({"scene": "scene.json",
    "pointing_jitter": {"sigma_rad": 0.003, "samples": 2, "seed": 3}})");
  const fs::path out = f.dir / "out";
  const test::Outcome batch = glint({"batch", study.string(), "-o", out.string()});
  ASSERT_EQ(batch.status, 0) << batch.err;
  FieldSpec spec;
  spec.min_m = Vec3(-50.5, -2, -1);
  spec.max_m = Vec3(-49.5, 2, 3);
  spec.voxel_m = 1.0;
  spec.block_voxels = 2;
  const std::vector<float> max_ratio =
      readLatticeVdb((out / "box.vdb").string(), "max_hazard_ratio", spec);
  std::vector<float> want(max_ratio.size(), 0.0f);
  for (const char* s : {"s000000", "s000001"}) {
    const std::vector<float> ratio =
        readLatticeVdb((out / "scenarios" / s / "engagement.vdb").string(), "hazard_ratio", spec);
    for (std::size_t p = 0; p < want.size(); ++p) want[p] = std::max(want[p], ratio[p]);
  }
  EXPECT_GT(*std::max_element(want.begin(), want.end()), 1.0f) << "the glint crosses the box";
  EXPECT_EQ(max_ratio, want);
  const test::Outcome again = glint({"batch", study.string(), "-o", out.string()});
  ASSERT_EQ(again.status, 0) << again.err;
  EXPECT_NE(again.err.find("(2 done before, 0 to run)"), std::string::npos) << again.err;
  EXPECT_EQ(readLatticeVdb((out / "box.vdb").string(), "max_hazard_ratio", spec), max_ratio);
}

TEST(EngagementStudy, SweepsAnEngagementCannotTakeAreRefused) {
  const Folder f("glint_engagement_study_refused");
  const std::string scene = sceneWith(kWall);
  f.write("scene.json", scene);
  const fs::path trajectory = f.write("trajectory.json", R"({"scene": "scene.json",
    "trajectory": {"poses": [{"time_s": 0}, {"time_s": 1, "offset_m": [0, 1, 0]}]}})");
  const test::Outcome t = glint({"batch", trajectory.string(), "-o", (f.dir / "t").string()});
  EXPECT_EQ(t.status, 2);
  EXPECT_NE(t.err.find("/trajectory: the scene is an engagement"), std::string::npos) << t.err;
  std::string keyed = scene;
  keyed.replace(keyed.find(R"("target": {"turn_deg_s")"), 0,
                R"("laser": {"pointing": "keyed", "directions": [{"time_s": 0,
                   "direction": [1, 0, 0]}]}, )");
  f.write("keyed.json", keyed);
  const fs::path jitter = f.write("jitter.json", R"({"scene": "keyed.json",
    "pointing_jitter": {"sigma_rad": 0.001, "samples": 2}})");
  const test::Outcome j = glint({"batch", jitter.string(), "-o", (f.dir / "j").string()});
  EXPECT_EQ(j.status, 2);
  EXPECT_NE(j.err.find("/pointing_jitter: the engagement's laser follows keyed directions"),
            std::string::npos)
      << j.err;
  for (const char* folder : {"t", "j"}) EXPECT_FALSE(fs::exists(f.dir / folder)) << folder;
}

}  // namespace
}  // namespace glint
