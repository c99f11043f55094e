// The terrain: an elevation model placed on the site, its surface's heights, and what it
// shadows, against references that need neither Embree nor the field: the ellipsoid's fall
// below the tangent plane, and a brute-force segment test against every triangle of the model.
#include "geo/terrain.h"

#include <arpa/inet.h>
#include <cpl_conv.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "facets/integrator.h"
#include "observers/field.h"
#include "observers/field_compare.h"
#include "pipeline/input/scene.h"
#include "pipeline/report/unlit_warning.h"
#include "pipeline/setup/target_builder.h"
#include "support/cli.h"
#include "support/dem.h"
#include "support/files.h"
#include "support/refusal.h"

namespace glint {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// A folder per test, removed after it.
class TerrainTest : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = test::freshTestFolder("glint_terrain_"); }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

const SiteSpec kSite{35.0, -106.0, 0.0, 0.0, MapProjection::Utm};

// A DEM over local x from -1200 to 600 m and y from -300 to 300 m, posts 5 m apart on the map.
void writeSiteDem(const fs::path& path, const std::function<double(double, double)>& height_m) {
  const SiteFrame site(kSite);
  const MapPoint o = site.toMap(Vec3(0.0));
  // +x is north and +y west: the map's rows run south from the corner's northing.
  test::writeDem(path, site, {o.easting_m - 330.0, o.northing_m + 630.0}, 5.0, 132, 372, height_m);
}

// Heights 0 above the ellipsoid: the surface falls below the tangent plane by d² / 2R, R the
// ellipsoid's radius of curvature in that direction (northward the meridian's M, eastward the
// prime vertical's N); the piecewise-linear surface between posts 5 m apart departs from the
// ellipsoid by at most (5 m)² / 8R, 5e-7 m.
TEST_F(TerrainTest, AFlatModelFallsBelowTheTangentPlaneAsTheEllipsoidDoes) {
  writeSiteDem(dir_ / "flat.tif", [](double, double) { return 0.0; });
  const SiteFrame site(kSite);
  const auto t = Terrain::read(dir_ / "flat.tif", site, {-1000.0, -200.0, 400.0, 200.0}, 1e6);
  const double a = 6378137.0, f = 1.0 / 298.257223563, e2 = f * (2.0 - f);
  const double s = std::sin(35.0 * 3.14159265358979323846 / 180.0);
  const double m = a * (1.0 - e2) / std::pow(1.0 - e2 * s * s, 1.5);
  const double n = a / std::sqrt(1.0 - e2 * s * s);
  for (double x : {-1000.0, -400.0, 0.0, 250.0, 400.0}) {
    const std::optional<double> z = t->surfaceZ(x, 0.0);
    ASSERT_TRUE(z.has_value()) << x;
    EXPECT_NEAR(*z, -x * x / (2.0 * m), 2e-4) << "north " << x << " m";
  }
  for (double y : {-200.0, 150.0}) {
    EXPECT_NEAR(*t->surfaceZ(0.0, y), -y * y / (2.0 * n), 2e-4) << "west " << y << " m";
  }
  EXPECT_FALSE(t->surfaceZ(5000.0, 0.0).has_value()) << "off the model";
  EXPECT_NEAR(t->postSpacingM(), 5.0, 0.01) << "5 m on the map, the map's scale ≈ 1";
}

// A model given in latitude and longitude is read in that frame: 100 m above the ellipsoid
// everywhere, posts 5e-5° apart (5.5 m north-south), around a site at 35° N, 106° W. Its
// surface lies 100 m up, less the ellipsoid's fall (d² / 2R) away from the site.
TEST_F(TerrainTest, AModelInLatitudeAndLongitudeIsReadInItsOwnFrame) {
  test::writeGeographicDem(dir_ / "geographic.tif", -106.006, 35.006, 5e-5, 240, 240,
                           [](double, double) { return 100.0; });
  const SiteFrame site(kSite);
  const auto t = Terrain::read(dir_ / "geographic.tif", site, {-400.0, -400.0, 400.0, 400.0}, 1e6);
  EXPECT_NE(t->crsName().find("WGS 84"), std::string::npos) << t->crsName();
  const double r = 6371000.0;  // the fall's radius to 0.3 %: at 400 m it moves 4e-5 m
  for (const auto& [x, y] : {std::pair{0.0, 0.0}, {350.0, 0.0}, {0.0, -300.0}, {-250.0, 250.0}}) {
    const std::optional<double> z = t->surfaceZ(x, y);
    ASSERT_TRUE(z.has_value()) << x << ", " << y;
    EXPECT_NEAR(*z, 100.0 - (x * x + y * y) / (2.0 * r), 1e-3) << x << ", " << y;
  }
}

