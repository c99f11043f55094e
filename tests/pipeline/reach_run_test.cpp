// glint run's hazard reach: a scene without a box, its summary, terminal line and maps, and the
// default example's reach against its box.
#include <gtest/gtest.h>
#include <openvdb/openvdb.h>
#include <vtkDataArray.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>
#include <vtkXMLPolyDataReader.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "export/exr_map.h"
#include "observers/detail/cube_faces.h"
#include "pipeline/base/input_error.h"
#include "pipeline/base/memory_budget.h"
#include "pipeline/input/scene.h"
#include "pipeline/setup/scene_regions.h"
#include "pipeline/setup/target_builder.h"
#include "support/cli.h"
#include "support/files.h"

namespace glint {
namespace {

namespace fs = std::filesystem;

struct RunResult {
  test::Outcome outcome;
  nlohmann::json summary;
  fs::path out;
};

RunResult runScene(const fs::path& scene, const std::string& name) {
  const fs::path out = fs::temp_directory_path() / name;
  fs::remove_all(out);
  RunResult r{test::glint({"run", scene.string(), "-o", out.string()}), {}, out};
  if (r.outcome.status == 0) r.summary = nlohmann::json::parse(std::ifstream(out / "summary.json"));
  return r;
}

// @p scene, edited from a file, run from a folder of its own (removed once the run is over) into
// the temporary folder @p name.
RunResult runEdited(const nlohmann::json& scene, const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / (name + "_scene");
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream(dir / "scene.json") << scene.dump();
  RunResult r = runScene(dir / "scene.json", name);
  fs::remove_all(dir);
  return r;
}

// The reach per direction as reach.vtp keeps it, read between its rays as the reach reads them
// (NearReach::toward()): a ray's distance is a layer plane's distance times the ray's stretch
// (distance per unit along the face's normal); toward a direction, the farthest plane of the
// four rays around it, along the direction itself.
class ReachRays {
 public:
  ReachRays(const fs::path& vtp, const nlohmann::json& reach)
      : n_(reach.at("lattice").at("face_cells").get<int>()) {
    const auto c = reach.at("centre_m").get<std::vector<double>>();
    centre_ = Vec3(c[0], c[1], c[2]);
    unclassified_m_ = reach.at("unclassified").at("half_edge_m").get<double>();
    auto reader = vtkSmartPointer<vtkXMLPolyDataReader>::New();
    reader->SetFileName(vtp.string().c_str());
    reader->Update();
    vtkDataArray* d = reader->GetOutput()->GetPointData()->GetArray("distance_m");
    if (d == nullptr) return;
    for (vtkIdType p = 0; p < d->GetNumberOfTuples(); ++p) distance_m_.push_back(d->GetTuple1(p));
  }
  [[nodiscard]] bool complete() const {
    return distance_m_.size() == 6u * static_cast<std::size_t>((n_ + 1) * (n_ + 1));
  }
  [[nodiscard]] const Vec3& centre() const { return centre_; }
  /// @brief Whether @p x lies in the cube about the centre that the lattice does not sample.
  [[nodiscard]] bool unclassified(const Vec3& x) const {
    const Vec3 v = glm::abs(x - centre_);
    return std::max({v.x, v.y, v.z}) <= unclassified_m_;
  }
  [[nodiscard]] double toward(const Vec3& direction) const {
    const cube::FaceHit h = cube::faceHit(direction, n_);
    const int i = std::clamp(static_cast<int>(std::floor(h.x)), 0, n_ - 1);
    const int j = std::clamp(static_cast<int>(std::floor(h.y)), 0, n_ - 1);
    double plane_m = 0.0;
    for (int c = 0; c < 4; ++c) {
      const int a = i + (c & 1), b = j + (c >> 1);
      const double u = -1.0 + 2.0 * a / n_, v = -1.0 + 2.0 * b / n_;
      const std::size_t ray = static_cast<std::size_t>((h.face * (n_ + 1) + b) * (n_ + 1) + a);
      plane_m = std::max(plane_m, distance_m_[ray] / std::sqrt(1.0 + u * u + v * v));
    }
    return plane_m /
           glm::dot(direction, cube::kFaceFrames[static_cast<std::size_t>(h.face)].normal);
  }

