// `glint batch` on one process: the aggregated maps against the scenarios' own maps, the
// scenario table, resuming, and refusing another study's folder. (The MPI run is compared with
// this one by tests/pipeline/batch_mpi_test.sh.)
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/file.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <tuple>

#include "export/exr_map.h"
#include "export/lattice_vdb.h"
#include "pipeline/base/number_format.h"
#include "pipeline/input/scene.h"
#include "pipeline/input/study.h"
#include "pipeline/report/output_folder.h"
#include "pipeline/report/run_outputs.h"
#include "pipeline/setup/study_maps.h"
#include "pipeline/setup/target_builder.h"
#include "support/cli.h"
#include "support/files.h"

namespace glint {
namespace {

namespace fs = std::filesystem;

const std::string kStudy = std::string(GLINT_TEST_DATA_DIR) + "/study.json";

using test::glint;
using test::Outcome;

using test::readFile;

std::vector<float> exrChannel(const fs::path& p, const std::string& name) {
  int w = 0, h = 0;
  return readExrChannel(p.string(), name, w, h);
}

// The 4-scenario test study, run once by ctest before these tests (fixture glint_batch_run:
// each scenario takes seconds). Tests that change a folder work on their own copy.
class Batch : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(fs::exists(dir_ / "summary.json"))
        << "run the ctest fixture GlintBatch.RunsTheTestStudy first (it writes " << dir_ << ")";
  }
  // A copy of the run's folder for this test alone.
  fs::path copyOfRun() const {
    const fs::path copy =
        fs::temp_directory_path() /
        ("glint_batch_" +
         std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(copy);
    fs::copy(dir_, copy, fs::copy_options::recursive);
    return copy;
  }
  const fs::path dir_ = GLINT_BATCH_RUN_DIR;
};

TEST_F(Batch, AggregatesAreTheMaximumAndTheHazardFractionOfTheScenarioMaps) {
  const Study study = loadStudy(kStudy);
  const double mpe = study.base.hazard.mpe_w_m2;
  ASSERT_EQ(study.scenarios.size(), 4u);

  // The plane: channels of ground.exr against the four scenario maps, exactly.
  const std::vector<float> max_e = exrChannel(dir_ / "ground.exr", "max_irradiance_w_m2");
  const std::vector<float> cover = exrChannel(dir_ / "ground.exr", "coverage_probability");
  const std::vector<float> max_ratio = exrChannel(dir_ / "ground.exr", "max_hazard_ratio");
  std::vector<float> expect_max(max_e.size(), 0.0f);
  std::vector<int> hazardous(max_e.size(), 0);
  // Scenarios 0 and 1 are the first pitch's two jitter samples, 2 and 3 the second's.
  std::vector<std::array<int, 2>> by_pitch(max_e.size(), {0, 0});
  for (int s = 0; s < 4; ++s) {
    const auto e = exrChannel(dir_ / "scenarios" / ("s00000" + std::to_string(s)) / "ground.exr",
                              "irradiance_w_m2");
    ASSERT_EQ(e.size(), max_e.size());
    for (std::size_t i = 0; i < e.size(); ++i) {
      expect_max[i] = std::max(expect_max[i], e[i]);
      hazardous[i] += static_cast<double>(e[i]) >= mpe ? 1 : 0;
      by_pitch[i][s / 2] += static_cast<double>(e[i]) >= mpe ? 1 : 0;
    }
  }
  // The two pitches share each jitter sample, so their scenarios are not four independent
  // trials: each pixel's 95 % interval is the mean of each pitch's Clopper–Pearson interval of
  // its two samples at 2.5 % / 2 a side (Bonferroni over the pitches).
  const std::vector<float> lower = exrChannel(dir_ / "ground.exr", "coverage_lower");
  const std::vector<float> upper = exrChannel(dir_ / "ground.exr", "coverage_upper");
  int some = 0, all = 0;
  for (std::size_t i = 0; i < max_e.size(); ++i) {
    ASSERT_EQ(max_e[i], expect_max[i]) << "pixel " << i;
    ASSERT_EQ(cover[i], static_cast<float>(hazardous[i] / 4.0)) << "pixel " << i;
    const ProportionInterval a =
        clopperPearson(static_cast<std::uint64_t>(by_pitch[i][0]), 2, 0.0125);
    const ProportionInterval b =
        clopperPearson(static_cast<std::uint64_t>(by_pitch[i][1]), 2, 0.0125);
    ASSERT_EQ(lower[i], static_cast<float>(0.5 * (a.lower + b.lower))) << "pixel " << i;
    ASSERT_EQ(upper[i], static_cast<float>(0.5 * (a.upper + b.upper))) << "pixel " << i;
    ASSERT_LE(lower[i], cover[i]);
    ASSERT_GE(upper[i], cover[i]);
    ASSERT_EQ(max_ratio[i], static_cast<float>(static_cast<double>(max_e[i]) / mpe)) << i;
    some += hazardous[i] > 0 && hazardous[i] < 4 ? 1 : 0;
    all += hazardous[i] == 4 ? 1 : 0;
  }
  // The scene is made so the jitter and tilt move the hazard: a real test of the fraction.
  EXPECT_GT(some, 10) << "pixels hazardous in some scenarios but not all";
  EXPECT_GT(all, 10) << "pixels hazardous in every scenario";

  // The box: box.vdb against the scenarios' irradiance.vdb.
  const FieldSpec box = fieldSpec(study.base);
  const auto box_max = readLatticeVdb((dir_ / "box.vdb").string(), "max_irradiance_w_m2", box);
  const auto box_cover = readLatticeVdb((dir_ / "box.vdb").string(), "coverage_probability", box);
  std::vector<float> expect_box(box_max.size(), 0.0f);
  std::vector<int> box_hazardous(box_max.size(), 0);
  for (int s = 0; s < 4; ++s) {
    const auto e = readLatticeVdb(
        (dir_ / "scenarios" / ("s00000" + std::to_string(s)) / "irradiance.vdb").string(),
        "irradiance_w_m2", box);
    for (std::size_t i = 0; i < e.size(); ++i) {
      expect_box[i] = std::max(expect_box[i], e[i]);
      box_hazardous[i] += static_cast<double>(e[i]) >= mpe ? 1 : 0;
    }
  }
  EXPECT_EQ(box_max, expect_box);
  for (std::size_t i = 0; i < box_cover.size(); ++i)
    ASSERT_EQ(box_cover[i], static_cast<float>(box_hazardous[i] / 4.0)) << "voxel " << i;
}

TEST_F(Batch, TableHasOneRowPerScenarioAndTheSummaryItsQuantiles) {
  std::istringstream csv(readFile(dir_ / "scenarios.csv"));
  std::string header, line;
  std::getline(csv, header);
  EXPECT_EQ(header.rfind("scenario,time_s,", 0), 0u) << header;
  EXPECT_NE(header.find(",box_peak_hazard_ratio,box_hazard_volume_m3,ground_peak_hazard_ratio,"
                        "ground_hazardous_area_m2,far_max_nohd_m,far_peak_intensity_w_sr,"
                        "unconverged_points,evaluations,seconds"),
            std::string::npos)
      << header;
  std::vector<double> peaks;
  int rows = 0;
  while (std::getline(csv, line)) {
    EXPECT_EQ(line.substr(0, line.find(',')), std::to_string(rows)) << "rows in scenario order";
    const auto result = nlohmann::json::parse(
        readFile(dir_ / "scenarios" / ("s00000" + std::to_string(rows)) / "result.json"));
    peaks.push_back(result.at("regions")[1].at("peak_hazard_ratio").get<double>());
    ++rows;
  }
  EXPECT_EQ(rows, 4);
  std::sort(peaks.begin(), peaks.end());
  const auto summary = nlohmann::json::parse(readFile(dir_ / "summary.json"));
  EXPECT_EQ(summary.at("scenarios").at("count"), 4);
  const auto& ground = summary.at("regions")[1];
  EXPECT_EQ(ground.at("name"), "ground");
  // Type-7 quantiles of four values: the median halfway between the middle two.
  EXPECT_DOUBLE_EQ(ground.at("peak_hazard_ratio").at("median").get<double>(),
                   0.5 * (peaks[1] + peaks[2]));
  EXPECT_DOUBLE_EQ(ground.at("peak_hazard_ratio").at("max").get<double>(), peaks[3]);
  EXPECT_DOUBLE_EQ(ground.at("peak_hazard_ratio").at("p25").get<double>(),
                   peaks[0] + 0.75 * (peaks[1] - peaks[0]));

  // Issue 65: the study's time accounted for by phase, as a run's is.
  const nlohmann::json& timing = summary.at("timing");
  std::vector<std::string> phases;
  double within_s = 0.0;
  for (const nlohmann::json& p : timing.at("phases")) {
    phases.push_back(p.at("phase").get<std::string>());
    within_s += p.at("seconds").get<double>();
  }
  EXPECT_EQ(phases, (std::vector<std::string>{"reading the study and checking its memory",
                                              "reading the scenarios already done", "the scenarios",
                                              "writing the study's files"}))
      << timing.dump();
  const double wall_s = timing.at("wall_seconds").get<double>();
  EXPECT_GE(within_s, 0.95 * wall_s)
      << "the phases account for the study's time: " << timing.dump();
  EXPECT_LE(within_s, wall_s * (1.0 + 1e-9)) << timing.dump();
  EXPECT_NEAR(summary.at("wall_seconds").get<double>(), wall_s, 1e-6) << timing.dump();
}

// The test study sweeps two pitches beside its jitter: the summary says its intervals keep the
// two combinations apart.
TEST_F(Batch, IntervalsOfSweepsSharingTheirJitterKeepEachCombinationApart) {
  const auto summary = nlohmann::json::parse(readFile(dir_ / "summary.json"));
  for (const auto& region : summary.at("regions")) {
    const auto& c = region.at("coverage_confidence");
    EXPECT_EQ(c.at("combinations"), 2) << region.at("name");
    EXPECT_NE(c.at("pointwise").get<std::string>().find("not independent"), std::string::npos) << c;
  }
}

TEST_F(Batch, ResumeRedoesOnlyTheScenariosWithoutAResult) {
  const fs::path dir = copyOfRun();
  const std::string exr = readFile(dir / "ground.exr"), vdb = readFile(dir / "box.vdb");
  fs::remove(dir / "scenarios" / "s000002" / "result.json");
  const Outcome again = glint({"batch", kStudy, "-o", dir.string()});
  ASSERT_EQ(again.status, 0) << again.err;
  EXPECT_NE(again.err.find("(3 done before, 1 to run)"), std::string::npos) << again.err;
  EXPECT_EQ(readFile(dir / "ground.exr"), exr) << "a resumed study gives the same map";
  EXPECT_EQ(readFile(dir / "box.vdb"), vdb) << "and the same volume";
  const auto summary = nlohmann::json::parse(readFile(dir / "summary.json"));
  EXPECT_EQ(summary.at("scenarios").at("resumed"), 3);
  EXPECT_EQ(summary.at("scenarios").at("computed"), 1);
  fs::remove_all(dir);
}

TEST_F(Batch, RefusesAFolderOfAnotherStudyUnlessFresh) {
  const fs::path dir = copyOfRun();
  // Beside the folder, not in it: an output folder holding its own study is refused first.
  const fs::path other = dir.string() + "_other_study.json";
  std::ofstream(other) << R"({"scene": ")" << GLINT_TEST_DATA_DIR << R"(/study_scene.json"})";
  const Outcome refused = glint({"batch", other.string(), "-o", dir.string()});
  EXPECT_EQ(refused.status, 2);
  EXPECT_NE(refused.err.find("holds results of another study"), std::string::npos) << refused.err;
  EXPECT_NE(refused.err.find("--fresh"), std::string::npos) << refused.err;

  const fs::path fresh_dir = dir / "fresh";
  fs::create_directories(fresh_dir / "scenarios" / "s000007");
  std::ofstream(fresh_dir / "scenarios" / "s000007" / "result.json") << "{}";
  const Outcome fresh = glint({"batch", other.string(), "-o", fresh_dir.string(), "--fresh"});
  ASSERT_EQ(fresh.status, 0) << fresh.err;
  EXPECT_FALSE(fs::exists(fresh_dir / "scenarios" / "s000007")) << "--fresh clears old scenarios";
  EXPECT_TRUE(fs::exists(fresh_dir / "scenarios" / "s000000" / "result.json"));
  fs::remove(other);
  fs::remove_all(dir);
}

// A study of a 5 cm mirror disk at the origin, lit along +x from 100 m and glinting along +y,
// yawed 0° and 20°, with a 1 m observer box beside it and the far field: @p laser_keys gives
// the scene's `laser` (and its atmosphere and optical aid), @p plane_keys any `planes` entry
// (with its trailing comma). Runs glint batch into dir/out.
void runMirrorStudy(const fs::path& dir, const std::string& laser_keys,
                    const std::string& plane_keys) {
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream(dir / "scene.json") << "{" << laser_keys << ","
                                    << R"(
    "materials": {"mirror": {"specular_reflectance": 0.9, "sigma": 0.01}},
    "objects": [{"shape": "disk", "center": [0, 0, 0], "normal": [-1, 1, 0], "radius": 0.05,
                 "material": "mirror", "segments": 8}],
    "observers": {"min": [-1, 0.5, -0.25], "max": [0, 1.5, 0.25], "voxel_m": 0.25,
                  "block_m": 1.0, "tolerance": 0.05},)"
                                    << plane_keys << R"(
    "far_field": {"tolerance": 0.05, "face_pixels": 64}})";
  std::ofstream(dir / "study.json") << R"({"scene": "scene.json", "sweep": {"yaw_deg": [0, 20]}})";
  const Outcome batch =
      glint({"batch", (dir / "study.json").string(), "-o", (dir / "out").string(), "-q"});
  ASSERT_EQ(batch.status, 0) << batch.err;
}