TEST_F(TerrainTest, AModelThatMissesTheRegionIsRefusedNamingIt) {
  writeSiteDem(dir_ / "dem.tif", [](double, double) { return 0.0; });
  const SiteFrame site(kSite);
  try {
    (void)Terrain::read(dir_ / "dem.tif", site, {-100.0, -100.0, 2000.0, 100.0}, 1e6);
    ADD_FAILURE() << "a region beyond the model was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("does not cover the scene's region"), std::string::npos)
        << e.what();
  }
  try {
    (void)Terrain::read(dir_ / "dem.tif", site, {-100.0, -100.0, 100.0, 100.0}, 100);
    ADD_FAILURE() << "a window beyond max_posts was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("more than 100"), std::string::npos) << e.what();
  }
}

// A ridge across the view: 20 m high at x = 150 m, its slopes 50 m wide.
double ridge(double x, double) { return std::max(0.0, 20.0 * (1.0 - std::abs(x - 150.0) / 50.0)); }

// Whether the segment from p to q crosses triangle (a, b, c) strictly inside both
// (Möller–Trumbore in double precision).
bool crosses(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 d = q - p, e1 = b - a, e2 = c - a, h = glm::cross(d, e2);
  const double det = glm::dot(e1, h);
  if (std::abs(det) < 1e-14) return false;
  const Vec3 s = p - a;
  const double u = glm::dot(s, h) / det;
  if (u < 0.0 || u > 1.0) return false;
  const Vec3 qv = glm::cross(s, e1);
  const double v = glm::dot(d, qv) / det;
  if (v < 0.0 || u + v > 1.0) return false;
  const double t = glm::dot(e2, qv) / det;
  return t > 1e-9 && t < 1.0 - 1e-9;
}

json ridgeScene(const fs::path& dem) {
  return json::parse(R"({
    "site": {"latitude_deg": 35.0, "longitude_deg": -106.0},
    "laser": {"position": [-200, 0, 400], "direction": [200, 0, -395], "power_w": 1000.0,
              "wavelength_nm": 532, "beam": {"profile": "flat_top", "radius_m": 2.0}},
    "materials": {"painted": {"specular_reflectance": 0.5, "sigma": 0.05,
                              "diffuse_reflectance": 0.4}},
    "objects": [{"shape": "sphere", "center": [0, 0, 5], "radius": 0.5, "material": "painted"}],
    "planes": [{"name": "ground", "origin": [60, -60, 0], "u_axis": [1, 0, 0],
                "v_axis": [0, 1, 0], "size_m": [240, 120], "pixel_m": 4, "block_m": 32,
                "above_terrain_m": 1.7, "floor_w_m2": 1e-9}],
    "far_field": {"enabled": false},
    "terrain": {"file": ")" +
                     dem.string() + R"("}
  })");
}