 private:
  int n_;
  Vec3 centre_{0.0};
  double unclassified_m_ = 0.0;
  std::vector<double> distance_m_;
};

// tests/data/reach_pencil.json: a thin oblique pencil about 420 m long, and no box or plane.
// Issue 50 (1): the reach is followed from the mirror's face. Before, the lattice left out
// everything within 0.5 m of the mirror and began on a cube about the lit centre, and reach.exr
// read 0 toward azimuth 111.5°, elevation 39°, where glint points gives 14 327 × the MPE 0.3 m
// out: every point of the pencil's first metre that glint points finds hazardous now lies
// within the reach in its direction.
TEST(ReachRun, ASceneWithNeitherBoxNorPlanesFollowsThePencilFromTheMirrorOn) {
  const RunResult r =
      runScene(fs::path(GLINT_TEST_DATA_DIR) / "reach_pencil.json", "glint_reach_pencil_run");
  ASSERT_EQ(r.outcome.status, 0) << r.outcome.err;
  const nlohmann::json& reach = r.summary.at("hazard_reach");
  const double distance = reach.at("distance_m").get<double>();
  // I = 8.95e6 W/sr along the pencil (glint points at 100 m to 2.7 km: E r² within 1e-3),
  // √(I / 50 W/m²) = 423.1 m; the far field's map is within its tolerance of I, and the
  // distance carries the far field's allowance (1.1 × the tolerance of I).
  EXPECT_GT(distance, 423.0) << reach.dump();
  EXPECT_LT(distance, 423.1 * std::sqrt(1.01 * 1.011)) << reach.dump();
  EXPECT_TRUE(reach.at("closed").get<bool>()) << reach.dump();
  EXPECT_EQ(reach.at("from"), "far field");
  EXPECT_GT(reach.at("volume_m3").get<double>(), 0.0);
  char line[64];
  std::snprintf(line, sizeof line, "hazard reach: %.4g m", distance);
  EXPECT_NE(r.outcome.err.find(line), std::string::npos) << r.outcome.err;
  EXPECT_EQ(r.summary.at("files"), nlohmann::json({"summary.json", "far_field.exr", "far_field.vtp",
                                                   "reach.exr", "reach.vtp"}));

  // Where the time went (issue 65: of 7 min 44 s, the phases accounted for 4 min 18 s): each
  // phase of a box-less run by name, and what none holds a twentieth of the wall time at most.
  const nlohmann::json& timing = r.summary.at("timing");
  std::vector<std::string> phases;
  double within_s = 0.0;
  for (const nlohmann::json& p : timing.at("phases")) {
    phases.push_back(p.at("phase").get<std::string>());
    within_s += p.at("seconds").get<double>();
  }
  EXPECT_EQ(phases, (std::vector<std::string>{
                        "reading the scene and checking its memory", "building the target",
                        "the far field and its far radius", "the far field's hazard distances",
                        "writing the far field's files", "the hazard reach: its lattice",
                        "the hazard reach: each threshold's distance and volume",
                        "writing the hazard reach's files"}))
      << timing.dump();
  const double wall_s = timing.at("wall_seconds").get<double>();
  EXPECT_GE(within_s, 0.95 * wall_s) << "the phases account for the run's time: " << timing.dump();
  EXPECT_LE(within_s, wall_s * (1.0 + 1e-9)) << timing.dump();
  EXPECT_NEAR(timing.at("outside_phases_seconds").get<double>(), wall_s - within_s, 1e-6)
      << timing.dump();

  // reach.exr: its largest pixel is the reach; the opposite half of the sky (x > 0, behind
  // the mirror's lit side) reads no farther than the lattice's last layer.
  int w = 0, h = 0;
  const std::vector<float> map = readExrChannel((r.out / "reach.exr").string(), "reach_m", w, h);
  ASSERT_EQ(static_cast<std::size_t>(w) * static_cast<std::size_t>(h), map.size());
  const float largest = *std::max_element(map.begin(), map.end());
  EXPECT_NEAR(largest, distance, 1e-3 * distance) << "the map's farthest pixel is the reach";
  const double last = reach.at("lattice").at("last_layer_m").get<double>();
  double behind = 0.0;  // azimuth within 45° of +x: columns [3w/8, 5w/8)
  for (int j = 0; j < h; ++j)
    for (int i = 3 * w / 8; i < 5 * w / 8; ++i)
      behind = std::max(behind, static_cast<double>(map[static_cast<std::size_t>(j * w + i)]));
  EXPECT_LT(behind, std::sqrt(3.0) * last) << "no far-field hazard behind the mirror";

  // reach.vtp: the boundary, its points at their distance from the lit centre.
  auto reader = vtkSmartPointer<vtkXMLPolyDataReader>::New();
  reader->SetFileName((r.out / "reach.vtp").string().c_str());
  reader->Update();
  vtkPolyData* surface = reader->GetOutput();
  ASSERT_EQ(surface->GetNumberOfPoints(), 6 * 65 * 65);
  vtkDataArray* d = surface->GetPointData()->GetArray("distance_m");
  ASSERT_NE(d, nullptr);
  ASSERT_NE(surface->GetPointData()->GetArray("hazard_ratio"), nullptr);
  double range[2];
  d->GetRange(range);
  EXPECT_LE(range[1], distance * (1.0 + 1e-6)) << "no vertex beyond the reach";
  EXPECT_GT(range[1], 0.0);

  // Probes about the pencil's first metre, the issue's point among them: each that glint
  // points would find hazardous lies within the reach toward it.
  const ReachRays rays(r.out / "reach.vtp", reach);
  ASSERT_TRUE(rays.complete());
  const Scene scene = loadScene(fs::path(GLINT_TEST_DATA_DIR) / "reach_pencil.json");
  const FacetIntegrator integrator = buildIntegrator(scene, scene.accuracy);
  IntegratorWorkspace ws;
  const Vec3 pencil = glm::normalize(Vec3(-0.3158, 0.7895, 0.5263));
  const Vec3 e1 = glm::normalize(glm::cross(pencil, Vec3(0.0, 0.0, 1.0)));
  const Vec3 e2 = glm::cross(pencil, e1);
  std::vector<Vec3> probes = {Vec3(-0.0854, 0.2169, 0.1888)};
  for (int a = -6; a <= 6; ++a)
    for (int b = -6; b <= 6; ++b)
      for (const double r_m : {0.02, 0.05, 0.1, 0.2, 0.3, 0.45, 0.7, 1.0}) {
        const double off = std::tan(4.0 * kPi / 180.0);  // 4° steps, out to 24°
        const Vec3 tilt = static_cast<double>(a) * e1 + static_cast<double>(b) * e2;
        probes.push_back(rays.centre() + r_m * glm::normalize(pencil + off * tilt));
      }
  const double mpe = r.summary.at("hazard").at("mpe_w_m2").get<double>();
  int hazardous = 0, beyond = 0;
  for (const Vec3& x : probes) {
    if (rays.unclassified(x)) continue;
    const ObserverResult e = integrator.adaptive(x, ws);
    if (!(e.irradiance_w_m2 >= mpe)) continue;
    ++hazardous;
    const Vec3 v = x - rays.centre();
    const double reach_m = rays.toward(glm::normalize(v));
    if (!(glm::length(v) <= reach_m * (1.0 + 1e-6))) {
      ++beyond;
      ADD_FAILURE() << "(" << x.x << ", " << x.y << ", " << x.z << "), hazard ratio "
                    << e.irradiance_w_m2 / mpe << ", lies " << glm::length(v)
                    << " m from the lit centre, beyond the reach of " << reach_m << " m toward it";
    }
  }
  EXPECT_GT(hazardous, 200) << "premise: the pencil's first metre is hazardous";
  std::printf("[ reach ] pencil: %d hazardous probes of %zu, %d beyond the reach\n", hazardous,
              probes.size(), beyond);
  fs::remove_all(r.out);
}

// The default example (examples/cylinder.json) asks for the reach beside its box: the reach's
// farthest point from the target's centre is never nearer than the box's by more than one 0.1 m
// voxel, and farther by no more than a lattice cell's obliquity (its distance is the farthest
// layer plane of a cell's four rays along the cell's most oblique corner, as its maps read it:
// √3 / √(1 + 2 (1 − 2/16)²) = 1.0887 at 16 rays an edge). The example's box and layers as they are;
// its rays (16 per face edge, not 64) and far-field directions (256, not 1024) coarser, which
// only widen the reach between rays: the claim is about how near the target the reach begins,
// and the old lattice fails it here as with the example's own (1 806 and 2 416 of 13 784
// hazardous voxels beyond the reach), at a quarter of the cost.
TEST(ReachRun, TheDefaultExamplesReachIsItsBoxsHazardZoneWithinOneVoxel) {
  nlohmann::json scene =
      nlohmann::json::parse(std::ifstream(fs::path(GLINT_EXAMPLES_DIR) / "cylinder.json"));
  scene["reach"] = {{"face_cells", 16}};
  scene["far_field"] = {{"face_pixels", 256}};
  const RunResult r = runEdited(scene, "glint_reach_default");
  ASSERT_EQ(r.outcome.status, 0) << r.outcome.err;
  const nlohmann::json& reach = r.summary.at("hazard_reach");
  ASSERT_TRUE(reach.at("closed").get<bool>()) << reach.dump();
  const auto p = reach.at("farthest_point_m").get<std::vector<double>>();
  const double from_centre = std::hypot(p[0], p[1], p[2]);  // the target's centre: the origin
  const double box =
      r.summary.at("hazard").at("nominal_hazard_zone").at("farthest_from_target_m").get<double>();
  const double voxel = 0.1;
  EXPECT_GE(from_centre, box - voxel) << reach.dump();
  EXPECT_LE(from_centre, (box + voxel) * std::sqrt(3.0 / (1.0 + 2.0 * 0.875 * 0.875)))
      << reach.dump();
  EXPECT_EQ(reach.at("from"), "lattice");
  std::printf("[ reach ] default example: reach %.4g m from the target centre, box %.4g m\n",
              from_centre, box);

  // Issue 50 (1): every hazardous voxel of the box lies within the reach in its direction
  // (before, 614 of the 9 033 outside the lit ball lay beyond it: the lattice began on a cube
  // about the lit centre and left out 0.5 m about the target).
  const ReachRays rays(r.out / "reach.vtp", reach);
  ASSERT_TRUE(rays.complete());
  openvdb::initialize();
  openvdb::io::File file((r.out / "irradiance.vdb").string());
  file.open();
  const auto grid = openvdb::gridPtrCast<openvdb::FloatGrid>(file.readGrid("irradiance_w_m2"));
  file.close();
  ASSERT_NE(grid, nullptr);
  grid->tree().voxelizeActiveTiles();  // a tile stands for many voxels: each read alone
  const double mpe = r.summary.at("hazard").at("mpe_w_m2").get<double>();
  std::int64_t hazardous = 0, beyond = 0;
  for (auto v = grid->cbeginValueOn(); v; ++v) {
    if (!(static_cast<double>(*v) >= mpe)) continue;
    const openvdb::Vec3d w = grid->indexToWorld(v.getCoord());
    const Vec3 x(w.x(), w.y(), w.z());
    if (rays.unclassified(x)) continue;
    ++hazardous;
    const Vec3 d = x - rays.centre();
    const double reach_m = rays.toward(glm::normalize(d));
    if (!(glm::length(d) <= reach_m * (1.0 + 1e-6))) {
      if (++beyond <= 5) {
        ADD_FAILURE() << "(" << x.x << ", " << x.y << ", " << x.z << "), hazard ratio "
                      << static_cast<double>(*v) / mpe << ", " << glm::length(d)
                      << " m from the lit centre, beyond the reach of " << reach_m << " m";
      }
    }
  }
  EXPECT_EQ(beyond, 0) << "of " << hazardous << " hazardous voxels";
  EXPECT_GT(hazardous, 5000) << "premise: the box's zone is 13.8 m³ of 1e-3 m³ voxels";
  std::printf("[ reach ] default example: %lld hazardous voxels, %lld beyond the reach\n",
              static_cast<long long>(hazardous), static_cast<long long>(beyond));
  fs::remove_all(r.out);
}

// ABg and a measured table through glint points, glint run (far field and reach) and glint
// batch. The disk of reach_pencil.json, 0.1 m across under 7.96e5 W/m², cos θi =
// 1/|(−1, 0.6, 0.4)| = 0.811: its intensity is I = E A cos θi cos θr f, f = A/B = 20 /sr along
// the mirror direction for ABg (8.22e4 W/sr, 40.56 m to the MPE of 50 W/m²) and 0.05 /sr
// everywhere for the table (253 W/sr along the normal, 2.25 m).
TEST(ReachRun, AbgAndATableGiveTheirClosedFormsThroughPointsRunAndBatch) {
  const fs::path data(GLINT_TEST_DATA_DIR);
  const double e_beam = 1e5 / (kPi * 0.04), area = kPi * 0.05 * 0.05;
  const Vec3 n = glm::normalize(Vec3(-1, 0.6, 0.4)), wi(-1, 0, 0);
  const double cos_i = glm::dot(n, wi);
  const Vec3 mirror = 2.0 * cos_i * n - wi;
  const double peak_w_sr = e_beam * area * cos_i * cos_i * 0.02 / 1e-3;
  const double table_peak_w_sr = e_beam * area * cos_i * 0.05;
  const double mpe = 50.0;
  // glint points: E r² along the mirror direction for ABg, and in three directions for the table.
  const fs::path dir = test::freshTestFolder("glint_abg_table");
  // The table's at 20 m, where its light (0.5 W/m²) is far above the scene's floor (8e-4 W/m²,
  // 1e-9 of the beam), which bounds each observer's absolute error; 1/d² varies by 1e-5 over
  // the disk there.
  std::vector<Vec3> observers{200.0 * mirror};
  for (const Vec3& d :
       {mirror, glm::normalize(Vec3(-1, 0.2, 0.1)), glm::normalize(Vec3(-0.3, 1.0, 0.0))})
    observers.push_back(20.0 * d);
  // And 10 m away in the disk's own plane, where both terms vanish. Every piece of the disk
  // straddles the horizon there: before the bounds took cos θr into account, glint points
  // split such pieces on their bounds alone for minutes at this observer, and a run's far field
  // at one like it until memory ran out.
  observers.push_back(Vec3(1, 1, 1) * (10.0 / std::sqrt(3.0)));
  {
    std::ofstream csv(dir / "points.csv");
    csv << "x,y,z\n";
    for (const Vec3& o : observers) csv << o.x << "," << o.y << "," << o.z << "\n";
  }
  struct Point {
    double irradiance_w_m2, evaluations;
    bool converged;
  };
  const auto points = [&](const char* scene) {
    const fs::path out = dir / (std::string(scene) + ".csv");
    const test::Outcome o = test::glint({"points", (data / scene).string(), "--points",
                                         (dir / "points.csv").string(), "--out", out.string()});
    EXPECT_EQ(o.status, 0) << o.err;
    std::vector<Point> e;
    std::ifstream in(out);
    std::string line;
    std::getline(in, line);
    EXPECT_EQ(line.rfind("x,y,z,irradiance_w_m2,error_estimate_w_m2,evaluations,converged", 0), 0u)
        << line;
    while (std::getline(in, line)) {
      std::stringstream row(line);
      std::vector<std::string> cells;
      for (std::string cell; std::getline(row, cell, ',');) cells.push_back(cell);
      e.push_back({std::stod(cells.at(3)), std::stod(cells.at(5)), cells.at(6) == "1"});
    }
    return e;
  };
  const std::vector<Point> abg = points("abg_disk.json");
  ASSERT_EQ(abg.size(), observers.size());
  // At 200 m the disk subtends 2.5e-4 rad: ABg's peak (√B / 2 ≈ 0.016 rad wide) is flat across
  // it to 1e-4, and 1/d² to 5e-4.
  const double r2 = glm::dot(observers[0], observers[0]);
  EXPECT_NEAR(abg[0].irradiance_w_m2 * r2 / peak_w_sr, 1.0, 2e-3)
      << abg[0].irradiance_w_m2 * r2 << " W/sr";
  const std::vector<Point> table = points("table_disk.json");
  ASSERT_EQ(table.size(), observers.size());
  for (std::size_t k = 1; k < 4; ++k) {
    const Vec3 wo = glm::normalize(observers[k]);
    const double expected = e_beam * area * cos_i * glm::dot(n, wo) * 0.05;
    // The table's cubic on cos θi cos θo between nodes 5° apart: ~1e-4.
    EXPECT_NEAR(table[k].irradiance_w_m2 * glm::dot(observers[k], observers[k]) / expected, 1.0,
                2e-3)
        << "direction " << k;
  }
  for (const auto& [name, edge_on] : {std::pair{"ABg", abg.back()}, {"table", table.back()}}) {
    EXPECT_TRUE(edge_on.converged) << name;
    // The scene's floor (1e-9 of the beam's 7.96e5 W/m²) is all it may hold.
    EXPECT_LE(edge_on.irradiance_w_m2, 1e-3) << name;
    // One rule and its check per coarse facet, 8 × 25, or little more.
    EXPECT_LE(edge_on.evaluations, 2000.0) << name;
  }
  fs::remove_all(dir);

  // glint run: the far field's peak and the reach. The reach's lattice is coarse (16 cells per
  // face edge, the far field's 64) to keep the test short: it decides only within the far
  // radius (9.4 m), and the far field beyond, where E = I / r².
  nlohmann::json scene = nlohmann::json::parse(std::ifstream(data / "abg_disk.json"));
  scene["far_field"] = {{"face_pixels", 64}};
  scene["reach"] = {{"face_cells", 16}};
  const RunResult r = runEdited(scene, "glint_abg_disk_run");
  ASSERT_EQ(r.outcome.status, 0) << r.outcome.err;
  const double peak = r.summary.at("far_field").at("peak_intensity_w_sr").get<double>();
  // The far field's tolerance (0.01) bounds the peak's error.
  EXPECT_NEAR(peak / peak_w_sr, 1.0, 0.01) << peak;
  const nlohmann::json& reach = r.summary.at("hazard_reach");
  const double abg_reach = reach.at("distance_m").get<double>();
  const double abg_truth = std::sqrt(peak_w_sr / mpe);
  // Never short of the truth; beyond it by at most the far field's allowance (1.1 × its
  // tolerance of I, as for the pencil).
  EXPECT_GE(abg_reach, abg_truth) << reach.dump();
  EXPECT_LE(abg_reach, abg_truth * std::sqrt(1.01 * 1.011)) << reach.dump();
  EXPECT_TRUE(reach.at("closed").get<bool>()) << reach.dump();
  EXPECT_EQ(reach.at("from"), "far field");
  EXPECT_EQ(r.summary.at("materials").at("painted").at("model"), "ABg");
  fs::remove_all(r.out);

  // glint batch: the same disk in two surface states, ABg and the table.
  const fs::path study_dir = test::freshTestFolder("glint_abg_table_study");
  scene["materials"]["measured"] = {{"table", (data / "abg_disk_table.csv").string()}};
  // A study needs a box or a plane: a coarse plane beside the disk, as in reach_study.json.
  scene["planes"] = nlohmann::json::array({{{"name", "beside"},
                                            {"origin", {-2, -2, -1}},
                                            {"u_axis", {1, 0, 0}},
                                            {"v_axis", {0, 1, 0}},
                                            {"size_m", {4, 4}},
                                            {"pixel_m", 0.5}}});
  std::ofstream(study_dir / "scene.json") << scene.dump();
  std::ofstream(study_dir / "study.json")
      << R"({"scene": "scene.json", "sweep": {"surface_state": ["painted", "measured"], "material": "painted"}})";
  const fs::path out = study_dir / "out";
  const test::Outcome batch =
      test::glint({"batch", (study_dir / "study.json").string(), "-o", out.string()});
  ASSERT_EQ(batch.status, 0) << batch.err;
  std::vector<double> reaches;
  for (const char* scenario : {"s000000", "s000001"}) {
    const nlohmann::json result =
        nlohmann::json::parse(std::ifstream(out / "scenarios" / scenario / "result.json"));
    EXPECT_TRUE(result.at("hazard_reach").at("closed").get<bool>()) << scenario;
    reaches.push_back(result.at("hazard_reach").at("distance_m").get<double>());
  }
  EXPECT_NEAR(reaches[0], abg_reach, 1e-6 * abg_reach) << "the ABg state, as glint run gave it";
  // The table's hazard (2.25 m along the normal) lies within the far radius, so the reach's
  // coarse lattice decides it: never short of the truth, and over it by at most what a lattice
  // 5.6° between rays leaves unresolved against the table's 5° steps (measured: 2.488 m).
  const double table_truth = std::sqrt(table_peak_w_sr / mpe);
  EXPECT_GE(reaches[1], table_truth);
  EXPECT_LE(reaches[1], table_truth * 1.15);
  std::printf(
      "[ abg ] disk: I %.4g W/sr (closed form %.4g); reach %.4g m (%.4g m); table reach "
      "%.4g m (%.4g m)\n",
      abg[0].irradiance_w_m2 * r2, peak_w_sr, abg_reach, abg_truth, reaches[1], table_truth);
  fs::remove_all(study_dir);
}

// Without a box or plane the reach is all a run computes: refusing it, or the far field it
// ends in, leaves nothing to do, and the run says so before it starts.
TEST(ReachRun, WithoutBoxOrPlaneTheReachAndItsFarFieldCannotBeTurnedOff) {
  nlohmann::json scene =
      nlohmann::json::parse(std::ifstream(fs::path(GLINT_TEST_DATA_DIR) / "reach_pencil.json"));
  const fs::path dir = fs::temp_directory_path() / "glint_reach_refused";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const auto refusal = [&](const nlohmann::json& edited) {
    std::ofstream(dir / "scene.json") << edited.dump();
    return test::glint({"run", (dir / "scene.json").string(), "-o", (dir / "out").string()});
  };
  nlohmann::json no_reach = scene;
  no_reach["reach"] = {{"enabled", false}};
  const test::Outcome a = refusal(no_reach);
  EXPECT_EQ(a.status, 2);
  EXPECT_NE(a.err.find("/reach/enabled: false, and there is neither"), std::string::npos) << a.err;
  nlohmann::json no_far = scene;
  no_far["far_field"] = {{"enabled", false}};
  const test::Outcome b = refusal(no_far);
  EXPECT_EQ(b.status, 2);
  EXPECT_NE(b.err.find("the hazard reach needs the far field"), std::string::npos) << b.err;
  EXPECT_FALSE(fs::exists(dir / "out" / "summary.json")) << "nothing written";
  fs::remove_all(dir);
}

// A study whose scene asks for the reach: each scenario's result.json and row of scenarios.csv
// carry its reach, and the study's summary their quantiles and the farthest scenario.
TEST(ReachRun, AStudyGivesEachScenariosReachAndTheirQuantiles) {
  const fs::path out = fs::temp_directory_path() / "glint_reach_study";
  fs::remove_all(out);
  const test::Outcome run = test::glint(
      {"batch", (fs::path(GLINT_TEST_DATA_DIR) / "reach_study.json").string(), "-o", out.string()});
  ASSERT_EQ(run.status, 0) << run.err;
  std::vector<double> reaches;
  for (const char* scenario : {"s000000", "s000001"}) {
    const nlohmann::json result =
        nlohmann::json::parse(std::ifstream(out / "scenarios" / scenario / "result.json"));
    const nlohmann::json& reach = result.at("hazard_reach");
    EXPECT_TRUE(reach.at("closed").get<bool>()) << scenario << ": " << reach.dump();
    reaches.push_back(reach.at("distance_m").get<double>());
    // The tilts turn the pencil, not its length: each about 423 m.
    EXPECT_NEAR(reaches.back(), 423.1, 0.01 * 423.1) << scenario;
  }
  const nlohmann::json summary = nlohmann::json::parse(std::ifstream(out / "summary.json"));
  const nlohmann::json& study = summary.at("hazard_reach");
  EXPECT_EQ(study.at("scenarios_closed").get<int>(), 2) << study.dump();
  EXPECT_DOUBLE_EQ(study.at("distance_m").at("max").get<double>(),
                   std::max(reaches[0], reaches[1]));
  EXPECT_DOUBLE_EQ(study.at("distance_m").at("min").get<double>(),
                   std::min(reaches[0], reaches[1]));
  const std::string csv = test::readFile(out / "scenarios.csv");
  EXPECT_NE(csv.find(",reach_m,reach_closed,"), std::string::npos) << csv;
  EXPECT_NE(run.err.find("hazard reach: median"), std::string::npos) << run.err;
  fs::remove_all(out);
}

// The reach's lattices are refused before they are allocated when, beside the far field, they
// would pass the memory budget: one clear message that says what to lower. (Under glint run the
// resident memory of the program itself is over such a budget before the far field; the field
// builders' watch stops a lattice whose grids outgrow a larger one.)
TEST(ReachRun, ALatticeBeyondTheMemoryBudgetIsRefusedBeforeItIsAllocated) {
  Scene scene = loadScene(fs::path(GLINT_TEST_DATA_DIR) / "reach_pencil.json");
  scene.reach.face_cells = 512;  // 6 × 513² rays × 353 layers
  const SceneTarget target = sceneTarget(scene, reachAccuracy(scene));
  const FarField far =
      computeFarField(target.integrator, checkedFarFieldSpec(scene, target.integrator));
  const std::uint64_t far_bytes = farFieldMemoryFloorBytes(far.spec());
  const MemoryWatch watch(far_bytes + 1024);  // the far field fits, the lattice does not
  try {
    (void)sceneReach(target, scene, far, farHazard(far, scene.hazard), {watch, "the hazard reach"});
    ADD_FAILURE() << "a lattice beyond the budget was computed";
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("the hazard reach (6 × 513² rays × 353 layers"), std::string::npos) << m;
    EXPECT_NE(m.find("beside the far field"), std::string::npos) << m;
    EXPECT_NE(m.find("reach.face_cells"), std::string::npos) << "it says what to lower: " << m;
  }
}

// With an optical aid the reach is given for the aided eye beside the naked one: the pencil's
// far-field reach grows as the square root of the aid's gain.
TEST(ReachRun, AnOpticalAidsReachIsGivenBesideTheNakedEyes) {
  nlohmann::json scene =
      nlohmann::json::parse(std::ifstream(fs::path(GLINT_TEST_DATA_DIR) / "reach_pencil.json"));
  scene["optical_aid"] = {{"gain", 4.0}};
  const RunResult r = runEdited(scene, "glint_reach_aided_out");
  ASSERT_EQ(r.outcome.status, 0) << r.outcome.err;
  const nlohmann::json& reach = r.summary.at("hazard_reach");
  const double naked = reach.at("distance_m").get<double>();
  const double aided = reach.at("aided").at("distance_m").get<double>();
  EXPECT_NEAR(aided / naked, 2.0, 1e-3) << reach.dump();  // √4, both from the far field
  EXPECT_TRUE(reach.at("aided").at("closed").get<bool>());
  EXPECT_NE(r.outcome.err.find("through the optical aid: "), std::string::npos) << r.outcome.err;
  int w = 0, h = 0;
  const std::vector<float> map =
      readExrChannel((r.out / "reach.exr").string(), "aided_reach_m", w, h);
  EXPECT_NEAR(*std::max_element(map.begin(), map.end()), aided, 1e-3 * aided);
  fs::remove_all(r.out);
}

TEST(ReachRun, APlaneMayNotTakeTheReachsOrTheFarFieldsMapName) {
  for (const char* name : {"reach", "far_field"}) {
    const std::string scene =
        R"({"laser": {"position": [-100, 0, 0], "direction": [1, 0, 0], "power_w": 1.0,
             "wavelength_nm": 532, "beam": {"profile": "flat_top", "radius_m": 1}},
            "materials": {"m": {"specular_reflectance": 0.9, "sigma": 0.01}},
            "objects": [{"shape": "sphere", "center": [0, 0, 0], "radius": 0.5, "material": "m"}],
            "planes": [{"name": ")" +
        std::string(name) + R"(", "origin": [-2, -1, 0], "u_axis": [0, 1, 0],
             "v_axis": [0, 0, 1], "size_m": [2, 2], "pixel_m": 0.5}]})";
    try {
      parseScene(scene, "scene.json");
      ADD_FAILURE() << name << " was accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("is taken: glint run writes"), std::string::npos)
          << e.what();
    }
  }
}

}  // namespace
}  // namespace glint