// A study's far field: each scenario's hazard distance by direction is the one `glint run`
// finds for that scenario's scene, and the summary names the farthest. A 5 cm mirror at
// σ = 0.01 in a 1 MW beam reflects about 3.6e6 W/sr: a NOHD of some 270 m, beyond its far
// radius of 135 m, so the far field has a hazard to report.
TEST(BatchFarField, EachScenarioMatchesGlintRunAndTheSummaryNamesTheFarthest) {
  const fs::path dir = fs::temp_directory_path() / "glint_batch_far_field";
  ASSERT_NO_FATAL_FAILURE(runMirrorStudy(dir, R"(
    "laser": {"position": [-100, 0, 0], "direction": [1, 0, 0], "power_w": 1.0e6,
              "wavelength_nm": 1064, "exposure_s": 10,
              "beam": {"profile": "flat_top", "radius_m": 0.5}})",
                                         ""));

  std::vector<double> nohd;
  for (int s = 0; s < 2; ++s) {
    const fs::path scenario = dir / "out" / "scenarios" / ("s00000" + std::to_string(s));
    const auto far = nlohmann::json::parse(readFile(scenario / "result.json")).at("far_field");
    nohd.push_back(far.at("max_nohd_m").get<double>());
    EXPECT_GT(nohd.back(), far.at("far_radius_m").get<double>())
        << "scenario " << s << ": the mirror's glint is hazardous beyond the far radius";
    const Outcome run = glint({"run", (scenario / "scene.json").string(), "-o",
                               (dir / ("run" + std::to_string(s))).string(), "-q"});
    ASSERT_EQ(run.status, 0) << run.err;
    const auto ran =
        nlohmann::json::parse(readFile(dir / ("run" + std::to_string(s)) / "summary.json"))
            .at("far_field");
    // The same computation on the same scene: the same numbers, to the last bit.
    EXPECT_EQ(far.at("max_nohd_m"), ran.at("max_nohd_m")) << "scenario " << s;
    EXPECT_EQ(far.at("max_nohd_direction"), ran.at("max_nohd_direction")) << "scenario " << s;
    EXPECT_EQ(far.at("peak_intensity_w_sr"), ran.at("peak_intensity_w_sr")) << "scenario " << s;
    EXPECT_EQ(far.at("far_radius_m"), ran.at("far_radius_m")) << "scenario " << s;
  }
  const auto summary =
      nlohmann::json::parse(readFile(dir / "out" / "summary.json")).at("far_field");
  const auto farthest = std::max_element(nohd.begin(), nohd.end());
  EXPECT_EQ(summary.at("max_nohd_m").at("max").get<double>(), *farthest);
  EXPECT_EQ(summary.at("farthest").at("scenario").get<int>(), farthest - nohd.begin());
  EXPECT_EQ(summary.at("scenarios_hazardous_beyond_far_radius").get<int>(), 2);

  std::istringstream csv(readFile(dir / "out" / "scenarios.csv"));
  std::string header, row;
  std::getline(csv, header);
  std::getline(csv, row);
  EXPECT_NE(header.find(",far_max_nohd_m,far_peak_intensity_w_sr,"), std::string::npos) << header;
  std::string cell = ",";  // built in steps: GCC 12 warns falsely on "," + s + ","
  cell += formatNumber("%.10g", nohd[0]);
  cell += ",";
  EXPECT_NE(row.find(cell), std::string::npos) << "scenario 0's far-field NOHD in its row: " << row;
  fs::remove_all(dir);
}