// Behind a ridge: an observer on the ground sees the sphere exactly when the segment from the
// sphere's lit facets to it misses every triangle of the model. glint's plane laid over the
// terrain has irradiance 0 at exactly the points a brute-force test of the segment from the
// sphere's centre finds shadowed, save those within a post of the shadow's edge (where which
// of the sphere's facets is seen decides, and the model's resolution ends).
TEST_F(TerrainTest, ARidgeRemovesExactlyTheShadowedObservers) {
  writeSiteDem(dir_ / "ridge.tif", ridge);
  const Scene scene = parseScene(ridgeScene(dir_ / "ridge.tif").dump(), "ridge.json");
  ASSERT_TRUE(scene.terrain);
  const auto target = buildTarget(scene);
  const FacetIntegrator integrator(target, scene.laser, scene.accuracy);
  IntegratorWorkspace ws;
  const FieldSpec spec = planeFieldSpec(scene, scene.planes[0]);
  const auto n = spec.nodes();
  const ShadowMesh& mesh = *scene.terrain->mesh();
  const Vec3 sphere(0.0, 0.0, 5.0);
  int shadowed = 0, lit = 0, edge = 0;
  for (int j = 0; j < n[1]; j += 3)
    for (int i = 0; i < n[0]; i += 2) {
      const Vec3 p = spec.position(i, j, 0);
      EXPECT_NEAR(p.z - *scene.terrain->surfaceZ(p.x, p.y), 1.7, 1e-6) << "eye height";
      bool blocked = false;
      for (const auto& tri : mesh.triangles) {
        blocked = crosses(sphere, p, mesh.vertices_m[tri[0]], mesh.vertices_m[tri[1]],
                          mesh.vertices_m[tri[2]]);
        if (blocked) break;
      }
      // The shadow's edge: the line over the crest (x = 150 m, 20 m) from the sphere.
      const double over_crest_z = 5.0 + (20.0 - 5.0) * p.x / 150.0;
      if (p.x > 140.0 && std::abs(p.z - over_crest_z) < 2.0) {
        ++edge;
        continue;
      }
      const double e = integrator.adaptive(p, ws).irradiance_w_m2;
      if (blocked) {
        ++shadowed;
        EXPECT_EQ(e, 0.0) << "shadowed at (" << p.x << ", " << p.y << ", " << p.z << ")";
      } else {
        ++lit;
        EXPECT_GT(e, 0.0) << "in view at (" << p.x << ", " << p.y << ", " << p.z << ")";
      }
    }
  EXPECT_GT(shadowed, 100) << "the ridge hides the ground behind it";
  EXPECT_GT(lit, 100) << "the ground before it is lit";
  EXPECT_LT(edge, (shadowed + lit) / 10) << "few points at the shadow's edge are excused";
}

// The plane over the ridge refined adaptively, against its dense twin (every lattice point
// integrated): within the field's tolerance everywhere, no bright point proven dark by a bound
// (the bounds leave the ground out, so they stay upper bounds), and at every point the field
// integrated, exactly what the integrator gives there on its own (what `glint points` gives).
TEST_F(TerrainTest, APlaneOverTheTerrainMatchesItsDenseTwinAndThePointsAtItsObservers) {
  writeSiteDem(dir_ / "ridge.tif", ridge);
  json j = ridgeScene(dir_ / "ridge.tif");
  j["planes"][0]["floor_w_m2"] = 1e-6;
  const Scene scene = parseScene(j.dump(), "ridge.json");
  const FieldSpec spec = planeFieldSpec(scene, scene.planes[0]);
  const FieldProblem p = fieldProblem(scene, spec);
  const ObserverField adaptive = computeField(p.integrator, spec, p.excluded);
  const ObserverField dense = computeDenseField(p.integrator, spec, p.excluded);
  const FieldComparison c = compareFields(adaptive, dense);
  EXPECT_LE(c.max_error_w_m2, c.allowed_error_w_m2)
      << "at (" << c.max_error_at_m.x << ", " << c.max_error_at_m.y << ", " << c.max_error_at_m.z
      << "), peak " << c.peak_w_m2;
  EXPECT_EQ(c.bright_skipped, 0);
  EXPECT_GT(c.peak_w_m2, 100.0 * spec.floor_w_m2) << "the test needs light on the ground";
  const auto n = spec.nodes();
  IntegratorWorkspace ws;
  int evaluated = 0;
  for (int jj = 0; jj < n[1]; ++jj)
    for (int i = 0; i < n[0]; ++i) {
      if (adaptive.status(i, jj, 0) != VoxelStatus::Evaluated) continue;
      ++evaluated;
      const Vec3 at = spec.position(i, jj, 0);
      const double alone = p.integrator.adaptive(at, ws).irradiance_w_m2;
      EXPECT_NEAR(adaptive.irradiance(i, jj, 0), alone, 1e-6 * alone + 1e-30)
          << "(" << at.x << ", " << at.y << ", " << at.z << ")";
    }
  EXPECT_GT(evaluated, 50);
}

