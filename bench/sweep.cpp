// Run time against error for glint points: the adaptive integration over a range of
// tolerances and the uniform twin over a range of levels, each measured against a reference
// that shares no decision with the adaptive code: the uniform twin at two deep levels,
// Richardson-extrapolated (its second-order convergence checked on the way).
//
//   glint_sweep SCENE.json POINTS.csv --reference-level 9 [--tolerances 1e-2,1e-3,...]
//               [--levels 3,4,5,...] [--normals surface|flat] [--out results.csv]
//               [--reference-tolerance 1e-7] [--lobe-tolerances 1e-2,1e-3,...]
//
// "adaptive" rows are the paper's scheme (whatever the scene's accuracy.scheme), "lobe" rows the
// lobe scheme (integrator.h), "uniform" rows the uniform twin; the reference is always computed
// with the paper's scheme or the uniform twin, never with the lobe scheme it judges.
//
// Where the uniform twin converges too slowly to serve (σ = 0.003: levels 7 and 8 still differ
// by a third at the worst observer), --reference-tolerance makes the reference the adaptive
// integration at that tolerance instead: not independent of the code under test, but a
// thousand times tighter than the tolerances it judges.
//
// The reference is cached beside the output as <out>.reference.csv (delete it to recompute).
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

#include "observers/point_set.h"
#include "pipeline/input/points_file.h"
#include "pipeline/input/scene.h"
#include "pipeline/setup/target_builder.h"

using namespace glint;