// A pulsed laser in fog seen through binoculars: each scenario's result gives the aided figures
// beside the unaided ones (34.3 × the ratio), the per-pulse exposure, and the far field's aided
// NOHD; scenarios.csv and summary.json carry them.
TEST(BatchHazard, PulsesFogAndBinocularsReachEveryScenarioAndTheSummary) {
  const fs::path dir = fs::temp_directory_path() / "glint_batch_hazard";
  ASSERT_NO_FATAL_FAILURE(runMirrorStudy(dir, R"(
    "laser": {"position": [-100, 0, 0], "direction": [1, 0, 0], "wavelength_nm": 1064,
              "pulse": {"energy_j": 10.0, "duration_s": 1e-8, "repetition_rate_hz": 10},
              "beam": {"profile": "flat_top", "radius_m": 0.5}},
    "atmosphere": {"visibility_m": 5000},
    "optical_aid": {"aperture_m": 0.05, "magnification": 7, "transmission": 0.7})",
                                         R"(
    "planes": [{"name": "far", "origin": [-2, 100, -2], "u_axis": [1, 0, 0], "v_axis": [0, 0, 1],
                "size_m": [4, 4], "pixel_m": 0.25}],)"));
  for (int s = 0; s < 2; ++s) {
    const auto rec = nlohmann::json::parse(
        readFile(dir / "out" / "scenarios" / ("s00000" + std::to_string(s)) / "result.json"));
    const auto& box = rec.at("regions").at(0);
    const double ratio = box.at("peak_hazard_ratio").get<double>();
    EXPECT_NEAR(box.at("aided_peak_hazard_ratio").get<double>(), 34.3 * ratio, 1e-9 * ratio);
    EXPECT_GE(box.at("aided_hazardous_points").get<std::int64_t>(),
              box.at("hazardous_points").get<std::int64_t>());
    EXPECT_GT(box.at("peak_radiant_exposure_j_m2_per_pulse").get<double>(), 0.0);
    const auto& far = rec.at("far_field");
    EXPECT_GT(far.at("aided_max_nohd_m").get<double>(), far.at("max_nohd_m").get<double>())
        << far.dump();
  }
  const auto summary = nlohmann::json::parse(readFile(dir / "out" / "summary.json"));
  EXPECT_EQ(summary.at("hazard").at("pulse").at("rule").get<int>(), 3);
  EXPECT_NEAR(summary.at("hazard").at("optical_aid").at("gain").get<double>(), 34.3, 1e-12);
  EXPECT_GT(summary.at("hazard").at("atmosphere").at("extinction_per_m").get<double>(), 0.0);
  EXPECT_TRUE(summary.at("regions").at(0).contains("aided_peak_hazard_ratio"));
  EXPECT_TRUE(summary.at("far_field").contains("aided_max_nohd_m"));
  std::istringstream csv(readFile(dir / "out" / "scenarios.csv"));
  std::string header;
  std::getline(csv, header);
  EXPECT_NE(header.find(",box_aided_peak_hazard_ratio,box_aided_hazard_volume_m3,"),
            std::string::npos)
      << header;
  EXPECT_NE(header.find(",far_aided_max_nohd_m,"), std::string::npos) << header;

  // The coverage maps through the aid, box and plane: at every point at least the naked eye's
  // coverage, and the fraction of the two scenarios whose stored irradiance × 34.3 reaches the
  // MPE; the plane 100 m down the glint is hazardous through the aid only (unaided peak 0.53).
  const Scene base = loadScene(dir / "scene.json");
  auto read = [&](const fs::path& file, const std::string& channel, const FieldSpec& spec) {
    return file.extension() == ".vdb" ? readLatticeVdb(file.string(), channel, spec)
                                      : exrChannel(file, channel);
  };
  int aided_only = 0;
  for (const auto& [spec, study_file, scenario_file] :
       {std::tuple{fieldSpec(base), "box.vdb", "irradiance.vdb"},
        std::tuple{planeFieldSpec(base, base.planes[0]), "far.exr", "far.exr"}}) {
    const fs::path map = dir / "out" / study_file;
    const auto cover = read(map, "coverage_probability", spec);
    const auto aided_cover = read(map, "aided_coverage_probability", spec);
    const auto aided_max = read(map, "aided_max_hazard_ratio", spec);
    std::vector<std::vector<float>> scenario_e;
    for (int s = 0; s < 2; ++s) {
      scenario_e.push_back(
          read(dir / "out" / "scenarios" / ("s00000" + std::to_string(s)) / scenario_file,
               "irradiance_w_m2", spec));
    }
    ASSERT_EQ(aided_cover.size(), cover.size()) << study_file;
    for (std::size_t i = 0; i < cover.size(); ++i) {
      int reached = 0;
      for (const auto& e : scenario_e)
        reached += base.hazard.aidedRatio(static_cast<double>(e[i])) >= 1.0 ? 1 : 0;
      ASSERT_EQ(aided_cover[i], 0.5f * static_cast<float>(reached)) << study_file << " " << i;
      ASSERT_GE(aided_cover[i], cover[i]) << study_file << " " << i;
      aided_only += aided_cover[i] > cover[i] ? 1 : 0;
      const float e_max = std::max(scenario_e[0][i], scenario_e[1][i]);
      ASSERT_EQ(aided_max[i],
                static_cast<float>(base.hazard.aidedRatio(static_cast<double>(e_max))))
          << study_file << " " << i;
    }
  }
  EXPECT_GT(aided_only, 0) << "premise: the aid makes some points hazardous the eye alone is not";
  const auto& plane = summary.at("regions").at(1);
  EXPECT_GT(plane.at("aided_hazardous_in_any_scenario_m2").get<double>(),
            plane.at("hazardous_in_any_scenario_m2").get<double>())
      << plane.dump();
  fs::remove_all(dir);
}

