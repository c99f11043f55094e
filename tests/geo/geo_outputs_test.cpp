// Every plane map glint writes is placed on the Earth when the scene has a site: a study's
// aggregated maps and an engagement's maps get their GeoTIFF (its bands the EXR's channels) and
// their zones, as a single pose's maps do (tests/export/check_geo.py reads those).
#include <gdal_priv.h>
#include <gtest/gtest.h>
#include <ogrsf_frmts.h>

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

// Every polygon of @p g (a polygon, or a collection of them at any depth).
void polygonsOf(const OGRGeometry* g, std::vector<const OGRPolygon*>& out) {
  if (g == nullptr) return;
  if (wkbFlatten(g->getGeometryType()) == wkbPolygon) {
    out.push_back(g->toPolygon());
    return;
  }
  if (OGR_GT_IsSubClassOf(wkbFlatten(g->getGeometryType()), wkbGeometryCollection)) {
    for (const OGRGeometry* part : *g->toGeometryCollection()) polygonsOf(part, out);
  }
}

// issue 50 (6.3): a zone across longitude ±180° was written as one ring from 179.99° to
// −179.99°, which a GIS draws the long way round the Earth (RFC 7946 §3.1.9 asks GeoJSON to cut
// it; KML has no other way). A site 0.00001° west of the antimeridian at 60° N, +x to the west:
// the cylinder's hazardous zone toward the laser runs from 0.1 m west of the site to 2.2 m east
// of it, across ±180° 0.56 m east. Read back, both files' zones are cut there (no ring spans
// more than 180° of longitude, and pieces lie on either side), and their area in the map is
// the pixels' they were drawn from.
TEST(GeoOutputs, AZoneAcrossTheAntimeridianIsCutThereAndKeepsItsArea) {
  const fs::path dir = test::freshTestFolder("glint_geo_antimeridian_");
  json scene = json::parse(test::readFile(fs::path(GLINT_TEST_DATA_DIR) / "site_plane.json"));
  scene["site"] = {{"latitude_deg", 60.0}, {"longitude_deg", 179.99999}, {"bearing_deg", 270.0}};
  scene["planes"].erase(1);  // the wall
  std::ofstream(dir / "scene.json") << scene.dump();
  const test::Outcome run =
      test::glint({"run", (dir / "scene.json").string(), "-o", (dir / "out").string(), "--quiet"});
  ASSERT_EQ(run.status, 0) << run.err;
  const fs::path out = dir / "out";
  // The map's pixel (UTM zone 60N) against the plane's 0.25 m: area_m2 is the plane's.
  GDALAllRegister();
  double gt[6] = {};
  OGRSpatialReference map_srs;
  {
    GDALDataset* tif =
        GDALDataset::FromHandle(GDALOpen((out / "eye_level.tif").c_str(), GA_ReadOnly));
    ASSERT_NE(tif, nullptr);
    ASSERT_EQ(tif->GetGeoTransform(gt), CE_None);
    map_srs = *tif->GetSpatialRef();
    GDALClose(GDALDataset::ToHandle(tif));
  }
  map_srs.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  const double map_per_plane_m2 = std::abs(gt[1] * gt[5] - gt[2] * gt[4]) / (0.25 * 0.25);
  OGRSpatialReference wgs84;
  wgs84.SetWellKnownGeogCS("WGS84");
  wgs84.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  std::unique_ptr<OGRCoordinateTransformation> to_map(
      OGRCreateCoordinateTransformation(&wgs84, &map_srs));
  ASSERT_TRUE(to_map);
  double written_m2 = 0.0;  // the zones' area_m2 in the map, from the GeoJSON (KML keeps none)
  for (const char* name : {"eye_level_zones.geojson", "eye_level_zones.kml"}) {
    GDALDataset* d = GDALDataset::FromHandle(
        GDALOpenEx((out / name).c_str(), GDAL_OF_VECTOR, nullptr, nullptr, nullptr));
    ASSERT_NE(d, nullptr) << name;
    double read_m2 = 0.0;
    int east = 0, west = 0;
    for (OGRLayer* layer : d->GetLayers()) {
      for (auto& f : *layer) {
        const int area_field = f->GetFieldIndex("area_m2");
        if (area_field >= 0 && std::string(name).ends_with(".geojson"))
          written_m2 += f->GetFieldAsDouble(area_field) * map_per_plane_m2;
        std::vector<const OGRPolygon*> polygons;
        polygonsOf(f->GetGeometryRef(), polygons);
        for (const OGRPolygon* p : polygons) {
          OGREnvelope e;
          p->getEnvelope(&e);
          EXPECT_LE(e.MaxX - e.MinX, 180.0)
              << name << ": a ring spans " << e.MinX << "° to " << e.MaxX << "°";
          (e.MinX >= 0.0 ? west : east) += 1;
          std::unique_ptr<OGRGeometry> in_map(p->clone());
          ASSERT_EQ(in_map->transform(to_map.get()), OGRERR_NONE);
          read_m2 += in_map->toPolygon()->get_Area();
        }
      }
    }
    GDALClose(GDALDataset::ToHandle(d));
    EXPECT_GT(east, 0) << name << ": premise, a zone reaches east of ±180°";
    EXPECT_GT(west, 0) << name << ": and west of it";
    ASSERT_GT(written_m2, 0.0) << "premise: a hazardous zone";
    // Coordinates of 1e-9° (0.1 mm) about zones of a few metres: 1e-4 of their area.
    EXPECT_NEAR(read_m2, written_m2, 1e-4 * written_m2) << name << ": the area in the map";
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace glint
