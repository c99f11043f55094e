// Adaptive observer field against its uniform dense twin, scene by scene: evaluations, wall
// time and the accuracy the issue asks for (max error ≤ tolerance × peak + floor, volumes
// above 1 %, 10 %, 50 % of the peak within 1 %, no bright voxel skipped), and the volume above
// the scene's MPE (the nominal hazard zone) in either field.
//
//   glint_field_bench SCENE.json [SCENE.json ...] [--voxel M] [--tolerance T[,T...]]
//                     [--scheme lobe|paper|cubature] [--isotropic] [--dense-sample N]
//                     [--out results.csv]
//
// Each scene needs an `observers` box; --voxel overrides its finest spacing (the coarsest
// block keeps its size in metres, so the refinement gets one more level per halving) and
// --tolerance its tolerance; --scheme its accuracy.scheme (both fields use it). The dense twin does
// not depend on the tolerance: it runs once per scene, then the adaptive field once per tolerance,
// one row each. Memory: the grids of each field, and the peak resident set during the adaptive
// field, working memory included (the peak is reset before each adaptive run through
// /proc/self/clear_refs).
//
// --isotropic halves every axis of a refined block (the octree of the first versions), to set
// beside the default anisotropic refinement. --dense-sample N replaces the dense twin, where it
// is too slow, by direct integration at N random lattice points (uniform, seeded; a point inside
// the target costs nothing, as in the twin): their mean cost × the lattice points estimates the
// twin's evaluations (± its standard error), and the adaptive field is checked against them and
// against every lattice point within a voxel of a feature of the scene's cylinders (the planes of
// their rims, where the reflected sheet ends, and the sides of their shadows), at the accuracy
// the field promises (tolerance × peak + floor).
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <limits>
#include <optional>
#include <random>

#include "observers/field_compare.h"
#include "pipeline/base/input_error.h"
#include "pipeline/input/scene.h"
#include "pipeline/setup/target_builder.h"

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

double ratio(double a, double b) { return b > 0.0 ? a / b : 0.0; }

// The adaptive field against direct integration at sampled lattice points (--dense-sample).
struct SampledRow {
  std::string scene;
  FieldSpec spec;
  FieldStats adaptive;
  std::int64_t adaptive_peak_rss_bytes = 0;
  std::int64_t sample_points = 0;
  double dense_evaluations = 0.0;     // estimated: mean cost of a random point × points
  double dense_evaluations_se = 0.0;  // its standard error
  double dense_seconds = 0.0;         // estimated likewise from the samples' time
  std::int64_t feature_points = 0;
  double peak_w_m2 = 0.0;
  double max_error_w_m2 = 0.0;
  Vec3 max_error_at_m{0.0};
  double allowed_error_w_m2 = 0.0;
  [[nodiscard]] bool withinAccuracy() const { return max_error_w_m2 <= allowed_error_w_m2; }
};

using Index3 = std::array<int, 3>;

// The lattice points within one voxel of a feature of the scene's cylinders: the planes of
// their rims (|along axis| = L/2), and behind them the sides of their shadows (distance R from
// the axis across the beam, in the half-space beyond the centre).
std::vector<Index3> featurePoints(const Scene& scene, const FieldSpec& spec) {
  const std::array<int, 3> n = spec.nodes();
  const Vec3 beam = scene.laser.direction;
  std::vector<Index3> out;
  for (int i = 0; i < n[0]; ++i)
    for (int j = 0; j < n[1]; ++j)
      for (int k = 0; k < n[2]; ++k) {
        const Vec3 x = spec.position(i, j, k);
        for (const ObjectSpec& o : scene.objects) {
          const AnalyticShape* shape = o.analytic();
          const CylinderShape* c = shape ? std::get_if<CylinderShape>(shape) : nullptr;
          if (!c) continue;
          const Vec3 v = x - c->centre_m;
          const bool rim =
              std::abs(std::abs(glm::dot(v, c->axis)) - 0.5 * c->length_m) <= spec.voxel_m;
          const Vec3 across = glm::cross(c->axis, beam);
          const double across_len = glm::length(across);
          const bool shadow_side =
              across_len > 1e-9 && glm::dot(v, beam) > 0.0 &&
              std::abs(std::abs(glm::dot(v, across / across_len)) - c->radius_m) <= spec.voxel_m;
          if (rim || shadow_side) {
            out.push_back({i, j, k});
            break;
          }
        }
      }
  return out;
}

// The adaptive field of @p s, with the process's peak resident set while it ran.
struct AdaptiveRun {
  ObserverField field;
  std::int64_t peak_rss_bytes = 0;  // 0 where the kernel would not reset the peak
};

