// The shipped examples run, converge, and hold the accuracy the README and docs/ promise.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "observers/point_set.h"
#include "pipeline/input/points_file.h"
#include "pipeline/input/scene.h"
#include "pipeline/setup/target_builder.h"
#include "support/cli.h"

namespace glint {
namespace {

std::string example(const std::string& name) {
  return std::string(GLINT_EXAMPLES_DIR) + "/" + name;
}

std::vector<ObserverResult> run(const std::string& scene_file, const std::string& points_file,
                                double tolerance_factor = 1.0) {
  const Scene scene = loadScene(example(scene_file));
  IntegratorOptions o = scene.accuracy;
  o.tolerance *= tolerance_factor;
  const FacetIntegrator fi(buildTarget(scene), scene.laser, o);
  return evaluatePoints(fi, loadPoints(example(points_file)), PointScheme{});
}

TEST(Examples, EveryExampleRunsAndConverges) {
  const std::vector<std::pair<std::string, std::string>> examples = {
      {"cylinder.json", "cylinder_186.csv"},
      {"cylinder_broad.json", "cylinder_186.csv"},
      {"sphere.json", "sphere_points.csv"},
      {"disk.json", "disk_points.csv"}};
  for (const auto& [scene, points] : examples) {
    const auto results = run(scene, points);
    std::size_t lit = 0;
    for (std::size_t i = 0; i < results.size(); ++i) {
      EXPECT_TRUE(results[i].converged) << scene << " observer " << i;
      EXPECT_TRUE(std::isfinite(results[i].irradiance_w_m2)) << scene << " observer " << i;
      lit += results[i].irradiance_w_m2 > 0.0 ? 1 : 0;
    }
    EXPECT_GT(lit, results.size() / 2) << scene << ": most observers see the glint";
  }
}

TEST(Examples, RangeSceneIsAKilometreBoxWhoseSheetIsHazardousToAbout490Metres) {
  // examples/range_2km.json as its description says: at least 1e9 lattice points at 0.25 m or
  // finer, and, back along the beam, the sheet above the MPE at 470 m and below it at 505 m
  // (its radiant intensity, 1.19e7 W/sr, over the 50 W/m² MPE: sqrt(I / MPE) = 488 m).
  const Scene scene = loadScene(example("range_2km.json"));
  const FieldSpec spec = fieldSpec(scene);
  const auto n = spec.nodes();
  EXPECT_LE(spec.voxel_m, 0.25);
  EXPECT_GE(static_cast<double>(n[0]) * n[1] * n[2], 1e9) << n[0] << "×" << n[1] << "×" << n[2];
  const FacetIntegrator fi(buildTarget(scene), scene.laser, scene.accuracy);
  IntegratorWorkspace ws;
  const double mpe = scene.hazard.mpe_w_m2;
  ASSERT_NEAR(mpe, 50.0, 0.5) << "1064 nm, 10 s";
  const ObserverResult inside = fi.adaptive(Vec3(-470.0, 0.0, 0.0), ws);
  const ObserverResult outside = fi.adaptive(Vec3(-505.0, 0.0, 0.0), ws);
  EXPECT_GT(inside.irradiance_w_m2, mpe) << "470 m back along the beam";
  EXPECT_LT(outside.irradiance_w_m2, mpe) << "505 m back along the beam";
  EXPECT_TRUE(inside.converged && outside.converged);
}

TEST(Examples, CylinderChangesLessThanATenthOfAPercentWhenTheToleranceIsHalved) {
  for (const char* scene : {"cylinder.json", "cylinder_broad.json"}) {
    const auto a = run(scene, "cylinder_186.csv");
    const auto b = run(scene, "cylinder_186.csv", 0.5);
    double worst = 0.0;
    for (std::size_t i = 0; i < a.size(); ++i) {
      const double scale = std::max(std::abs(b[i].irradiance_w_m2), 1e-9);
      worst = std::max(worst, std::abs(a[i].irradiance_w_m2 - b[i].irradiance_w_m2) / scale);
    }
    EXPECT_LT(worst, 1e-3) << scene;
  }
}

TEST(Examples, FinnedMissileOcclusionOnlyEverRemovesLight) {
  // The finned missile with and without occlusion rays, over the eye-level plane: the rays can
  // only take light away (within the integration tolerance), and here they do take some.
  const Scene scene = loadScene(example("finned_missile.json"));
  IntegratorOptions with = scene.accuracy;
  IntegratorOptions without = with;
  without.occlusion = false;
  const FacetIntegrator occluded(buildTarget(scene), scene.laser, with);
  const FacetIntegrator open(buildTarget(scene), scene.laser, without);
  EXPECT_TRUE(occluded.cullStats().occlusion);
  EXPECT_GT(occluded.cullStats().shadowed, 0u) << "the fins shadow the body";
  EXPECT_EQ(occluded.cullStats().lit + occluded.cullStats().shadowed, open.cullStats().lit);
  std::vector<Vec3> points;
  for (int i = 0; i < 16; ++i)
    for (int j = 0; j < 16; ++j) points.push_back({-15.0 + 2.0 * i, -15.0 + 2.0 * j, 1.7});
  const auto a = evaluatePoints(occluded, points, PointScheme{});
  const auto b = evaluatePoints(open, points, PointScheme{});
  std::size_t dimmed = 0;
  for (std::size_t k = 0; k < points.size(); ++k) {
    const double slack = 2.0 * with.tolerance * b[k].irradiance_w_m2 + 2.0 * with.floor_w_m2;
    EXPECT_LE(a[k].irradiance_w_m2, b[k].irradiance_w_m2 + slack)
        << "observer (" << points[k].x << ", " << points[k].y << ")";
    dimmed += a[k].irradiance_w_m2 < 0.99 * b[k].irradiance_w_m2 ? 1 : 0;
  }
  EXPECT_GT(dimmed, 0u) << "somewhere on the plane the fins must hide part of the body";
}

// The README's first command runs examples/cylinder.json at 0.1 m (minutes); the same scene
// (or another example's, @p scene_file) at 0.5 m voxels shows the same things in seconds. `edit`
// changes the scene before the run.
struct CoarseRun {
  test::Outcome run;
  nlohmann::json summary;
  std::set<std::string> files;  ///< the output folder's entries
};
CoarseRun runCoarseExample(const std::string& name,
                           const std::function<void(nlohmann::json&)>& edit = {},
                           const std::string& scene_file = "cylinder.json") {
  auto scene = nlohmann::json::parse(std::ifstream(example(scene_file)));
  scene["observers"]["voxel_m"] = 0.5;
  scene["observers"]["block_m"] = 2.0;
  scene.erase("reach");  // the box is what these runs show (ReachRun runs the example whole)
  if (edit) edit(scene);
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "cylinder.json") << scene.dump();
  CoarseRun r;
  r.run = test::glint({"run", (dir / "cylinder.json").string(), "-o", (dir / "out").string()});
  if (r.run.status == 0) {
    r.summary = nlohmann::json::parse(std::ifstream(dir / "out" / "summary.json"));
    for (const auto& entry : std::filesystem::directory_iterator(dir / "out"))
      r.files.insert(entry.path().filename().string());
  }
  std::filesystem::remove_all(dir);
  return r;
}

TEST(Examples, DefaultExampleShowsAHazardZoneInsideItsBoxWithoutWarning) {
  // A hazard zone that ends inside the box, and every point converged: those on the shadow's
  // edge lines (y = ±0.5 m, where the lit and the visible side meet in a line) too, since no
  // piece that cannot both see the laser and be seen is kept there. At 0.5 m the lattice is
  // coarser than the cylinder's facets, whose light may then pass between its points next to
  // the surface: the run says so (status 6), and that a lattice no finer than the example's
  // own 0.1 m resolves it; nothing else is warned of.
  const CoarseRun r = runCoarseExample("glint_default_example");
  ASSERT_EQ(r.run.status, 0) << r.run.err;
  const auto& hazard = r.summary["hazard"];
  const auto& zone = hazard["nominal_hazard_zone"];
  EXPECT_GT(hazard["peak_hazard_ratio"].get<double>(), 2.0) << hazard.dump();
  EXPECT_GT(zone["points"].get<int>(), 20) << zone.dump();
  EXPECT_FALSE(zone["reaches_box_edge"].get<bool>()) << zone.dump();
  const double reach = zone["farthest_from_target_m"].get<double>();
  EXPECT_GT(reach, 1.5) << "the backscattered fan reaches about 2.5 m";
  EXPECT_LT(reach, 3.0) << "and ends a metre inside the box's 4 m";
  EXPECT_FALSE(r.summary.contains("unconverged")) << r.summary["unconverged"];
  EXPECT_FALSE(hazard["unconverged_may_be_hazardous"].get<bool>());
  ASSERT_TRUE(r.summary.contains("narrow_glints")) << r.run.err;
  EXPECT_GE(r.summary["narrow_glints"]["resolving_voxel_m"].get<double>(), 0.1)
      << r.summary["narrow_glints"].dump();
  const std::string::size_type narrow = r.run.err.find("warning: a glint narrower than");
  EXPECT_NE(narrow, std::string::npos) << r.run.err;
  EXPECT_EQ(r.run.err.find("warning"), narrow) << r.run.err;
  EXPECT_EQ(r.run.err.find("warning", narrow + 1), std::string::npos) << r.run.err;
  EXPECT_EQ(r.run.err.find("note:"), std::string::npos) << r.run.err;
}

TEST(Examples, UnconvergedPointsWarnOnlyWhereTheirBoundReachesTheMpe) {
  // 100 evaluations per observer leave many points short of their tolerance. Each is judged
  // by its irradiance plus its error estimate: at the example's 6 kW the bound passes the MPE
  // (a warning: they may be hazardous); at 60 mW, 1e-5 of it, the same bounds are 1e-5 as
  // large and the run can say that none of them is hazardous (a note).
  for (const double power_w : {6000.0, 0.06}) {
    const CoarseRun r = runCoarseExample("glint_unconverged_example", [&](nlohmann::json& scene) {
      scene["laser"]["power_w"] = power_w;
      scene["accuracy"]["max_evaluations"] = 100;
    });
    ASSERT_EQ(r.run.status, 0) << r.run.err;
    ASSERT_TRUE(r.summary.contains("unconverged")) << "the premise, at " << power_w << " W";
    const bool may = power_w > 1.0;
    const double upper = r.summary["unconverged"]["max_hazard_ratio_plus_error"].get<double>();
    EXPECT_EQ(r.summary["unconverged"]["may_be_hazardous"].get<bool>(), may) << upper;
    EXPECT_EQ(r.summary["hazard"]["unconverged_may_be_hazardous"].get<bool>(), may);
    EXPECT_EQ(upper >= 1.0, may) << power_w << " W";
    const std::string::size_type line = r.run.err.find("points did not reach the integration");
    ASSERT_NE(line, std::string::npos) << r.run.err;
    const std::string::size_type start = r.run.err.rfind('\n', line) + 1;
    EXPECT_EQ(r.run.err.compare(start, 11, "  warning: ") == 0, may) << r.run.err;
    EXPECT_EQ(r.run.err.find("so none of them can be hazardous") != std::string::npos, !may)
        << r.run.err;
  }
}

TEST(Examples, TheCarBodyWithoutNormalsGlintsOnEverySurface) {
  // examples/targets/car_body.glb has no normals: they come from its faces, smooth within the
  // 30° crease angle and split across its sharper edges. PN triangles, the quadric fit and flat
  // facets must give each observer a finite, converged irradiance, and the curved two must
  // agree on the brightest observer to within what the mesh's coarseness allows (its 1 458
  // triangles: the surface check says 0.4 %; 25 % leaves room for the glint's curvature, which
  // computed normals fix only to first order). The quadric fit used to refine every observer
  // to the depth limit and report 0 here (fits whose gradient may vanish within the facet: now
  // refused, QuadricFitStatus::Unbounded). Nagata patches still bulge on this body
  // (docs/meshes.md), so they are not asked to.
  const nlohmann::json scene = {
      {"laser",
       {{"position", {-40, -30, 8}},
        {"direction", {40, 30, -7}},
        {"power_w", 2000.0},
        {"wavelength_nm", 1064},
        {"beam", {{"profile", "gaussian"}, {"w_m", 2.0}}}}},
      {"materials",
       {{"paint", {{"specular_reflectance", 0.5}, {"sigma", 0.05}, {"diffuse_reflectance", 0.1}}}}},
      {"objects", {{{"shape", "mesh"}, {"file", "targets/car_body.glb"}, {"material", "paint"}}}}};
  std::vector<Vec3> observers;
  for (int i = 0; i < 12; ++i) {
    const double a = -2.6 + 0.1 * i;  // a fan of directions back toward the laser's side
    observers.push_back(Vec3(20.0 * std::cos(a), 20.0 * std::sin(a), 1.0 + 0.5 * i));
  }
  std::vector<double> brightest;
  std::size_t peak = 0;
  for (const char* surface : {"pn", "quadric_fit", "flat"}) {
    nlohmann::json s = scene;
    s["objects"][0]["surface"] = surface;
    const Scene parsed = parseScene(s.dump(), "car.json", GLINT_EXAMPLES_DIR);
    ASSERT_GT(parsed.objects[0].mesh()->normals_computed, 0u) << "the file gives no normals";
    const FacetIntegrator fi(buildTarget(parsed), parsed.laser, parsed.accuracy);
    const auto results = evaluatePoints(fi, observers, PointScheme{});
    double lit = 0.0;
    for (std::size_t k = 0; k < results.size(); ++k) {
      EXPECT_TRUE(std::isfinite(results[k].irradiance_w_m2)) << surface << " observer " << k;
      EXPECT_TRUE(results[k].converged) << surface << " observer " << k;
      if (std::string(surface) == "pn" &&
          results[k].irradiance_w_m2 > results[peak].irradiance_w_m2)
        peak = k;
      lit += results[k].irradiance_w_m2;
    }
    EXPECT_GT(lit, 0.0) << surface << ": the car's flank faces the observers";
    brightest.push_back(results[peak].irradiance_w_m2);
  }
  EXPECT_NEAR(brightest[1] / brightest[0], 1.0, 0.25) << "quadric_fit against pn";
}

TEST(Examples, FinnedMissileRunsThroughGlintRun) {
  const std::filesystem::path out =
      std::filesystem::temp_directory_path() / "glint_finned_missile_run";
  std::filesystem::remove_all(out);
  const auto r =
      test::glint({"run", std::string(GLINT_TEST_DATA_DIR) + "/finned_missile_coarse.json", "-o",
                   out.string(), "--quiet"});
  ASSERT_EQ(r.status, 0) << r.err;
  const auto summary = nlohmann::json::parse(std::ifstream(out / "summary.json"));
  EXPECT_TRUE(summary["target"]["occlusion_rays"].get<bool>());
  EXPECT_GT(summary["target"]["shadowed"].get<int>(), 0);
  const auto& mesh = summary["meshes"][0];
  EXPECT_EQ(mesh["triangles"].get<int>(), 2064) << mesh.dump();
  EXPECT_EQ(mesh["open_edges"].get<int>(), 0) << "the body and each fin are closed";
  EXPECT_GT(mesh["crease_edges"].get<int>(), 0) << "the tail disc, the nose joint and the fins";
  EXPECT_GT(summary["planes"][0]["peak_hazard_ratio"].get<double>(), 1.0);
  EXPECT_TRUE(std::filesystem::exists(out / "eye_level.exr"));
  // The mesh's surface checked at the plane's brightest point: the same integration as the
  // plane's there, and the other surfaces a little off (the mesh has 2 064 triangles).
  const auto& check = summary["surface_check"];
  EXPECT_EQ(check["compared"], "pn against quadric_fit, nagata") << check.dump();
  ASSERT_EQ(check["probes"].size(), 1u) << check.dump();
  const auto& probe = check["probes"][0];
  EXPECT_EQ(probe["where"], "plane eye_level's peak");
  // The same point at the same accuracy, though not the same candidates: the plane's block
  // dropped some facets' light (at most its allowance) and its refinement may settle a far
  // facet's diffuse light from the facet's moments where the probe's splits it, each within
  // its error. Both are within the tolerance (1e-3) of the truth; they agree to 8e-6.
  EXPECT_NEAR(probe["irradiance_w_m2"].get<double>() /
                  summary["planes"][0]["peak_irradiance_w_m2"].get<double>(),
              1.0, 1e-4)
      << "the probe is the plane's peak, integrated at the plane's accuracy";
  // The body is a cylinder with its exporter's normals, where every surface converges at second
  // order: they agree on the plane's peak to 2e-5 (a quadric fit that bulged on its long facets
  // once made it 3.8 %: now refused, QuadricFitStatus::Unbounded).
  EXPECT_FALSE(probe["alternative"].is_null()) << "an other surface converged there";
  const double change = check["max_relative_change"].get<double>();
  EXPECT_GE(change, 0.0);
  EXPECT_LT(change, 1e-3) << check.dump();
  std::filesystem::remove_all(out);
}

}  // namespace
}  // namespace glint

