// Every name a run's outputs carry, from one registry read off the scene: a level's or a plane's
// name never takes the place of glint's own outputs or of each other's (issue 64), and what a
// run writes is what the registry lists.
#include "pipeline/input/output_registry.h"

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <gtest/gtest.h>
#include <openvdb/openvdb.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "support/cli.h"
#include "support/files.h"
#include "support/refusal.h"

namespace glint {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// A 532 nm mirror ball seen through 7 × 50 binoculars.
json aidedBall() {
  return json::parse(R"({
    "laser": {"position": [-50, 0, 0], "direction": [1, 0, 0], "power_w": 5.0,
              "wavelength_nm": 532, "beam": {"profile": "flat_top", "radius_m": 0.5}},
    "optical_aid": {"aperture_m": 0.05, "magnification": 7, "transmission": 0.7},
    "materials": {"mirror": {"specular_reflectance": 0.9, "sigma": 0.02}},
    "objects": [{"shape": "sphere", "center": [0, 0, 0], "radius": 0.2, "material": "mirror"}]
  })");
}

json plane(const std::string& name) {
  return {{"name", name},        {"origin", {-3, -3, 1}}, {"u_axis", {1, 0, 0}},
          {"v_axis", {0, 1, 0}}, {"size_m", {6, 6}},      {"pixel_m", 0.5}};
}

std::string refusal(const json& scene) {
  return test::refusalOf([&] { parseScene(scene.dump(), "scene.json"); });
}

// The issue's cases: each once wrote one output over another (the aided map's channel held a
// level's ratio, 39 000× below the aided hazard; a plane's map replaced the footprint's).
TEST(OutputRegistry, ALevelOrPlaneNameThatWouldTakeAnotherOutputsNameIsRefusedWithItsKey) {
  struct Case {
    const char* what;
    json scene;
    std::string key, says;
  };
  std::vector<Case> cases;
  {
    json j = aidedBall();
    j["hazard"] = {{"levels", json::array({{{"name", "aided_hazard"}, {"irradiance_w_m2", 1e5}}})}};
    cases.push_back({"a level named as the aided ratio", j, "scene.json: /hazard/levels/0/name: ",
                     "the aided_hazard level's ratio and the aided hazard ratio would both be "
                     "aided_hazard_ratio in the points table's columns"});
  }
  {
    json j = aidedBall();
    j["site"] = {{"latitude_deg", 32.9}, {"longitude_deg", -106.4}};
    j["reach"] = {{"footprint", {{"radius_m", 100}}}};
    j["planes"] = json::array({plane("reach_footprint")});
    cases.push_back({"a plane named as the footprint", j, "scene.json: /planes/0/name: ",
                     "would both be reach_footprint.tif in the run's files"});
  }
  {
    json j = aidedBall();
    j["planes"] = json::array({plane("P"), plane("p")});
    cases.push_back({"two planes whose files differ in case only", j,
                     "scene.json: /planes/1/name: ",
                     "(p.exr and P.exr are one file where case is not told apart)"});
  }
  {
    json j = aidedBall();
    j["observers"] = {{"min", {-1, -1, -1}}, {"max", {1, 1, 1}}, {"voxel_m", 0.25}};
    j["planes"] = json::array({plane("box")});
    cases.push_back({"a plane named as the study's box", j, "scene.json: /planes/0/name: ",
                     "would both be box_peak_hazard_ratio in a study's scenarios.csv columns"});
  }
  {
    json j = aidedBall();
    j["planes"] = json::array({plane("x"), plane("x_aided")});
    cases.push_back({"a plane named as another's aided columns", j, "scene.json: /planes/1/name: ",
                     "would both be x_aided_peak_hazard_ratio in a study's scenarios.csv columns"});
  }
  {
    json j = aidedBall();
    j["site"] = {{"latitude_deg", 32.9}, {"longitude_deg", -106.4}};
    j["reach"] = {{"footprint", {{"radius_m", 100}, {"flight_altitudes_m", {50, 50.0000001}}}}};
    cases.push_back({"two flight altitudes that are written alike", j,
                     "scene.json: /reach/footprint/flight_altitudes_m/1: ",
                     "would both be reach_at_50m in the reach footprint's layers"});
  }
  {
    json j = aidedBall();
    j["hazard"] = {
        {"levels", json::array({{{"name", std::string(65, 'a')}, {"irradiance_w_m2", 1.0}}})}};
    cases.push_back({"a level name longer than its channels may carry", j,
                     "scene.json: /hazard/levels/0/name: ", "must be at most 64 characters"});
  }
  for (const Case& c : cases) {
    const std::string message = refusal(c.scene);
    EXPECT_EQ(message.rfind(c.key, 0), 0u) << c.what << ": " << message;
    EXPECT_NE(message.find(c.says), std::string::npos) << c.what << ": " << message;
  }
}