AdaptiveRun runAdaptive(const std::filesystem::path& path, const FieldProblem& problem,
                        const FieldSpec& s) {
  std::fprintf(stderr, "%s: adaptive, tolerance %g ...\n", path.filename().c_str(), s.tolerance);
  const bool rss_valid = resetPeakRss();
  ObserverField field = computeField(problem.integrator, s, problem.excluded);
  return {std::move(field), rss_valid ? peakRssBytes() : 0};
}

SampledRow measureSampled(const std::filesystem::path& path, const Scene& scene,
                          const FieldProblem& problem, const FieldSpec& s, int samples) {
  SampledRow row;
  row.scene = path.filename().string();
  row.spec = s;
  const AdaptiveRun run = runAdaptive(path, problem, s);
  const ObserverField& adaptive = run.field;
  row.adaptive = adaptive.stats();
  row.adaptive_peak_rss_bytes = run.peak_rss_bytes;

  const std::array<int, 3> n = s.nodes();
  std::mt19937_64 rng(20261124);
  std::vector<Index3> points;
  for (int p = 0; p < samples; ++p) {
    points.push_back({std::uniform_int_distribution<int>(0, n[0] - 1)(rng),
                      std::uniform_int_distribution<int>(0, n[1] - 1)(rng),
                      std::uniform_int_distribution<int>(0, n[2] - 1)(rng)});
  }
  const std::vector<Index3> features = featurePoints(scene, s);
  row.sample_points = samples;
  row.feature_points = static_cast<std::int64_t>(features.size());
  points.insert(points.end(), features.begin(), features.end());
  std::fprintf(stderr, "%s: direct integration at %d random and %zu feature points ...\n",
               path.filename().c_str(), samples, features.size());

  struct Direct {
    double irradiance_w_m2 = 0.0;
    std::int64_t evaluations = 0;
    double seconds = 0.0;
    bool excluded = false;
  };
  std::vector<Direct> direct(points.size());
  tbb::enumerable_thread_specific<IntegratorWorkspace> workspaces;
  const auto start = std::chrono::steady_clock::now();
  tbb::parallel_for(std::size_t{0}, points.size(), [&](std::size_t p) {
    const Vec3 x = s.position(points[p][0], points[p][1], points[p][2]);
    if (problem.excluded && problem.excluded(x)) {
      direct[p].excluded = true;
      return;
    }
    const auto t0 = std::chrono::steady_clock::now();
    const ObserverResult r = problem.integrator.adaptive(x, workspaces.local());
    direct[p] = {r.irradiance_w_m2, r.evaluations,
                 std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count()};
  });
  const double wall =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  // The twin's cost from the random points alone (features are not a uniform sample).
  double sum = 0.0, sum_sq = 0.0, cpu = 0.0, cpu_all = 0.0;
  for (std::size_t p = 0; p < direct.size(); ++p) {
    cpu_all += direct[p].seconds;
    if (p >= static_cast<std::size_t>(samples)) continue;
    const double e = static_cast<double>(direct[p].evaluations);
    sum += e;
    sum_sq += e * e;
    cpu += direct[p].seconds;
  }
  const double points_in_box = static_cast<double>(row.adaptive.lattice_points);
  const double mean = sum / samples;
  const double variance = samples > 1 ? (sum_sq - samples * mean * mean) / (samples - 1) : 0.0;
  row.dense_evaluations = mean * points_in_box;
  row.dense_evaluations_se = std::sqrt(std::max(variance, 0.0) / samples) * points_in_box;
  // The random points' share of the wall time (on all threads), scaled to the box.
  row.dense_seconds = cpu_all > 0.0 ? wall * (cpu / cpu_all) * points_in_box / samples : 0.0;

  row.peak_w_m2 = row.adaptive.peak_w_m2;
  for (const Direct& d : direct) row.peak_w_m2 = std::max(row.peak_w_m2, d.irradiance_w_m2);
  row.allowed_error_w_m2 = s.tolerance * row.peak_w_m2 + s.floor_w_m2;
  for (std::size_t p = 0; p < points.size(); ++p) {
    if (direct[p].excluded) continue;
    const Index3& q = points[p];
    if (adaptive.status(q[0], q[1], q[2]) == VoxelStatus::Excluded) continue;
    const double error =
        std::abs(adaptive.irradiance(q[0], q[1], q[2]) - direct[p].irradiance_w_m2);
    // A NaN error is the worst error.
    if (!(error <= row.max_error_w_m2)) {
      row.max_error_w_m2 = std::isnan(error) ? std::numeric_limits<double>::infinity() : error;
      row.max_error_at_m = s.position(q[0], q[1], q[2]);
    }
  }
  return row;
}