// The lines of a scenarios.csv without their last cell (each scenario's seconds, a wall-clock
// time).
std::string withoutSeconds(const std::string& csv) {
  std::istringstream in(csv);
  std::string out;
  for (std::string line; std::getline(in, line);) out += line.substr(0, line.rfind(',')) + "\n";
  return out;
}

std::string hostName() {
  char buf[256] = {};
  ::gethostname(buf, sizeof buf - 1);
  return buf;
}

// The names in @p dir, sorted.
std::vector<std::string> namesIn(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

// The mirror study (2 scenarios, under a second) with a plane in the glint, run into dir/out.
void runMirrorStudyWithAPlane(const fs::path& dir) {
  runMirrorStudy(dir, R"(
    "laser": {"position": [-100, 0, 0], "direction": [1, 0, 0], "power_w": 1.0e6,
              "wavelength_nm": 1064, "exposure_s": 10,
              "beam": {"profile": "flat_top", "radius_m": 0.5}})",
                 R"(
    "planes": [{"name": "ground", "origin": [-1, 0.5, 0], "u_axis": [1, 0, 0],
                "v_axis": [0, 1, 0], "size_m": [1, 1], "pixel_m": 0.125}],)");
}

TEST(BatchFolder, AFolderHeldByAnotherProcessIsRefusedWithItsPidAndNothingIsWritten) {
  const fs::path dir = fs::temp_directory_path() / "glint_batch_held";
  fs::remove_all(dir);
  fs::create_directories(dir);
  {
    // This test holds the folder as another `glint batch` would: flock is per open file, so the
    // command run in this same process is refused like a second process.
    const FolderLock held(dir, "glint batch");
    const std::string holder = readFile(dir / FolderLock::kFileName);
    const Outcome refused = glint({"batch", kStudy, "-o", dir.string()});
    EXPECT_EQ(refused.status, 2) << refused.err;
    const std::string expect = dir.string() + " is in use by glint process " +
                               std::to_string(::getpid()) + " on host " + hostName() +
                               " (glint batch, since ";
    EXPECT_NE(refused.err.find(expect), std::string::npos) << refused.err;
    EXPECT_EQ(namesIn(dir), std::vector<std::string>{FolderLock::kFileName})
        << "the refused run wrote nothing into the held folder";
    EXPECT_EQ(readFile(dir / FolderLock::kFileName), holder) << "nor into the holder's lock file";
  }
  EXPECT_FALSE(fs::exists(dir / FolderLock::kFileName)) << "the holder removes its lock file";
  fs::remove_all(dir);
}