// A run with an aid, levels, a plane and the reach writes no name the registry does not list,
// in each place it lists: the points table's header, the plane map's and reach.exr's channels,
// the volume's grids and the run's files.
TEST(OutputRegistry, EveryNameARunWritesIsOneTheRegistryLists) {
  const fs::path dir = test::freshTestFolder("output_registry");
  json j = aidedBall();
  j["hazard"] = {{"flight_zones", true},
                 {"levels", json::array({{{"name", "site_glare"}, {"irradiance_w_m2", 0.5}}})}};
  j["observers"] = {{"min", {-1, -1, -1}}, {"max", {1, 1, 1}}, {"voxel_m", 0.5}};
  j["planes"] = json::array({plane("overhead")});
  // Coarse everywhere: the names, not the values, are what this test reads.
  j["reach"] = {{"face_cells", 16}, {"layer_ratio", 1.5}};
  j["far_field"] = {{"face_pixels", 16}};
  std::ofstream(dir / "scene.json") << j.dump();
  const Scene scene = loadScene(dir / "scene.json");
  std::map<std::string, std::set<std::string>> listed;
  for (const OutputName& n : outputNames(scene)) listed[n.place].insert(n.name);

  const test::Outcome run =
      test::glint({"run", (dir / "scene.json").string(), "-o", (dir / "out").string(), "-q"});
  ASSERT_EQ(run.status, 0) << run.err;
  for (const auto& entry : fs::directory_iterator(dir / "out")) {
    EXPECT_EQ(listed["the run's files"].count(entry.path().filename().string()), 1u)
        << entry.path().filename();
  }
  const auto channels = [](const fs::path& exr) {
    std::vector<std::string> names;
    Imf::InputFile file(exr.string().c_str());
    for (auto c = file.header().channels().begin(); c != file.header().channels().end(); ++c)
      names.emplace_back(c.name());
    return names;
  };
  for (const std::string& c : channels(dir / "out" / "overhead.exr"))
    EXPECT_EQ(listed["a plane map's channels"].count(c), 1u) << c;
  for (const std::string& c : channels(dir / "out" / "reach.exr"))
    EXPECT_EQ(listed["reach.exr's channels"].count(c), 1u) << c;
  openvdb::initialize();
  openvdb::io::File vdb((dir / "out" / "irradiance.vdb").string());
  vdb.open();
  for (auto g = vdb.beginName(); g != vdb.endName(); ++g)
    EXPECT_EQ(listed["the volumes' grids and arrays"].count(g.gridName()), 1u) << g.gridName();
  vdb.close();

  std::ofstream(dir / "points.csv") << "x,y,z\n0,0,2\n";
  const test::Outcome points =
      test::glint({"points", (dir / "scene.json").string(), "--points",
                   (dir / "points.csv").string(), "--out", (dir / "points_out.csv").string()});
  ASSERT_EQ(points.status, 0) << points.err;
  std::string header;
  std::getline(std::ifstream(dir / "points_out.csv"), header);
  std::stringstream cells(header);
  int columns = 0;
  for (std::string c; std::getline(cells, c, ','); ++columns)
    EXPECT_EQ(listed["the points table's columns"].count(c), 1u) << c;
  EXPECT_EQ(columns, 13) << header << ": x, y, z, four of glint's, the MPE's, the aid's, 4 levels'";
  fs::remove_all(dir);
}

}  // namespace
}  // namespace glint
