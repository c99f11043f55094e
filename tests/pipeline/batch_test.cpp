// `glint batch` on one process: the aggregated maps against the scenarios' own maps, the
// scenario table, resuming, and refusing another study's folder. (The MPI run is compared with
// this one by tests/pipeline/batch_mpi_test.sh.)
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "export/exr_map.h"
#include "export/lattice_vdb.h"
#include "pipeline/scene.h"
#include "pipeline/study.h"
#include "pipeline/target_builder.h"
#include "support/cli.h"

namespace glint {
namespace {

namespace fs = std::filesystem;

const std::string kStudy = std::string(GLINT_TEST_DATA_DIR) + "/study.json";

using test::glint;
using test::Outcome;

std::string bytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

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
  const double mpe = study.base.hazard.mpe.irradiance_w_m2;
  ASSERT_EQ(study.scenarios.size(), 4u);

  // The plane: channels of ground.exr against the four scenario maps, exactly.
  const std::vector<float> max_e = exrChannel(dir_ / "ground.exr", "max_irradiance_w_m2");
  const std::vector<float> cover = exrChannel(dir_ / "ground.exr", "coverage_probability");
  const std::vector<float> max_ratio = exrChannel(dir_ / "ground.exr", "max_hazard_ratio");
  std::vector<float> expect_max(max_e.size(), 0.0f);
  std::vector<int> hazardous(max_e.size(), 0);
  for (int s = 0; s < 4; ++s) {
    const auto e = exrChannel(dir_ / "scenarios" / ("s00000" + std::to_string(s)) / "ground.exr",
                              "irradiance_w_m2");
    ASSERT_EQ(e.size(), max_e.size());
    for (std::size_t i = 0; i < e.size(); ++i) {
      expect_max[i] = std::max(expect_max[i], e[i]);
      hazardous[i] += static_cast<double>(e[i]) >= mpe ? 1 : 0;
    }
  }
  int some = 0, all = 0;
  for (std::size_t i = 0; i < max_e.size(); ++i) {
    ASSERT_EQ(max_e[i], expect_max[i]) << "pixel " << i;
    ASSERT_EQ(cover[i], static_cast<float>(hazardous[i] / 4.0)) << "pixel " << i;
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
  std::istringstream csv(bytes(dir_ / "scenarios.csv"));
  std::string header, line;
  std::getline(csv, header);
  EXPECT_EQ(header.rfind("scenario,time_s,", 0), 0u) << header;
  EXPECT_NE(header.find(",box_peak_hazard_ratio,box_hazard_volume_m3,ground_peak_hazard_ratio,"
                        "ground_hazardous_area_m2,unconverged_points,evaluations,seconds"),
            std::string::npos)
      << header;
  std::vector<double> peaks;
  int rows = 0;
  while (std::getline(csv, line)) {
    EXPECT_EQ(line.substr(0, line.find(',')), std::to_string(rows)) << "rows in scenario order";
    const auto result = nlohmann::json::parse(
        bytes(dir_ / "scenarios" / ("s00000" + std::to_string(rows)) / "result.json"));
    peaks.push_back(result.at("regions")[1].at("peak_hazard_ratio").get<double>());
    ++rows;
  }
  EXPECT_EQ(rows, 4);
  std::sort(peaks.begin(), peaks.end());
  const auto summary = nlohmann::json::parse(bytes(dir_ / "summary.json"));
  EXPECT_EQ(summary.at("scenarios").at("count"), 4);
  const auto& ground = summary.at("regions")[1];
  EXPECT_EQ(ground.at("name"), "ground");
  // Type-7 quantiles of four values: the median halfway between the middle two.
  EXPECT_DOUBLE_EQ(ground.at("peak_hazard_ratio").at("median").get<double>(),
                   0.5 * (peaks[1] + peaks[2]));
  EXPECT_DOUBLE_EQ(ground.at("peak_hazard_ratio").at("max").get<double>(), peaks[3]);
  EXPECT_DOUBLE_EQ(ground.at("peak_hazard_ratio").at("p25").get<double>(),
                   peaks[0] + 0.75 * (peaks[1] - peaks[0]));
}

TEST_F(Batch, ResumeRedoesOnlyTheScenariosWithoutAResult) {
  const fs::path dir = copyOfRun();
  const std::string exr = bytes(dir / "ground.exr"), vdb = bytes(dir / "box.vdb");
  fs::remove(dir / "scenarios" / "s000002" / "result.json");
  const Outcome again = glint({"batch", kStudy, "-o", dir.string()});
  ASSERT_EQ(again.status, 0) << again.err;
  EXPECT_NE(again.err.find("(3 done before, 1 to run)"), std::string::npos) << again.err;
  EXPECT_EQ(bytes(dir / "ground.exr"), exr) << "a resumed study gives the same map";
  EXPECT_EQ(bytes(dir / "box.vdb"), vdb) << "and the same volume";
  const auto summary = nlohmann::json::parse(bytes(dir / "summary.json"));
  EXPECT_EQ(summary.at("scenarios").at("resumed"), 3);
  EXPECT_EQ(summary.at("scenarios").at("computed"), 1);
  fs::remove_all(dir);
}

TEST_F(Batch, RefusesAFolderOfAnotherStudyUnlessFresh) {
  const fs::path dir = copyOfRun();
  const fs::path other = dir / "other_study.json";
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
  fs::remove_all(dir);
}

}  // namespace
}  // namespace glint
