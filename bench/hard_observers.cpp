// The observers that are hard for an adaptive integrator (issue 16's classes: a beam edge across
// a glint, near a sphere's terminator, grazing forward scatter, the near field), each scheme at
// the scene's own accuracy, against an independent reference: the brute force of the tests
// (tests/support/brute_force.h: the integrand written out again, nested adaptive Gauss–Kronrod
// in the shape's exact parametrisation; nothing of facets/ is evaluated by it).
//
//   glint_hard_bench SCENE.json... [--schemes lobe,paper] [--out hard.csv] (the table on
//   standard output; the CSV only with --out)
//
// Each scene (one cylinder, sphere or disk; see bench/scenes/hard/) comes with its observers in
// the CSV file of the same name. Per scene and scheme: how many observers converged, the
// median, 99th percentile and largest evaluations per observer, the wall time, and the achieved
// error against what was allowed (tolerance × reference + floor + the reference's own error).
#include <tbb/parallel_for.h>

#include <CLI/CLI.hpp>
#include <algorithm>
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
#include "support/brute_force.h"

using namespace glint;

namespace {

struct Row {
  std::string scene, scheme;
  int observers = 0, converged = 0;
  std::int64_t median = 0, p99 = 0, max = 0;
  double mean = 0.0, seconds = 0.0;
  double worst_error_over_allowed = 0.0;  // over the observers reported converged
  double max_rel_error = 0.0;             // over all observers, relative to the peak reference
  int estimate_below_error = 0;           // converged observers whose own estimate < achieved
};

// The reference's view of the scene's only object.
test::brute::Parametrisation parametrisation(const ObjectSpec& o, const Beam& beam,
                                             const Vec3& observer_m) {
  const AnalyticShape* shape = o.analytic();
  if (!shape) throw std::runtime_error("the reference needs an analytic shape, not a mesh");
  // One case a shape: a shape without its parametrisation here does not compile.
  struct Exact {
    const Beam& beam;
    const Vec3& observer_m;
    test::brute::Parametrisation operator()(const CylinderShape& c) const {
      return test::brute::cylinder(c);
    }
    test::brute::Parametrisation operator()(const DiskShape& d) const {
      return test::brute::disk(d);
    }
    test::brute::Parametrisation operator()(const ConeShape& c) const {
      return test::brute::cone(c);
    }
    // The glint lies in the plane of the beam, the centre and the observer: its normal as the
    // pole keeps the glint on the equator, far from the parametrisation's poles.
    test::brute::Parametrisation operator()(const SphereShape& sphere) const {
      const Vec3 to = observer_m - sphere.centre_m;
      Vec3 pole = glm::cross(beam.direction, to);
      if (glm::length(pole) < 1e-6 * glm::length(to)) {
        pole = glm::cross(beam.direction, Vec3(0.3, 0.5, 0.7));
      }
      return test::brute::sphere(sphere, pole);
    }
  };
  return std::visit(Exact{beam, observer_m}, *shape);
}

std::int64_t quantile(std::vector<std::int64_t> v, double q) {
  std::sort(v.begin(), v.end());
  const auto k = static_cast<std::size_t>(std::ceil(q * static_cast<double>(v.size()))) - 1;
  return v[std::min(k, v.size() - 1)];
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"glint_hard_bench: hard observers, each scheme against a brute-force reference"};
  std::vector<std::string> scene_paths;
  std::vector<std::string> schemes{"lobe", "paper"};
  std::string out_path;  // no CSV unless asked for
  app.add_option("scenes", scene_paths, "Scene files; observers in <scene>.csv")->required();
  app.add_option("--schemes", schemes)
      ->delimiter(',')
      ->check(CLI::IsMember({"lobe", "paper", "cubature"}));
  app.add_option("--out", out_path, "Also write the table as CSV here");
  CLI11_PARSE(app, argc, argv);