TEST(BatchFolder, ALinkPlantedAsTheLockFileIsRefusedNotFollowed) {
  const fs::path dir = fs::temp_directory_path() / "glint_batch_lock_link";
  fs::remove_all(dir);
  fs::create_directories(dir / "out");
  fs::create_symlink(dir / "elsewhere", dir / "out" / FolderLock::kFileName);
  const Outcome refused = glint({"batch", kStudy, "-o", (dir / "out").string()});
  EXPECT_EQ(refused.status, 2) << refused.err;
  EXPECT_NE(refused.err.find("it is a symbolic link; remove it"), std::string::npos) << refused.err;
  EXPECT_FALSE(fs::exists(dir / "elsewhere")) << "the link was not followed";
  EXPECT_EQ(namesIn(dir / "out"), std::vector<std::string>{FolderLock::kFileName})
      << "nothing written";
  fs::remove_all(dir);
}

TEST(BatchFolder, ALockFileLeftByAKilledProcessBlocksNothingAndTheRunRemovesIt) {
  const fs::path dir = fs::temp_directory_path() / "glint_batch_stale_lock";
  ASSERT_NO_FATAL_FAILURE(runMirrorStudyWithAPlane(dir));
  // A child takes the lock and dies without releasing it (as under SIGKILL): its lock file stays,
  // its flock goes with it. Only async-signal-safe calls in the child of a threaded process.
  const std::string lock_file = (dir / "out" / FolderLock::kFileName).string();
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    const int fd = ::open(lock_file.c_str(), O_RDWR | O_CREAT, 0644);
    if (fd < 0 || ::flock(fd, LOCK_EX | LOCK_NB) != 0) ::_exit(1);
    char text[64];
    const int n = std::snprintf(text, sizeof text, "pid=%d\n", static_cast<int>(::getpid()));
    ::_exit(::write(fd, text, static_cast<std::size_t>(n)) == n ? 0 : 1);
  }
  int status = -1;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "the child took the lock";
  ASSERT_NE(readFile(lock_file).find("pid=" + std::to_string(child)), std::string::npos)
      << "premise: the dead process's lock file is there";

  const Outcome again =
      glint({"batch", (dir / "study.json").string(), "-o", (dir / "out").string()});
  ASSERT_EQ(again.status, 0) << again.err;
  EXPECT_NE(again.err.find("(2 done before, 0 to run)"), std::string::npos) << again.err;
  EXPECT_FALSE(fs::exists(lock_file)) << "the run took the stale lock over and removed it";
  fs::remove_all(dir);
}