struct Options {
  double voxel_m = 0.0;
  std::vector<double> tolerances;
  std::optional<IntegrationScheme> scheme;
  bool isotropic = false;
  int dense_sample = 0;
};

FieldSpec benchSpec(const Scene& scene, const Options& o) {
  FieldSpec spec = fieldSpec(scene);
  if (o.voxel_m > 0.0) {
    const double block_m = spec.voxel_m * spec.block_voxels;
    spec.voxel_m = o.voxel_m;
    spec.block_voxels = 1;
    while (spec.block_voxels * o.voxel_m < block_m * (1.0 - 1e-9)) spec.block_voxels *= 2;
  }
  spec.anisotropic = !o.isotropic;
  return spec;
}

// A scene as the options set it up: its lattice, its problem, and the lattice once per
// tolerance asked (the scene's own when none is).
struct BenchCase {
  Scene scene;
  FieldSpec spec;
  FieldProblem problem;

  [[nodiscard]] std::vector<FieldSpec> perTolerance(const Options& o) const {
    std::vector<FieldSpec> out;
    for (const double t : o.tolerances.empty() ? std::vector{spec.tolerance} : o.tolerances) {
      out.push_back(spec);
      out.back().tolerance = t;
    }
    return out;
  }
};

BenchCase loadCase(const std::filesystem::path& path, const Options& o) {
  Scene scene = loadScene(path);
  if (o.scheme) scene.accuracy.scheme = *o.scheme;
  const FieldSpec spec = benchSpec(scene, o);
  FieldProblem problem = fieldProblem(scene, spec);
  return {std::move(scene), spec, std::move(problem)};
}

std::vector<SampledRow> measureSampled(const std::filesystem::path& path, const Options& o) {
  const BenchCase c = loadCase(path, o);
  std::vector<SampledRow> rows;
  for (const FieldSpec& s : c.perTolerance(o)) {
    rows.push_back(measureSampled(path, c.scene, c.problem, s, o.dense_sample));
  }
  return rows;
}

std::vector<Row> measure(const std::filesystem::path& path, const Options& o) {
  const BenchCase c = loadCase(path, o);
  std::fprintf(stderr, "%s: dense ...\n", path.filename().c_str());
  const ObserverField dense = computeDenseField(c.problem.integrator, c.spec, c.problem.excluded);
  std::vector<Row> rows;
  for (const FieldSpec& s : c.perTolerance(o)) {
    const AdaptiveRun run = runAdaptive(path, c.problem, s);
    rows.push_back({path.filename().string(), s, run.field.stats(), dense.stats(),
                    compareFields(run.field, dense, c.scene.hazard.mpe_w_m2), run.peak_rss_bytes});
  }
  return rows;
}

// Every scene's rows, or nothing where a scene file is refused (the message on stderr).
template <class RowT>
std::optional<std::vector<RowT>> measureScenes(
    const std::vector<std::string>& scenes,
    const std::function<std::vector<RowT>(const std::string&)>& measureOne) {
  std::vector<RowT> rows;
  try {
    for (const std::string& s : scenes) {
      for (RowT& r : measureOne(s)) rows.push_back(std::move(r));
    }
  } catch (const InputError& e) {
    std::cerr << "glint_field_bench: " << e.what() << "\n";
    return std::nullopt;
  }
  return rows;
}