  std::vector<Row> rows;
  for (const std::string& path : scene_paths) {
    const Scene scene = loadScene(path);
    if (scene.objects.size() != 1) {
      std::cerr << path << ": the reference needs a scene of one object\n";
      return 2;
    }
    const std::vector<Vec3> points =
        loadPoints(std::filesystem::path(path).replace_extension(".csv"));
    const Target target = buildTarget(scene);
    const Beam beam = scene.laser;
    const Material material = target.materials.at(scene.objects[0].material);
    const IntegratorOptions options = scene.accuracy;

    std::vector<test::brute::Estimate> ref(points.size());
    tbb::parallel_for(std::size_t(0), points.size(), [&](std::size_t i) {
      ref[i] = test::brute::irradiance(parametrisation(scene.objects[0], beam, points[i]), beam,
                                       material, points[i]);
    });
    double peak = 0.0;
    for (const auto& r : ref) peak = std::max(peak, r.value);

    for (const std::string& name : schemes) {
      IntegratorOptions o = options;
      o.scheme = name == "lobe"    ? IntegrationScheme::Lobe
                 : name == "paper" ? IntegrationScheme::Paper
                                   : IntegrationScheme::Cubature;
      const FacetIntegrator fi(target, beam, o);
      const auto t0 = std::chrono::steady_clock::now();
      const std::vector<ObserverResult> r = evaluatePoints(fi, points, PointScheme{});
      Row row;
      row.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      row.scene = std::filesystem::path(path).stem().string();
      row.scheme = name;
      row.observers = static_cast<int>(points.size());
      std::vector<std::int64_t> evaluations;
      for (std::size_t i = 0; i < r.size(); ++i) {
        evaluations.push_back(r[i].evaluations);
        row.mean += static_cast<double>(r[i].evaluations) / static_cast<double>(r.size());
        const double error = std::abs(r[i].irradiance_w_m2 - ref[i].value);
        row.max_rel_error = std::max(row.max_rel_error, error / std::max(peak, 1e-300));
        if (!r[i].converged) continue;
        ++row.converged;
        const double allowed = o.tolerance * ref[i].value + o.floor_w_m2 + ref[i].error;
        row.worst_error_over_allowed = std::max(row.worst_error_over_allowed, error / allowed);
        if (r[i].error_estimate_w_m2 + ref[i].error < error) ++row.estimate_below_error;
      }
      row.median = quantile(evaluations, 0.5);
      row.p99 = quantile(evaluations, 0.99);
      row.max = quantile(evaluations, 1.0);
      rows.push_back(row);
      std::fprintf(stderr, "%s, %s: %d of %d converged, evaluations median %lld, max %lld\n",
                   row.scene.c_str(), name.c_str(), row.converged, row.observers,
                   static_cast<long long>(row.median), static_cast<long long>(row.max));
    }
  }

  std::ofstream out;
  if (!out_path.empty()) out.open(out_path);
  out << "scene,scheme,observers,converged,evaluations_median,evaluations_p99,evaluations_max,"
         "evaluations_mean,seconds,worst_error_over_allowed,max_rel_error,estimate_below_error\n";
  std::printf("%-18s %-6s %9s %8s %8s %8s %9s %12s %12s %s\n", "scene", "scheme", "converged",
              "median", "p99", "max", "seconds", "err/allowed", "max rel err", "estimate<err");
  for (const Row& r : rows) {
    out << r.scene << ',' << r.scheme << ',' << r.observers << ',' << r.converged << ',' << r.median
        << ',' << r.p99 << ',' << r.max << ',' << r.mean << ',' << r.seconds << ','
        << r.worst_error_over_allowed << ',' << r.max_rel_error << ',' << r.estimate_below_error
        << '\n';
    std::printf("%-18s %-6s %4d/%-4d %8lld %8lld %8lld %9.3f %12.3g %12.3g %d\n", r.scene.c_str(),
                r.scheme.c_str(), r.converged, r.observers, static_cast<long long>(r.median),
                static_cast<long long>(r.p99), static_cast<long long>(r.max), r.seconds,
                r.worst_error_over_allowed, r.max_rel_error, r.estimate_below_error);
  }
  return 0;
}