TEST(BatchFolder, AnEditedResultOrASwappedMapIsRedoneAndTheStudyIsAsIfUntouched) {
  const fs::path dir = fs::temp_directory_path() / "glint_batch_tampered";
  ASSERT_NO_FATAL_FAILURE(runMirrorStudyWithAPlane(dir));
  const fs::path out = dir / "out", untouched = dir / "untouched";
  fs::copy(out, untouched, fs::copy_options::recursive);
  const fs::path s0 = out / "scenarios" / "s000000", s1 = out / "scenarios" / "s000001";
  // Scenario 0's box peak edited to 0, as in the issue: the figure is carried into the table
  // and the summary unless the record is checked.
  auto result = nlohmann::json::parse(readFile(s0 / "result.json"));
  ASSERT_GT(result.at("regions")[0].at("peak_hazard_ratio").get<double>(), 0.0) << "premise";
  result["regions"][0]["peak_hazard_ratio"] = 0;
  std::ofstream(s0 / "result.json") << result.dump(2) << "\n";
  // Scenario 1's plane map replaced by scenario 0's: a whole, readable map, but not its own.
  ASSERT_TRUE(readFile(s1 / "ground.exr") != readFile(s0 / "ground.exr"))
      << "premise: the two scenarios' maps differ";
  fs::copy_file(s0 / "ground.exr", s1 / "ground.exr", fs::copy_options::overwrite_existing);

  const Outcome again = glint({"batch", (dir / "study.json").string(), "-o", out.string()});
  ASSERT_EQ(again.status, 0) << again.err;
  EXPECT_NE(again.err.find("scenario 0 redone: " + (s0 / "result.json").string() +
                           " does not match its checksum (edited or damaged)"),
            std::string::npos)
      << again.err;
  EXPECT_NE(again.err.find("scenario 1 redone: " + (s1 / "ground.exr").string() +
                           " does not match its checksum in result.json"),
            std::string::npos)
      << again.err;

  // Compared as booleans: a difference of binary maps printed in full says nothing.
  EXPECT_TRUE(readFile(out / "ground.exr") == readFile(untouched / "ground.exr"))
      << "the coverage map";
  EXPECT_TRUE(readFile(out / "box.vdb") == readFile(untouched / "box.vdb")) << "the box's maps";
  EXPECT_EQ(withoutSeconds(readFile(out / "scenarios.csv")),
            withoutSeconds(readFile(untouched / "scenarios.csv")))
      << "the table, scenario 0's peak among it";
  const auto summary = nlohmann::json::parse(readFile(out / "summary.json"));
  const auto before = nlohmann::json::parse(readFile(untouched / "summary.json"));
  EXPECT_EQ(summary.at("regions"), before.at("regions")) << "the peak quantiles and areas";
  EXPECT_EQ(summary.at("far_field"), before.at("far_field"));
  EXPECT_EQ(summary.at("scenarios").at("computed"), 2) << "both scenarios redone";
  fs::remove_all(dir);
}