// The terrain's own segment test (the reach footprint's shadow): from the sphere's stand over the
// ridge's crest, blocked exactly where the brute-force test says.
TEST_F(TerrainTest, SegmentsOverTheRidgeAreBlockedAsTheTrianglesSay) {
  writeSiteDem(dir_ / "ridge.tif", ridge);
  const SiteFrame site(kSite);
  const auto t = Terrain::read(dir_ / "ridge.tif", site, {-100.0, -100.0, 400.0, 100.0}, 1e6);
  const Vec3 from(0.0, 0.0, 5.0);
  int blocked = 0, clear = 0;
  for (double x = 20.0; x <= 380.0; x += 7.0)
    for (double y : {-60.0, 0.0, 45.0}) {
      const Vec3 to(x, y, *t->surfaceZ(x, y) + 1.7);
      bool brute = false;
      for (const auto& tri : t->mesh()->triangles) {
        brute = crosses(from, to, t->mesh()->vertices_m[tri[0]], t->mesh()->vertices_m[tri[1]],
                        t->mesh()->vertices_m[tri[2]]);
        if (brute) break;
      }
      // Within 0.5 m of grazing the crest either answer is right (float against double).
      const double over_crest_z = 5.0 + (20.0 - 5.0) * x / 150.0;
      if (x > 140.0 && std::abs(to.z - over_crest_z) < 0.5) continue;
      EXPECT_EQ(t->segmentClear(from, to), !brute) << "to (" << x << ", " << y << ")";
      (brute ? blocked : clear) += 1;
    }
  EXPECT_GT(blocked, 20);
  EXPECT_GT(clear, 20);
}

// A ridge between the laser and the target: the beam never reaches it.
TEST_F(TerrainTest, ARidgeBeforeTheTargetMasksTheBeam) {
  writeSiteDem(dir_ / "wall.tif", [](double x, double) {
    return std::max(0.0, 80.0 * (1.0 - std::abs(x + 400.0) / 30.0));
  });
  json j = ridgeScene(dir_ / "wall.tif");
  // Low over the ridge's crest: the line to the sphere passes 32.5 m up at x = -400 m.
  j["laser"]["position"] = {-800, 0, 60};
  j["laser"]["direction"] = {800, 0, -55};
  const Scene scene = parseScene(j.dump(), "wall.json");
  const FacetIntegrator integrator(buildTarget(scene), scene.laser, scene.accuracy);
  EXPECT_EQ(integrator.cullStats().lit, 0u) << "every facet's ray to the laser meets the ridge";
  EXPECT_GT(integrator.cullStats().shadowed, 0u);
  // Without the terrain the sphere is lit.
  j.erase("terrain");
  j["planes"][0].erase("above_terrain_m");
  const Scene open = parseScene(j.dump(), "open.json");
  EXPECT_GT(FacetIntegrator(buildTarget(open), open.laser, open.accuracy).cullStats().lit, 0u);
}