namespace glint {
namespace {

// Runs `glint <command> <example> args...` with the example's scene edited by @p edit, in a
// fresh folder; returns the outcome and the folder (removed by the caller).
struct EditedRun {
  test::Outcome outcome;
  std::filesystem::path dir;
};
EditedRun runEdited(const std::string& name, const std::string& scene_file,
                    const std::function<void(nlohmann::json&)>& edit,
                    const std::vector<std::string>& command) {
  auto scene = nlohmann::json::parse(std::ifstream(example(scene_file)));
  if (edit) edit(scene);
  EditedRun r;
  r.dir = std::filesystem::temp_directory_path() / name;
  std::filesystem::remove_all(r.dir);
  std::filesystem::create_directories(r.dir);
  std::ofstream(r.dir / "scene.json") << scene.dump();
  std::vector<std::string> args = {command.front(), (r.dir / "scene.json").string()};
  args.insert(args.end(), command.begin() + 1, command.end());
  r.outcome = test::glint(args);
  return r;
}

// `glint points` on an example scene (edited by @p edit), the observers of @p points_file; its
// table in <temp>/<name>.csv.
struct PointsRun {
  EditedRun run;
  std::filesystem::path csv;
};
PointsRun runExamplePoints(const std::string& name, const std::string& scene_file,
                           const std::string& points_file,
                           const std::function<void(nlohmann::json&)>& edit = {}) {
  PointsRun r;
  r.csv = std::filesystem::temp_directory_path() / (name + ".csv");
  r.run = runEdited(name, scene_file, edit,
                    {"points", "--points", points_file, "--out", r.csv.string(), "-q"});
  return r;
}

std::vector<std::vector<double>> readCsvNumbers(const std::filesystem::path& path,
                                                std::string& header) {
  std::ifstream in(path);
  std::getline(in, header);
  std::vector<std::vector<double>> rows;
  for (std::string line; std::getline(in, line);) {
    std::vector<double> row;
    std::stringstream cells(line);
    for (std::string c; std::getline(cells, c, ',');) row.push_back(std::stod(c));
    rows.push_back(row);
  }
  return rows;
}

// examples/mirror_fog.json: fog of 500 m visibility (Kim: μ = 3.912 / 500 m, grey) on the laser's
// 100.3 m to the mirror and on each observer's r back: E falls by exp(−μ (100.3 m + r)) from the
// same scene in vacuum, to within the mirror's ±5 cm of path (μ × 0.1 m = 8e-4) and the two
// integrations' tolerance (1e-3 each).
TEST(Examples, FogAttenuatesTheMirrorsGlintOnBothLegsByBeerLambert) {
  const std::string points = example("mirror_fog_points.csv");
  const PointsRun fog = runExamplePoints("glint_fog", "mirror_fog.json", points);
  ASSERT_EQ(fog.run.outcome.status, 0) << fog.run.outcome.err;
  const PointsRun vacuum = runExamplePoints("glint_vacuum", "mirror_fog.json", points,
                                            [](nlohmann::json& j) { j.erase("atmosphere"); });
  ASSERT_EQ(vacuum.run.outcome.status, 0) << vacuum.run.outcome.err;
  std::string header;
  const auto f = readCsvNumbers(fog.csv, header);
  const auto v = readCsvNumbers(vacuum.csv, header);
  const double mu = 3.912 / 500.0;
  ASSERT_EQ(f.size(), 5u);
  for (std::size_t i = 0; i < f.size(); ++i) {
    const double r = f[i][1];  // from the mirror's centre (0.3, 0, 0.3) along +y
    const double expected = std::exp(-mu * (100.3 + r));
    EXPECT_NEAR(f[i][3] / v[i][3], expected, 3e-3 * expected) << "observer at y = " << f[i][1];
  }
  EXPECT_GT(f[2][7], 1.0) << "hazardous at 60 m in fog";
  EXPECT_LT(f[3][7], 1.0) << "not at 100 m in fog";
  EXPECT_GT(v[3][7], 1.0) << "hazardous at 100 m in vacuum";
  for (const auto& p : {fog.run.dir, vacuum.run.dir}) std::filesystem::remove_all(p);
}

// examples/pulsed_nd_yag.json: 0.6 J, 10 ns at 10 Hz for 10 s, the MPE set by rule 3 (2.0e-2
// J/m² × 100^-0.25 a pulse); `glint points` gives each observer's radiant exposure per pulse,
// E / 10 Hz, and its ratio E / (MPE per pulse × 10 Hz).
TEST(Examples, PulsedNdYagIsJudgedPerPulseInPointsAndRun) {
  const double mpe_pulse_j_m2 = 2.0e-2 / std::sqrt(10.0);
  const PointsRun points =
      runExamplePoints("glint_pulsed", "pulsed_nd_yag.json", example("cylinder_186.csv"));
  ASSERT_EQ(points.run.outcome.status, 0) << points.run.outcome.err;
  std::string header;
  const auto rows = readCsvNumbers(points.csv, header);
  EXPECT_EQ(header,
            "x,y,z,irradiance_w_m2,error_estimate_w_m2,evaluations,converged,hazard_ratio,"
            "radiant_exposure_j_m2_per_pulse");
  double peak_ratio = 0.0;
  for (const auto& row : rows) {
    EXPECT_NEAR(row[8], row[3] / 10.0, 1e-15 * row[3]) << "E / f";
    EXPECT_NEAR(row[7], row[8] / mpe_pulse_j_m2, 1e-12 * row[7]) << "H / MPE per pulse";
    peak_ratio = std::max(peak_ratio, row[7]);
  }
  EXPECT_GT(peak_ratio, 0.0);

  const CoarseRun run = runCoarseExample("glint_pulsed_run", {}, "pulsed_nd_yag.json");
  ASSERT_EQ(run.run.status, 0) << run.run.err;
  const nlohmann::json& summary = run.summary;
  const auto& hazard = summary.at("hazard");
  EXPECT_EQ(hazard.at("pulse").at("rule").get<int>(), 3) << hazard.dump();
  EXPECT_NEAR(hazard.at("pulse").at("mpe_j_m2_per_pulse").get<double>(), mpe_pulse_j_m2, 1e-15);
  EXPECT_NEAR(hazard.at("mpe_w_m2").get<double>(), 10.0 * mpe_pulse_j_m2, 1e-14);
  EXPECT_NEAR(hazard.at("peak_radiant_exposure_j_m2_per_pulse").get<double>(),
              hazard.at("peak_hazard_ratio").get<double>() * mpe_pulse_j_m2, 1e-12);
  EXPECT_GT(hazard.at("nominal_hazard_zone").at("volume_m3").get<double>(), 0.0);
  std::filesystem::remove_all(points.run.dir);
}

// examples/cylinder_binoculars.json: 7×50 binoculars, τ = 0.7: gain 0.7 × 49 = 34.3. The aided
// ratio is the unaided one × 34.3 everywhere, and the aided zone holds the unaided one.
TEST(Examples, BinocularsScaleTheAidedRatioAndWidenTheZone) {
  const PointsRun points =
      runExamplePoints("glint_aided", "cylinder_binoculars.json", example("cylinder_186.csv"));
  ASSERT_EQ(points.run.outcome.status, 0) << points.run.outcome.err;
  std::string header;
  for (const auto& row : readCsvNumbers(points.csv, header)) {
    EXPECT_NEAR(row[8], 34.3 * row[7], 1e-12 * row[8]) << "aided = 34.3 × unaided";
  }
  EXPECT_EQ(header.substr(header.size() - 31), "hazard_ratio,aided_hazard_ratio") << header;

  const CoarseRun run = runCoarseExample("glint_aided_run", {}, "cylinder_binoculars.json");
  ASSERT_EQ(run.run.status, 0) << run.run.err;
  const nlohmann::json& summary = run.summary;
  const auto& hazard = summary.at("hazard");
  EXPECT_NEAR(hazard.at("optical_aid").at("gain").get<double>(), 34.3, 1e-12);
  EXPECT_NEAR(hazard.at("aided_peak_hazard_ratio").get<double>(),
              34.3 * hazard.at("peak_hazard_ratio").get<double>(), 1e-9);
  const auto& unaided = hazard.at("nominal_hazard_zone");
  const auto& aided = hazard.at("aided_nominal_hazard_zone");
  // At these 0.5 m voxels the naked eye's zone (peak ratio about 1) may fall between lattice
  // points; the aided one spans the box.
  EXPECT_GT(aided.at("volume_m3").get<double>(), 50.0) << hazard.dump();
  EXPECT_GE(aided.at("volume_m3").get<double>(), unaided.at("volume_m3").get<double>());
  EXPECT_TRUE(aided.at("reaches_box_edge").get<bool>()) << "34.3× reaches beyond the 8 m box";
  EXPECT_TRUE(summary.at("far_field").contains("aided_max_nohd_m")) << summary.dump();
  EXPECT_EQ(run.files.count("far_field_aided.vtp"), 1u) << "the aided eye's hazard boundary";
  EXPECT_EQ(summary.at("far_field").at("files").size(), 3u) << summary.at("far_field").dump();
  std::filesystem::remove_all(points.run.dir);
}

}  // namespace
}  // namespace glint