TEST(BatchFolder, FreshRemovesOnlyGlintsOwnFilesAndSaysWhatItKept) {
  const fs::path dir = fs::temp_directory_path() / "glint_batch_fresh";
  ASSERT_NO_FATAL_FAILURE(runMirrorStudyWithAPlane(dir));
  const fs::path scenarios = dir / "out" / "scenarios";
  std::ofstream(scenarios / "notes.txt") << "mine";
  fs::create_directories(scenarios / "mine");
  std::ofstream(scenarios / "mine" / "result.json") << "mine too";
  std::ofstream(scenarios / "s000000" / "notes.txt") << "about scenario 0";
  std::ofstream(scenarios / "s000001" / "notes.txt") << "about scenario 1";
  fs::create_directories(scenarios / "s000002");
  std::ofstream(scenarios / "s000002" / "result.json") << "{}";  // an old study's, glint's name
  // The base scene alone: another study, so the folder's scenarios are discarded.
  std::ofstream(dir / "one.json") << R"({"scene": "scene.json"})";

  const Outcome fresh =
      glint({"batch", (dir / "one.json").string(), "-o", (dir / "out").string(), "--fresh"});
  ASSERT_EQ(fresh.status, 0) << fresh.err;
  EXPECT_EQ(readFile(scenarios / "notes.txt"), "mine");
  EXPECT_EQ(readFile(scenarios / "mine" / "result.json"), "mine too") << "a folder not glint's";
  EXPECT_EQ(readFile(scenarios / "s000000" / "notes.txt"), "about scenario 0");
  EXPECT_EQ(namesIn(scenarios / "s000001"), std::vector<std::string>{"notes.txt"})
      << "glint's files go, the user's stay (and the folder holding them)";
  EXPECT_FALSE(fs::exists(scenarios / "s000002")) << "a scenario folder of glint's files alone";
  EXPECT_TRUE(fs::exists(scenarios / "s000000" / "result.json")) << "the new study's scenario";
  EXPECT_NE(fresh.err.find("--fresh kept 4 file(s) or folder(s) glint did not write"),
            std::string::npos)
      << fresh.err;
  EXPECT_NE(fresh.err.find((scenarios / "s000001" / "notes.txt").string()), std::string::npos)
      << fresh.err;
  fs::remove_all(dir);
}