// issue 50 (6.1): a terrain took about 430 bytes a post where 100 were documented, outside
// the memory budget: 3.9 M posts reached 1.69 GB under --memory 1G and the stop blamed the
// meshes. Its posts over the scene's region are now held to the budget, with the target's,
// before a height is read: here the model's heights cannot be read at all (its VRT's source is
// gone), and the refusal comes first, naming the terrain and what to change.
TEST_F(TerrainTest, ATerrainBeyondTheBudgetIsRefusedBeforeAHeightIsRead) {
  writeSiteDem(dir_ / "dem.tif", [](double, double) { return 0.0; });
  {
    GDALDataset* source =
        GDALDataset::FromHandle(GDALOpen((dir_ / "dem.tif").c_str(), GA_ReadOnly));
    ASSERT_NE(source, nullptr);
    GDALDriver* vrt = GetGDALDriverManager()->GetDriverByName("VRT");
    GDALClose(GDALDataset::ToHandle(
        vrt->CreateCopy((dir_ / "dem.vrt").c_str(), source, FALSE, nullptr, nullptr, nullptr)));
    GDALClose(GDALDataset::ToHandle(source));
  }
  fs::copy_file(dir_ / "dem.tif", dir_ / "kept.tif");
  fs::remove(dir_ / "dem.tif");
  const std::string scene = ridgeScene(dir_ / "dem.vrt").dump();
  // Premise: without a budget the heights are read, and cannot be.
  EXPECT_NE(test::refusalOf([&] { parseScene(scene, "s.json"); }).find("cannot be read"),
            std::string::npos);
  const std::string refusal =
      test::refusalOf([&] { parseScene(scene, "s.json", std::nullopt, {}, 1 << 20); });
  for (const char* part : {"s.json: /terrain/file: the terrain (", " posts over the scene's region",
                           "of memory, more than the budget of 1 MB (--memory); crop the "
                           "elevation model or resample it to a coarser post spacing"})
    EXPECT_NE(refusal.find(part), std::string::npos) << refusal;
  // Within the budget it is read, and holds what was reckoned for its window.
  const Scene read = parseScene(ridgeScene(dir_ / "kept.tif").dump(), "s.json", std::nullopt, {},
                                std::uint64_t{1} << 30);
  ASSERT_TRUE(read.terrain);
  EXPECT_GE(read.terrain->windowPosts(), read.terrain->posts());
  EXPECT_EQ(read.terrain->memoryBytes(), Terrain::memoryBytes(read.terrain->windowPosts()));
  EXPECT_GE(read.terrain->memoryBytes(), 400 * read.terrain->windowPosts())
      << "the measured cost of a post (docs/terrain.md, Memory)";
}

// Each command reads the scene (the study's base scene too) within its --memory.
TEST_F(TerrainTest, EveryCommandRefusesATerrainBeyondItsBudgetAndWritesNothing) {
  writeSiteDem(dir_ / "dem.tif", [](double, double) { return 0.0; });
  std::ofstream(dir_ / "scene.json") << ridgeScene(dir_ / "dem.tif").dump();
  std::ofstream(dir_ / "p.csv") << "x,y,z\n100,0,2\n";
  std::ofstream(dir_ / "study.json") << R"({"scene": "scene.json", "sweep": {"yaw_deg": [0, 10]}})";
  const std::string scene = (dir_ / "scene.json").string();
  for (const std::vector<std::string>& args :
       {std::vector<std::string>{"run", scene, "-o", (dir_ / "out").string()},
        std::vector<std::string>{"points", scene, "--points", (dir_ / "p.csv").string(), "--out",
                                 (dir_ / "p_out.csv").string()},
        std::vector<std::string>{"batch", (dir_ / "study.json").string(), "-o",
                                 (dir_ / "out").string()}}) {
    std::vector<std::string> with_budget = args;
    with_budget.insert(with_budget.end(), {"--memory", "1M"});
    const test::Outcome r = test::glint(with_budget);
    EXPECT_EQ(r.status, 2) << args[0] << ": " << r.err;
    EXPECT_NE(r.err.find("/terrain/file: the terrain ("), std::string::npos)
        << args[0] << ": " << r.err;
    EXPECT_FALSE(fs::exists(dir_ / "out")) << args[0];
    EXPECT_FALSE(fs::exists(dir_ / "p_out.csv")) << args[0];
  }
}

