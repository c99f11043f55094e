// Adaptive observer field against its uniform dense twin, scene by scene: evaluations, wall
// time and the accuracy the issue asks for (max error ≤ tolerance × peak + floor, volumes
// above 1 %, 10 %, 50 % of the peak within 1 %, no bright voxel skipped), and the volume above
// the scene's MPE (the nominal hazard zone) in either field.
//
//   glint_field_bench SCENE.json [SCENE.json ...] [--voxel M] [--tolerance T[,T...]]
//                     [--scheme lobe|paper|cubature] [--out results.csv]
//
// Each scene needs an `observers` box; --voxel overrides its finest spacing (the coarsest
// block keeps its size in metres, so the refinement gets one more level per halving) and
// --tolerance its tolerance; --scheme its accuracy.scheme (both fields use it). The dense twin does
// not depend on the tolerance: it runs once per scene, then the adaptive field once per tolerance,
// one row each. Memory: the grids of each field, and the peak resident set during the adaptive
// field, working memory included (the peak is reset before each adaptive run through
// /proc/self/clear_refs).
#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>

#include "observers/field_compare.h"
#include "pipeline/input_error.h"
#include "pipeline/scene.h"
#include "pipeline/target_builder.h"

using namespace glint;

namespace {

struct Row {
  std::string scene;
  FieldSpec spec;
  FieldStats adaptive, dense;
  FieldComparison comparison;
  std::int64_t adaptive_peak_rss_bytes = 0;
};

// The peak resident set of this process so far (Linux: VmHWM), 0 where unknown.
std::int64_t peakRssBytes() {
  std::ifstream status("/proc/self/status");
  for (std::string line; std::getline(status, line);) {
    if (line.rfind("VmHWM:", 0) == 0) return std::stoll(line.substr(6)) * 1024;  // kB
  }
  return 0;
}

// Restarts the peak resident set (VmHWM) from the current one; false where the kernel refuses.
bool resetPeakRss() {
  std::ofstream clear("/proc/self/clear_refs");
  clear << "5";
  clear.flush();
  return static_cast<bool>(clear);
}

std::vector<Row> measure(const std::filesystem::path& path, double voxel_m,
                         const std::vector<double>& tolerances,
                         std::optional<IntegrationScheme> scheme) {
  Scene scene = loadScene(path);
  if (scheme) scene.accuracy.scheme = *scheme;
  FieldSpec spec = fieldSpec(scene);
  if (voxel_m > 0.0) {
    const double block_m = spec.voxel_m * spec.block_voxels;
    spec.voxel_m = voxel_m;
    spec.block_voxels = 1;
    while (spec.block_voxels * voxel_m < block_m * (1.0 - 1e-9)) spec.block_voxels *= 2;
  }
  const FieldProblem problem = fieldProblem(scene, spec);
  std::fprintf(stderr, "%s: dense ...\n", path.filename().c_str());
  const ObserverField dense = computeDenseField(problem.integrator, spec, problem.excluded);
  std::vector<Row> rows;
  for (const double tolerance : tolerances.empty() ? std::vector{spec.tolerance} : tolerances) {
    FieldSpec s = spec;
    s.tolerance = tolerance;
    std::fprintf(stderr, "%s: adaptive, tolerance %g ...\n", path.filename().c_str(), tolerance);
    const bool rss_valid = resetPeakRss();
    const ObserverField adaptive = computeField(problem.integrator, s, problem.excluded);
    rows.push_back({path.filename().string(), s, adaptive.stats(), dense.stats(),
                    compareFields(adaptive, dense, scene.hazard.mpe.irradiance_w_m2),
                    rss_valid ? peakRssBytes() : 0});
  }
  return rows;
}

double ratio(double a, double b) { return b > 0.0 ? a / b : 0.0; }

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"glint_field_bench: adaptive observer field against its dense twin"};
  std::vector<std::string> scenes;
  double voxel_m = 0.0;
  std::string out_path;
  app.add_option("scenes", scenes, "scene files with an observers box")->required();
  app.add_option("--voxel", voxel_m, "override the finest voxel size (m)");
  std::vector<double> tolerances;
  app.add_option("--tolerance", tolerances, "override the field's tolerance (a list: one row each)")
      ->delimiter(',')
      ->check(CLI::Range(1e-6, 0.5));
  std::string scheme_name;
  app.add_option("--scheme", scheme_name, "override the scenes' integration scheme")
      ->check(CLI::IsMember(integrationSchemeNames()));
  app.add_option("--out", out_path, "write the rows as CSV");
  CLI11_PARSE(app, argc, argv);
  std::optional<IntegrationScheme> scheme;
  if (!scheme_name.empty()) scheme = integrationSchemeByName(scheme_name);

  std::vector<Row> rows;
  try {
    for (const std::string& s : scenes) {
      for (Row& r : measure(s, voxel_m, tolerances, scheme)) rows.push_back(std::move(r));
    }
  } catch (const InputError& e) {
    std::cerr << "glint_field_bench: " << e.what() << "\n";
    return 2;
  }

  std::printf(
      "%-18s %6s %7s %9s | %9s %10s %8s | %9s %10s %8s | %6s %6s | %9s %9s | %6s %6s %6s | %s\n",
      "scene", "voxel", "tol.", "points", "adapt.pts", "adapt.eval", "adapt.s", "dense.pts", "dense.eval",
      "dense.s", "eval×", "time×", "max.err", "allowed", "V1%", "V10%", "V50%", "bright skipped");
  for (const Row& r : rows) {
    const FieldComparison& c = r.comparison;
    std::printf(
        "%-18s %6.3f %7.3g %9lld | %9lld %10.3e %8.1f | %9lld %10.3e %8.1f | %6.1f %6.1f | %9.3g "
        "%9.3g | %6.4f %6.4f %6.4f | %lld\n",
        r.scene.c_str(), r.spec.voxel_m, r.spec.tolerance, static_cast<long long>(r.adaptive.lattice_points),
        static_cast<long long>(r.adaptive.evaluated_points),
        static_cast<double>(r.adaptive.evaluations), r.adaptive.seconds,
        static_cast<long long>(r.dense.evaluated_points), static_cast<double>(r.dense.evaluations),
        r.dense.seconds,
        ratio(static_cast<double>(r.dense.evaluations),
              static_cast<double>(r.adaptive.evaluations)),
        ratio(r.dense.seconds, r.adaptive.seconds), c.max_error_w_m2, c.allowed_error_w_m2,
        c.volumeRatio(0), c.volumeRatio(1), c.volumeRatio(2),
        static_cast<long long>(c.bright_skipped));
  }
  if (!out_path.empty()) {
    std::ofstream out(out_path);
    out << "scene,voxel_m,tolerance,lattice_points,adaptive_points,adaptive_evaluations,adaptive_"
           "seconds,"
           "adaptive_unconverged,dense_points,dense_evaluations,dense_seconds,dense_unconverged,"
           "peak_w_m2,max_error_w_m2,rms_error_w_m2,allowed_error_w_m2,volume_ratio_1pct,"
           "volume_ratio_10pct,volume_ratio_50pct,bright_skipped,within_accuracy,"
           "adaptive_grid_bytes,dense_grid_bytes,adaptive_peak_rss_bytes,mpe_w_m2,"
           "dense_volume_above_mpe_m3,volume_ratio_mpe\n";
    for (const Row& r : rows) {
      const FieldComparison& c = r.comparison;
      out << r.scene << ',' << r.spec.voxel_m << ',' << r.spec.tolerance << ','
          << r.adaptive.lattice_points << ',' << r.adaptive.evaluated_points << ','
          << r.adaptive.evaluations << ',' << r.adaptive.seconds << ','
          << r.adaptive.unconverged_points << ',' << r.dense.evaluated_points << ','
          << r.dense.evaluations << ',' << r.dense.seconds << ',' << r.dense.unconverged_points
          << ',' << c.peak_w_m2 << ',' << c.max_error_w_m2 << ',' << c.rms_error_w_m2 << ','
          << c.allowed_error_w_m2 << ',' << c.volumeRatio(0) << ',' << c.volumeRatio(1) << ','
          << c.volumeRatio(2) << ',' << c.bright_skipped << ','
          << (c.withinAccuracy() ? "yes" : "no") << ',' << r.adaptive.grid_bytes << ','
          << r.dense.grid_bytes << ',' << r.adaptive_peak_rss_bytes << ',' << c.level_w_m2 << ','
          << c.dense_level_volume_m3 << ',' << c.levelVolumeRatio() << '\n';
    }
  }
  bool all_within = true;
  for (const Row& r : rows) all_within = all_within && r.comparison.withinAccuracy();
  return all_within ? 0 : 1;
}