TEST(BatchFolder, AFailedRunTakesAwayTheFoldersItMadeAndNoOther) {
  const fs::path dir = fs::temp_directory_path() / "glint_batch_failed";
  fs::remove_all(dir);
  fs::create_directories(dir / "empty");
  const fs::path study = dir / "one.json";
  std::ofstream(study) << R"({"scene": ")" << GLINT_TEST_DATA_DIR << R"(/study_scene.json"})";
  // A budget above the study's memory floor but below what this process already holds: the
  // memory watch stops the first scenario once its folder and scene.json are written.
  for (const fs::path& out : {dir / "new" / "out", dir / "empty"}) {
    const Outcome failed = glint({"batch", study.string(), "-o", out.string(), "--memory", "4M"});
    EXPECT_EQ(failed.status, 2) << failed.err;
    EXPECT_NE(failed.err.find("scenario 0, region box: stopped when the resident memory reached"),
              std::string::npos)
        << "premise: the run failed during a scenario: " << failed.err;
  }
  EXPECT_FALSE(fs::exists(dir / "new")) << "out and its parent new/, both made by the run, go";
  ASSERT_TRUE(fs::is_directory(dir / "empty")) << "a folder the run found stays, though empty";
  EXPECT_TRUE(fs::is_empty(dir / "empty")) << "and holds nothing of the run";
  fs::remove_all(dir);
}

// Each scenario folder holds scene.json, result.json and the maps the list of outputs marks as a
// scenario's, each vouched for by result.json, and no file --fresh or a failed run would leave
// behind as not glint's: the names --fresh removes come from the same list as the files written.
TEST_F(Batch, EveryFileAScenarioWritesIsVouchedForAndAmongTheNamesFreshRemoves) {
  const Study study = loadStudy(kStudy);
  const std::vector<std::string> removable = ScenarioMaps::folderNames(study.base);
  std::size_t folders = 0;
  for (const auto& e : fs::directory_iterator(dir_ / "scenarios")) {
    ++folders;
    std::vector<std::string> expected = {"result.json", "scene.json"};
    for (const std::string& map : ScenarioMaps(study.base, e.path()).names())
      expected.push_back(map);
    std::sort(expected.begin(), expected.end());
    const std::vector<std::string> files = namesIn(e.path());
    EXPECT_EQ(files, expected) << e.path() << ": the maps the list names for the study's scene";
    const auto vouched =
        nlohmann::json::parse(readFile(e.path() / "result.json")).at("files_fnv1a64");
    for (const std::string& file : files) {
      EXPECT_TRUE(std::find(removable.begin(), removable.end(), file) != removable.end())
          << e.path() / file << " is not among the names --fresh may remove";
      if (file != "result.json") {
        EXPECT_TRUE(vouched.contains(file))
            << e.path() / file << " is not vouched for by its result.json";
      }
    }
  }
  EXPECT_EQ(folders, study.scenarios.size()) << "premise: every scenario's folder was looked at";
  const std::vector<std::string> maps = ScenarioMaps(study.base, dir_).names();
  for (const StudyLattice& r : studyLattices(study.base)) {
    EXPECT_TRUE(std::find(maps.begin(), maps.end(), r.scenarioFile()) != maps.end())
        << r.scenarioFile() << ", which a resumed scenario reads back, is not a map it writes";
  }
  EXPECT_GE(namesIn(dir_ / "scenarios" / "s000000").size(), 4u)
      << "premise: the test study writes a box's and a plane's maps";
}

}  // namespace
}  // namespace glint