// issue 50 (6.2): terrain.file took GDAL's network paths, so a scene file could make glint open
// connections. The scene reader refuses them, naming the key (exit status 2).
TEST_F(TerrainTest, ANetworkPathIsRefusedByTheSceneReader) {
  writeSiteDem(dir_ / "dem.tif", [](double, double) { return 0.0; });
  for (const auto& [name, says] : std::vector<std::pair<std::string, std::string>>{
           {"/vsicurl/http://127.0.0.1:9/dem.tif", "is a network path (vsicurl)"},
           {"/vsicurl?url=http://127.0.0.1:9/dem.tif", "is a network path (vsicurl)"},
           {"/vsis3/bucket/dem.tif", "is a network path (vsis3)"},
           {"/VSIGS/bucket/dem.tif", "is a network path (vsigs)"},
           {"/vsiaz/container/dem.tif", "is a network path (vsiaz)"},
           {"/vsiadls/fs/dem.tif", "is a network path (vsiadls)"},
           {"/vsioss/bucket/dem.tif", "is a network path (vsioss)"},
           {"/vsiswift/c/dem.tif", "is a network path (vsiswift)"},
           {"/vsihdfs/hdfs://h:9/dem.tif", "is a network path (vsihdfs)"},
           {"/vsiwebhdfs/http://h:9/dem.tif", "is a network path (vsiwebhdfs)"},
           {"/vsizip//vsicurl/http://h/a.zip/dem.tif",
            "is a path in one of GDAL's virtual file systems"},
           {"/vsistdin/", "is a path in one of GDAL's virtual file systems"},
           {"http://127.0.0.1:9/dem.tif", "is a URL"},
           {"HTTPS://example.org/dem.tif", "is a URL"},
           {"ftp://example.org/dem.tif", "is a URL"}}) {
    json j = ridgeScene(dir_ / "dem.tif");
    j["terrain"]["file"] = name;
    const std::string refusal = test::refusalOf([&] { parseScene(j.dump(), "s.json"); });
    EXPECT_NE(refusal.find("s.json: /terrain/file: " + says), std::string::npos)
        << name << ": " << refusal;
  }
  json j = ridgeScene(dir_ / "dem.tif");
  j["terrain"]["file"] = "/vsicurl/http://127.0.0.1:9/dem.tif";
  std::ofstream(dir_ / "net.json") << j.dump();
  const test::Outcome r =
      test::glint({"run", (dir_ / "net.json").string(), "-o", (dir_ / "out").string(), "--quiet"});
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_NE(r.err.find("a scene file opens no connection"), std::string::npos) << r.err;
}