namespace {

struct Row {
  std::string scheme;  // "adaptive" (the paper's), "lobe" or "uniform"
  double parameter;    // tolerance or level
  double evaluations_per_observer;
  double seconds;
  double max_error;  // relative, over observers
  double rms_error;
  int unconverged;
};

double seconds(const std::chrono::steady_clock::time_point& t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

std::vector<double> reference(const FacetIntegrator& fi, const std::vector<Vec3>& points, int level,
                              const std::filesystem::path& cache) {
  std::vector<double> ref(points.size());
  if (std::ifstream in(cache); in) {
    std::size_t n = 0;
    while (n < ref.size() && in >> ref[n]) ++n;
    if (n == ref.size()) return ref;
  }
  std::vector<double> coarse(points.size());
  tbb::enumerable_thread_specific<IntegratorWorkspace> workspaces;
  tbb::parallel_for(std::size_t(0), points.size(), [&](std::size_t i) {
    IntegratorWorkspace& ws = workspaces.local();
    coarse[i] = fi.uniform(points[i], level - 1, ws).irradiance_w_m2;
    ref[i] = fi.uniform(points[i], level, ws).irradiance_w_m2;
  });
  double worst_change = 0.0;
  std::ofstream out(cache);
  out.precision(17);
  for (std::size_t i = 0; i < ref.size(); ++i) {
    const double fine = ref[i];
    ref[i] = fine + (fine - coarse[i]) / 3.0;  // second-order Richardson
    worst_change =
        std::max(worst_change, std::abs(fine - coarse[i]) / std::max(std::abs(fine), 1e-300));
    out << ref[i] << "\n";
  }
  std::fprintf(stderr, "reference: uniform levels %d and %d, largest change %.2e (relative)\n",
               level - 1, level, worst_change);
  return ref;
}

Row measure(const FacetIntegrator& fi, const std::vector<Vec3>& points, const PointScheme& scheme,
            const std::vector<double>& ref, double floor_w_m2) {
  const auto t0 = std::chrono::steady_clock::now();
  const std::vector<ObserverResult> r = evaluatePoints(fi, points, scheme);
  const char* name = scheme.uniform                                   ? "uniform"
                     : fi.options().scheme == IntegrationScheme::Lobe ? "lobe"
                                                                      : "adaptive";
  Row row{name, 0, 0, seconds(t0), 0, 0, 0};
  double evals = 0.0, sq = 0.0;
  for (std::size_t i = 0; i < r.size(); ++i) {
    evals += static_cast<double>(r[i].evaluations);
    // Relative to the observer's irradiance, with the floor for observers that see nothing.
    const double err =
        std::abs(r[i].irradiance_w_m2 - ref[i]) / std::max(std::abs(ref[i]), floor_w_m2);
    row.max_error = std::max(row.max_error, err);
    sq += err * err;
    row.unconverged += (!scheme.uniform && !r[i].converged) ? 1 : 0;
  }
  row.evaluations_per_observer = evals / static_cast<double>(r.size());
  row.rms_error = std::sqrt(sq / static_cast<double>(r.size()));
  return row;
}

std::vector<double> parseList(const std::string& s) {
  std::vector<double> v;
  std::stringstream ss(s);
  for (std::string item; std::getline(ss, item, ',');) v.push_back(std::stod(item));
  return v;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"glint_sweep: adaptive and uniform integration against a uniform-twin reference"};
  std::string scene_path, points_path, out_path = "sweep.csv", normals = "surface";
  std::string tolerances = "1e-2,3e-3,1e-3,3e-4,1e-4,1e-5", levels = "2,3,4,5,6,7";
  std::string lobe_tolerances;
  int reference_level = 8;
  double reference_tolerance = 0.0;
  app.add_option("scene", scene_path)->required();
  app.add_option("points", points_path)->required();
  app.add_option("--reference-level", reference_level)->check(CLI::Range(2, 12));
  app.add_option("--reference-tolerance", reference_tolerance)->check(CLI::Range(1e-12, 1e-3));
  app.add_option("--tolerances", tolerances);
  app.add_option("--levels", levels);
  app.add_option("--lobe-tolerances", lobe_tolerances, "Also run the lobe scheme at these");
  app.add_option("--normals", normals)->check(CLI::IsMember({"surface", "flat"}));
  app.add_option("--out", out_path);
  CLI11_PARSE(app, argc, argv);

  const Scene scene = loadScene(scene_path);
  const std::vector<Vec3> points = loadPoints(points_path);
  IntegratorOptions options = scene.accuracy;
  options.scheme = IntegrationScheme::Paper;  // the "adaptive" rows and the reference
  options.normals = normals == "flat" ? NormalModel::Flat : NormalModel::Surface;
  std::vector<double> ref;
  if (reference_tolerance > 0.0) {
    IntegratorOptions o = options;
    o.tolerance = reference_tolerance;
    o.max_evaluations = 100'000'000;
    const FacetIntegrator fi(buildTarget(scene), scene.laser, o);
    for (const ObserverResult& r : evaluatePoints(fi, points, PointScheme{})) {
      ref.push_back(r.irradiance_w_m2);
    }
    std::fprintf(stderr, "reference: adaptive at tolerance %g\n", reference_tolerance);
  } else {
    ref = reference(FacetIntegrator(buildTarget(scene), scene.laser, options), points,
                    reference_level, out_path + ".reference.csv");
  }

  std::vector<Row> rows;
  auto adaptive_runs = [&](const std::string& list, IntegrationScheme scheme) {
    if (list.empty()) return;
    for (double tol : parseList(list)) {
      IntegratorOptions o = options;
      o.tolerance = tol;
      o.scheme = scheme;
      rows.push_back(measure(FacetIntegrator(buildTarget(scene), scene.laser, o), points,
                             PointScheme{}, ref, options.floor_w_m2));
      rows.back().parameter = tol;
    }
  };
  adaptive_runs(tolerances, options.scheme);
  adaptive_runs(lobe_tolerances, IntegrationScheme::Lobe);
  const FacetIntegrator fi(buildTarget(scene), scene.laser, options);
  for (double level : parseList(levels)) {
    rows.push_back(
        measure(fi, points, PointScheme{true, static_cast<int>(level)}, ref, options.floor_w_m2));
    rows.back().parameter = level;
  }

  std::ofstream out(out_path);
  out << "scheme,parameter,evaluations_per_observer,seconds,max_rel_error,rms_rel_error,"
         "unconverged\n";
  std::printf("%-9s %9s %14s %9s %12s %12s %s\n", "scheme", "param", "evals/observer", "seconds",
              "max error", "rms error", "unconverged");
  for (const Row& r : rows) {
    out << r.scheme << ',' << r.parameter << ',' << r.evaluations_per_observer << ',' << r.seconds
        << ',' << r.max_error << ',' << r.rms_error << ',' << r.unconverged << '\n';
    std::printf("%-9s %9g %14.0f %9.3f %12.3e %12.3e %d\n", r.scheme.c_str(), r.parameter,
                r.evaluations_per_observer, r.seconds, r.max_error, r.rms_error, r.unconverged);
  }
  // The cheapest row of `scheme` (by `cost`) at least as accurate as `than`, if any.
  auto cheapest_as_accurate = [&](const std::string& scheme, const Row& than,
                                  double Row::*cost) -> const Row* {
    const Row* best = nullptr;
    for (const Row& r : rows) {
      if (r.scheme == scheme && r.max_error <= than.max_error && (!best || r.*cost < best->*cost)) {
        best = &r;
      }
    }
    return best;
  };
  // The lobe scheme against the cheapest run of the paper's scheme at least as accurate.
  for (const Row& l : rows) {
    if (l.scheme != "lobe") continue;
    if (const Row* best = cheapest_as_accurate("adaptive", l, &Row::seconds)) {
      std::printf(
          "lobe at %-7g max error %.2e: %.0f vs %.0f evaluations (paper at %g): %.1fx "
          "fewer, %.1fx faster\n",
          l.parameter, l.max_error, l.evaluations_per_observer, best->evaluations_per_observer,
          best->parameter, best->evaluations_per_observer / l.evaluations_per_observer,
          best->seconds / l.seconds);
    } else {
      std::printf("lobe at %-7g max error %.2e: no run of the paper's scheme is as accurate\n",
                  l.parameter, l.max_error);
    }
  }
  // Savings at equal accuracy: the cheapest uniform level at least as accurate (max error).
  std::printf("\nat equal accuracy (max error): adaptive vs the cheapest uniform level as good\n");
  for (const Row& a : rows) {
    if (a.scheme != "adaptive") continue;
    if (const Row* best = cheapest_as_accurate("uniform", a, &Row::evaluations_per_observer)) {
      std::printf(
          "tolerance %-7g max error %.2e: %.0f vs %.0f evaluations (level %g): %.1fx fewer, %.1fx "
          "faster\n",
          a.parameter, a.max_error, a.evaluations_per_observer, best->evaluations_per_observer,
          best->parameter, best->evaluations_per_observer / a.evaluations_per_observer,
          best->seconds / a.seconds);
    } else {
      std::printf("tolerance %-7g max error %.2e: no uniform level measured is as accurate\n",
                  a.parameter, a.max_error);
    }
  }
  return 0;
}
