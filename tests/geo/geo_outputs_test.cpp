// Every plane map glint writes is placed on the Earth when the scene has a site: a study's
// aggregated maps and an engagement's maps get their GeoTIFF (its bands the EXR's channels) and
// their zones, as a single pose's maps do (tests/export/check_geo.py reads those).
#include <gdal_priv.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "export/exr_map.h"
#include "support/cli.h"
#include "support/files.h"

namespace glint {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// The GeoTIFF's band named @p name, in GDAL's row order (row r is lattice row height − 1 − r).
std::vector<float> band(const fs::path& tif, const std::string& name) {
  GDALAllRegister();
  GDALDataset* d = GDALDataset::FromHandle(GDALOpen(tif.c_str(), GA_ReadOnly));
  if (d == nullptr) return {};
  std::vector<float> v;
  for (int b = 1; b <= d->GetRasterCount(); ++b) {
    GDALRasterBand* rb = d->GetRasterBand(b);
    if (name != rb->GetDescription()) continue;
    v.resize(static_cast<std::size_t>(d->GetRasterXSize()) *
             static_cast<std::size_t>(d->GetRasterYSize()));
    if (rb->RasterIO(GF_Read, 0, 0, d->GetRasterXSize(), d->GetRasterYSize(), v.data(),
                     d->GetRasterXSize(), d->GetRasterYSize(), GDT_Float32, 0, 0) != CE_None)
      v.clear();
  }
  GDALClose(GDALDataset::ToHandle(d));
  return v;
}

// The EXR's channel (readExrChannel: lattice order, row j at j × width) in GDAL's row order.
std::vector<float> exrChannel(const fs::path& exr, const std::string& name) {
  int w = 0, h = 0;
  const std::vector<float> lattice = readExrChannel(exr.string(), name, w, h);
  std::vector<float> rows(lattice.size());
  for (int r = 0; r < h; ++r)
    for (int i = 0; i < w; ++i) {
      rows[static_cast<std::size_t>(r) * static_cast<std::size_t>(w) +
           static_cast<std::size_t>(i)] =
          lattice[static_cast<std::size_t>(h - 1 - r) * static_cast<std::size_t>(w) +
                  static_cast<std::size_t>(i)];
    }
  return rows;
}

TEST(GeoOutputs, AStudysPlaneMapIsOnTheEarthWithItsCoverageZones) {
  const fs::path dir = test::freshTestFolder("glint_geo_study_");
  fs::copy_file(fs::path(GLINT_TEST_DATA_DIR) / "study.json", dir / "study.json");
  json scene = json::parse(test::readFile(fs::path(GLINT_TEST_DATA_DIR) / "study_scene.json"));
  scene["site"] = {{"latitude_deg", 32.9}, {"longitude_deg", -106.4}, {"height_m", 1200}};
  std::ofstream(dir / "study_scene.json") << scene.dump();
  const test::Outcome run = test::glint(
      {"batch", (dir / "study.json").string(), "-o", (dir / "out").string(), "--quiet"});
  ASSERT_EQ(run.status, 0) << run.err;
  const fs::path out = dir / "out";
  for (const char* name : {"ground.tif", "ground_zones.geojson", "ground_zones.kml"})
    EXPECT_TRUE(fs::is_regular_file(out / name)) << name;
  for (const char* channel : {"max_hazard_ratio", "coverage_probability", "coverage_upper"}) {
    const std::vector<float> tif = band(out / "ground.tif", channel);
    EXPECT_FALSE(tif.empty()) << channel;
    EXPECT_EQ(tif, exrChannel(out / "ground.exr", channel)) << channel << ": the EXR's values";
  }
  const json summary = json::parse(test::readFile(out / "summary.json"));
  bool listed = false;
  for (const json& r : summary.at("regions")) {
    if (r.at("name") == "ground") listed = r.at("geo_files").size() == 3;
  }
  EXPECT_TRUE(listed) << summary.at("regions").dump();
  const std::string zones = test::readFile(out / "ground_zones.geojson");
  EXPECT_NE(zones.find("hazardous_in_some_scenario"), std::string::npos) << zones.substr(0, 400);
  fs::remove_all(dir);
}

TEST(GeoOutputs, AnEngagementsPlaneMapIsOnTheEarthWithItsWorstWindowZones) {
  const fs::path dir = test::freshTestFolder("glint_geo_engagement_");
  json scene = json::parse(test::readFile(fs::path(GLINT_TEST_DATA_DIR) / "engagement_mpi.json"));
  scene["site"] = {{"latitude_deg", 32.9}, {"longitude_deg", -106.4}};
  json ground = scene["planes"][0];
  ground["name"] = "ground";
  ground["u_axis"] = {1, 0, 0};
  ground["v_axis"] = {0, 1, 0};
  scene["planes"].push_back(ground);
  scene.erase("observers");
  std::ofstream(dir / "scene.json") << scene.dump();
  const test::Outcome run =
      test::glint({"run", (dir / "scene.json").string(), "-o", (dir / "out").string(), "--quiet"});
  ASSERT_EQ(run.status, 0) << run.err;
  const fs::path out = dir / "out";
  EXPECT_FALSE(fs::exists(out / "wall.tif")) << "a wall has no map from above";
  for (const char* name : {"ground.tif", "ground_zones.geojson", "ground_zones.kml"})
    EXPECT_TRUE(fs::is_regular_file(out / name)) << name;
  for (const char* channel : {"exposure_j_m2", "hazard_ratio", "stare_hazard_ratio"}) {
    const std::vector<float> tif = band(out / "ground.tif", channel);
    EXPECT_FALSE(tif.empty()) << channel;
    EXPECT_EQ(tif, exrChannel(out / "ground.exr", channel)) << channel << ": the EXR's values";
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace glint