// --dense-sample: one row per scene and tolerance, printed and written as CSV.
int sampledMain(const std::vector<std::string>& scenes, const Options& options,
                const std::string& out_path) {
  const std::optional<std::vector<SampledRow>> measured = measureScenes<SampledRow>(
      scenes, [&](const std::string& s) { return measureSampled(s, options); });
  if (!measured) return 2;
  const std::vector<SampledRow>& rows = *measured;
  std::printf("%-18s %6s %7s %11s | %9s %10s %7s %8s | %10s %9s %7s | %13s | %7s %9s %9s\n",
              "scene", "voxel", "tol.", "points", "adapt.pts", "adapt.eval", "adapt.s", "RSS MB",
              "dense.eval", "± s.e.", "dense.s", "eval× (± s.e.)", "checked", "max.err", "allowed");
  for (const SampledRow& r : rows) {
    const double ev = static_cast<double>(r.adaptive.evaluations);
    std::printf(
        "%-18s %6.3f %7.3g %11lld | %9lld %10.3e %7.1f %8.0f | %10.3e %9.2e %7.0f | %6.1f ± %4.1f "
        "| "
        "%7lld %9.3g %9.3g\n",
        r.scene.c_str(), r.spec.voxel_m, r.spec.tolerance,
        static_cast<long long>(r.adaptive.lattice_points),
        static_cast<long long>(r.adaptive.evaluated_points), ev, r.adaptive.seconds,
        static_cast<double>(r.adaptive_peak_rss_bytes) / 1e6, r.dense_evaluations,
        r.dense_evaluations_se, r.dense_seconds, ratio(r.dense_evaluations, ev),
        ratio(r.dense_evaluations_se, ev),
        static_cast<long long>(r.sample_points + r.feature_points), r.max_error_w_m2,
        r.allowed_error_w_m2);
  }
  if (!out_path.empty()) {
    std::ofstream out(out_path);
    out << "scene,voxel_m,tolerance,anisotropic,lattice_points,adaptive_points,adaptive_"
           "evaluations,"
           "adaptive_seconds,adaptive_peak_rss_bytes,adaptive_grid_bytes,active_voxels,"
           "sample_points,dense_evaluations_estimate,dense_evaluations_se,dense_seconds_estimate,"
           "feature_points,peak_w_m2,max_error_w_m2,allowed_error_w_m2,within_accuracy\n";
    for (const SampledRow& r : rows) {
      out << r.scene << ',' << r.spec.voxel_m << ',' << r.spec.tolerance << ','
          << (r.spec.anisotropic ? "yes" : "no") << ',' << r.adaptive.lattice_points << ','
          << r.adaptive.evaluated_points << ',' << r.adaptive.evaluations << ','
          << r.adaptive.seconds << ',' << r.adaptive_peak_rss_bytes << ',' << r.adaptive.grid_bytes
          << ',' << r.adaptive.active_voxels << ',' << r.sample_points << ',' << r.dense_evaluations
          << ',' << r.dense_evaluations_se << ',' << r.dense_seconds << ',' << r.feature_points
          << ',' << r.peak_w_m2 << ',' << r.max_error_w_m2 << ',' << r.allowed_error_w_m2 << ','
          << (r.withinAccuracy() ? "yes" : "no") << '\n';
    }
  }
  bool all_within = true;
  for (const SampledRow& r : rows) all_within = all_within && r.withinAccuracy();
  return all_within ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"glint_field_bench: adaptive observer field against its dense twin"};
  std::vector<std::string> scenes;
  Options options;
  std::string out_path;
  app.add_option("scenes", scenes, "scene files with an observers box")->required();
  app.add_option("--voxel", options.voxel_m, "override the finest voxel size (m)");
  app.add_option("--tolerance", options.tolerances,
                 "override the field's tolerance (a list: one row each)")
      ->delimiter(',')
      ->check(CLI::Range(1e-6, 0.5));
  std::string scheme_name;
  app.add_option("--scheme", scheme_name, "override the scenes' integration scheme")
      ->check(CLI::IsMember(integrationSchemeNames()));
  app.add_flag("--isotropic", options.isotropic,
               "halve every axis of a refined block (the first versions' octree)");
  app.add_option("--dense-sample", options.dense_sample,
                 "instead of the dense twin, integrate N random lattice points and the cylinders' "
                 "feature points directly")
      ->check(CLI::Range(2, 100000000));
  app.add_option("--out", out_path, "write the rows as CSV");
  CLI11_PARSE(app, argc, argv);
  if (!scheme_name.empty()) options.scheme = integrationSchemeByName(scheme_name);

  if (options.dense_sample > 0) return sampledMain(scenes, options, out_path);
  const std::optional<std::vector<Row>> measured =
      measureScenes<Row>(scenes, [&](const std::string& s) { return measure(s, options); });
  if (!measured) return 2;
  const std::vector<Row>& rows = *measured;

  std::printf(
      "%-18s %6s %7s %9s | %9s %10s %8s | %9s %10s %8s | %6s %6s | %9s %9s | %6s %6s %6s | %s\n",
      "scene", "voxel", "tol.", "points", "adapt.pts", "adapt.eval", "adapt.s", "dense.pts",
      "dense.eval", "dense.s", "eval×", "time×", "max.err", "allowed", "V1%", "V10%", "V50%",
      "bright skipped");
  for (const Row& r : rows) {
    const FieldComparison& c = r.comparison;
    std::printf(
        "%-18s %6.3f %7.3g %9lld | %9lld %10.3e %8.1f | %9lld %10.3e %8.1f | %6.1f %6.1f | %9.3g "
        "%9.3g | %6.4f %6.4f %6.4f | %lld\n",
        r.scene.c_str(), r.spec.voxel_m, r.spec.tolerance,
        static_cast<long long>(r.adaptive.lattice_points),
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