// A loopback port that accepts connections without answering, and counts them.
class Listener {
 public:
  Listener() {
    fd_ = ::socket(AF_INET, SOCK_STREAM | SOCK_NONBLOCK, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    socklen_t length = sizeof a;
    if (fd_ < 0 || ::bind(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0 ||
        ::listen(fd_, 64) != 0 || ::getsockname(fd_, reinterpret_cast<sockaddr*>(&a), &length) != 0)
      throw std::runtime_error("cannot listen on the loopback");
    port_ = ntohs(a.sin_port);
  }
  ~Listener() { ::close(fd_); }
  Listener(const Listener&) = delete;
  Listener& operator=(const Listener&) = delete;
  [[nodiscard]] int port() const { return port_; }
  // The connections made since the last call.
  int connections() {
    int n = 0;
    for (int c; (c = ::accept(fd_, nullptr, nullptr)) >= 0; ++n) ::close(c);
    return n;
  }

 private:
  int fd_ = -1;
  int port_ = 0;
};

// Whatever name reaches the GDAL module (a file the scene reader lets through, such as a VRT
// whose source is a URL), it opens no connection: every name here connected to the port (and
// waited for an answer) before GDAL was kept off the network.
TEST_F(TerrainTest, TheGdalModuleOpensNoConnectionWhateverItIsGiven) {
  Listener port;
  const std::string at = "127.0.0.1:" + std::to_string(port.port());
  // Should a connection be made, it is not waited on for long, and S3 is this port too.
  const std::vector<std::pair<const char*, std::string>> config = {
      {"GDAL_HTTP_TIMEOUT", "2"}, {"GDAL_HTTP_MAX_RETRY", "0"},
      {"AWS_S3_ENDPOINT", at},    {"AWS_NO_SIGN_REQUEST", "YES"},
      {"AWS_HTTPS", "NO"},        {"AWS_VIRTUAL_HOSTING", "FALSE"}};
  for (const auto& [key, value] : config) CPLSetConfigOption(key, value.c_str());
  // A model over the region (1 km square about the site, 1 m posts), its heights at the port:
  // GDAL fetches a VRT's source when the heights are read.
  const SiteFrame site(kSite);
  const MapPoint o = site.toMap(Vec3(0.0));
  std::ofstream(dir_ / "net.vrt")
      << "<VRTDataset rasterXSize=\"1000\" rasterYSize=\"1000\"><SRS>EPSG:" << site.mapEpsg()
      << "</SRS><GeoTransform>" << std::to_string(o.easting_m - 500.0) << ", 1, 0, "
      << std::to_string(o.northing_m + 500.0) << ", 0, -1</GeoTransform>"
      << "<VRTRasterBand dataType=\"Float32\" band=\"1\"><SimpleSource><SourceFilename>"
      << "/vsicurl/http://" << at << "/dem.tif</SourceFilename><SourceBand>1</SourceBand>"
      << "</SimpleSource></VRTRasterBand></VRTDataset>";
  for (const std::string& name : std::vector<std::string>{
           (dir_ / "net.vrt").string(), "/vsicurl/http://" + at + "/dem.tif",
           "/vsicurl?url=http://" + at + "/dem.tif", "http://" + at + "/dem.tif",
           "/vsis3/bucket/dem.tif", "/vsizip//vsicurl/http://" + at + "/a.zip/dem.tif"}) {
    EXPECT_THROW((void)Terrain::read(name, site, {-100.0, -100.0, 100.0, 100.0}, 1e6),
                 std::runtime_error)
        << name;
    EXPECT_EQ(port.connections(), 0) << name << " connected to " << at;
  }
  for (const auto& [key, value] : config) CPLSetConfigOption(key, nullptr);
}

// issue 50 (6.4): a target under the ground is lit by nothing, and says so, and why.
TEST_F(TerrainTest, ATargetUnderTheGroundIsWarnedOfAsUnlit) {
  writeSiteDem(dir_ / "high.tif", [](double, double) { return 20.0; });
  json j = ridgeScene(dir_ / "high.tif");
  j["planes"][0]["above_terrain_m"] = 1.7;
  const Scene scene = parseScene(j.dump(), "buried.json");
  const FacetIntegrator integrator(buildTarget(scene), scene.laser, scene.accuracy);
  ASSERT_EQ(integrator.cullStats().lit, 0u) << "premise: the sphere at z = 5 m is 15 m down";
  const std::vector<std::string> w = unlitTargetWarnings(scene, integrator.cullStats());
  ASSERT_EQ(w.size(), 1u);
  for (const char* part : {"no facet of the target is lit: ", "are in the terrain's shadow",
                           "object 0's centre lies 15 m below the ground", "not a safe one"})
    EXPECT_NE(w[0].find(part), std::string::npos) << w[0];
  // The open sphere on its stand over flat ground is lit: no warning.
  writeSiteDem(dir_ / "flat.tif", [](double, double) { return 0.0; });
  const Scene open = parseScene(ridgeScene(dir_ / "flat.tif").dump(), "open.json");
  const FacetIntegrator lit(buildTarget(open), open.laser, open.accuracy);
  EXPECT_TRUE(unlitTargetWarnings(open, lit.cullStats()).empty());
}

TEST_F(TerrainTest, SceneKeysAreRefusedWhereTheyCannotHold) {
  writeSiteDem(dir_ / "dem.tif", [](double, double) { return 0.0; });
  json j = ridgeScene(dir_ / "dem.tif");
  j.erase("site");
  EXPECT_NE(test::refusalOf([&] { parseScene(j.dump(), "s.json"); }).find("needs a site"),
            std::string::npos);
  j = ridgeScene(dir_ / "dem.tif");
  j.erase("terrain");
  EXPECT_NE(test::refusalOf([&] { parseScene(j.dump(), "s.json"); }).find("there is no terrain"),
            std::string::npos);
  j = ridgeScene(dir_ / "dem.tif");
  j["planes"][0]["v_axis"] = {0, 0, 1};
  EXPECT_NE(test::refusalOf([&] { parseScene(j.dump(), "s.json"); }).find("horizontal plane"),
            std::string::npos);
  j = ridgeScene(dir_ / "dem.tif");
  j.erase("site");
  j.erase("terrain");
  j["planes"][0].erase("above_terrain_m");
  j["reach"] = {{"footprint", {{"radius_m", 500}}}};
  EXPECT_NE(test::refusalOf([&] { parseScene(j.dump(), "s.json"); }).find("needs a site"),
            std::string::npos);
  j = ridgeScene(dir_ / "missing.tif");
  EXPECT_NE(test::refusalOf([&] { parseScene(j.dump(), "s.json"); }).find("/terrain/file"),
            std::string::npos);
}

}  // namespace
}  // namespace glint
