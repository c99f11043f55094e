#include "pipeline/commands/points_command.h"

#include <tbb/global_control.h>
#include <tbb/info.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <stdexcept>

#include "export/atomic_file.h"
#include "export/points_csv.h"
#include "observers/exposure.h"
#include "observers/point_set.h"
#include "pipeline/base/input_error.h"
#include "pipeline/base/memory_budget.h"
#include "pipeline/base/number_format.h"
#include "pipeline/base/output_names.h"
#include "pipeline/base/progress.h"
#include "pipeline/base/test_pause.h"
#include "pipeline/input/input_files.h"
#include "pipeline/input/points_file.h"
#include "pipeline/input/scene.h"
#include "pipeline/report/engagement_report.h"
#include "pipeline/report/output_folder.h"
#include "pipeline/report/run_report.h"
#include "pipeline/report/unlit_warning.h"
#include "pipeline/setup/engagement.h"
#include "pipeline/setup/target_builder.h"

namespace glint {
namespace {

// The brightest observer: the row the summary reports and the meshes' surface is checked at.
std::size_t brightest(std::span<const ObserverResult> results) {
  std::size_t peak = 0;
  for (std::size_t i = 0; i < results.size(); ++i) {
    if (results[i].irradiance_w_m2 > results[peak].irradiance_w_m2) peak = i;
  }
  return peak;
}

// Bytes of the points and their results.
std::uint64_t pointsBytes(const std::vector<Vec3>& points) {
  return points.size() * (sizeof(Vec3) + sizeof(ObserverResult));
}

// No infinity may reach the file or read as a harmless 0. An unbounded error with a finite
// value is the lobe scheme saying that a piece of the target stays unbounded from the observer,
// as it does from a point on the target's surface or within about a micrometre of it: that is
// the observer's position, refused with it. Anything else not finite is an internal error. Both
// before anything is written.
void requireFiniteResults(const std::vector<Vec3>& points,
                          const std::vector<ObserverResult>& results) {
  for (std::size_t i = 0; i < results.size(); ++i) {
    const ObserverResult& r = results[i];
    if (std::isfinite(r.irradiance_w_m2) && std::isfinite(r.error_estimate_w_m2)) continue;
    const std::string which =
        "observer " + std::to_string(i + 1) + " (" + formatNumber("%.9g", points[i].x) + ", " +
        formatNumber("%.9g", points[i].y) + ", " + formatNumber("%.9g", points[i].z) + ")";
    if (std::isfinite(r.irradiance_w_m2) && r.error_estimate_w_m2 > 0.0) {
      throw InputError(which +
                       ": its irradiance has no finite bound: a part of the target stays "
                       "unbounded from there, as it does from a point on the target's surface or "
                       "within about a micrometre of it; move the observer off the surface "
                       "(nothing was written)");
    }
    throw std::runtime_error(which +
                             ": the irradiance or its error is not a finite number; nothing "
                             "was written");
  }
}

// The observers' evaluations and how many did not converge.
struct EvaluationTally {
  std::int64_t total = 0, lo = 0, hi = 0;
  std::size_t unconverged = 0, depth_limited = 0;
  double unconverged_upper_w_m2 = 0.0;  ///< the largest irradiance + error of those unconverged
};

EvaluationTally tally(std::span<const ObserverResult> results) {
  EvaluationTally t;
  t.lo = results.empty() ? 0 : results[0].evaluations;
  for (const ObserverResult& r : results) {
    t.total += r.evaluations;
    t.lo = std::min(t.lo, r.evaluations);
    t.hi = std::max(t.hi, r.evaluations);
    t.unconverged += r.converged ? 0 : 1;
    if (!r.converged) {
      t.unconverged_upper_w_m2 =
          std::max(t.unconverged_upper_w_m2, r.irradiance_w_m2 + r.error_estimate_w_m2);
    }
    t.depth_limited += r.depth_limited ? 1 : 0;
  }
  return t;
}

// What culling made of the target's facets.
void printTarget(std::ostream& err, const CullStats& cull) {
  err << "  target: " << cull.coarse_facets << " coarse facets; " << cull.lit << " lit, "
      << cull.facing_away << " facing away from the laser, " << cull.outside_beam
      << " outside the beam, " << cull.degenerate << " degenerate";
  if (cull.occlusion) err << ", " << cull.shadowed << " in the target's shadow";
  err << "\n";
  if (cull.occlusion) err << "  occlusion: rays to the laser and to each observer (Embree)\n";
}

// The limits and the peak's hazard.
void printHazard(std::ostream& err, const HazardSpec& hazard, double e_peak) {
  err << "  hazard: " << hazardLine(hazard) << "; peak hazard ratio "
      << formatNumber("%.3g", hazard.ratio(e_peak));
  if (hazard.aid) err << ", aided " << formatNumber("%.3g", hazard.aidedRatio(e_peak));
  if (hazard.pulse) {
    err << "; peak " << formatNumber("%.3g", hazard.pulseRadiantExposureJ_m2(e_peak))
        << " J/m² a pulse";
  }
  err << "\n";
}

void printSummary(std::ostream& err, const PointsArgs& args, const Scene& scene,
                  const FacetIntegrator& integrator, std::span<const Vec3> points,
                  std::span<const ObserverResult> results, std::size_t peak, double seconds,
                  int threads, const SurfaceModelCheck* surface_check) {
  const IntegratorOptions& opt = integrator.options();
  const EvaluationTally t = tally(results);
  const std::string scheme = args.uniform_level
                                 ? "uniform twin, level " + std::to_string(*args.uniform_level)
                                 : "adaptive, tolerance " + formatNumber("%g", opt.tolerance) +
                                       ", floor " + formatNumber("%.3g", opt.floor_w_m2) + " W/m²";
  err << "glint points: " << points.size() << " observers, " << scheme << ", " << threads
      << (threads == 1 ? " thread\n" : " threads\n");
  err << "  laser: " << laserLine(scene.laser, scene.hazard) << "\n";
  printTarget(err, integrator.cullStats());
  err << "  evaluations: " << formatNumber("%.4g", static_cast<double>(t.total))
      << " in all; per observer "
      << formatNumber("%.4g", static_cast<double>(t.total) / static_cast<double>(results.size()))
      << " on average, " << t.lo << " to " << t.hi << "\n";
  const Vec3& p = points[peak];
  const double e_peak = results[peak].irradiance_w_m2;
  err << "  peak irradiance: " << formatNumber("%.6g", e_peak) << " W/m² at (" << p.x << ", " << p.y
      << ", " << p.z << ")\n";
  printHazard(err, scene.hazard, e_peak);
  err << "  time: " << formatDuration(seconds) << " ("
      << formatNumber("%.3g", static_cast<double>(t.total) / std::max(seconds, 1e-9))
      << " evaluations/s)\n";
  if (!args.uniform_level) {
    if (t.unconverged == 0) {
      err << "  accuracy: all observers within the tolerance\n";
    } else {
      // Their values are estimates short of the tolerance: what they may reach is value plus
      // error, and that is the hazard the analyst must read, not the peak of the estimates.
      const HazardSpec& h = scene.hazard;
      const double upper = t.unconverged_upper_w_m2;
      err << "  warning: " << t.unconverged << " of " << results.size()
          << " observers did not reach the tolerance (converged = 0 in the output; "
          << t.depth_limited << " hit accuracy.max_depth); at them irradiance plus its error "
          << "estimate reaches " << formatNumber("%.3g", upper) << " W/m² ("
          << formatNumber("%.3g", h.ratio(upper)) << " × the MPE"
          << (h.aid ? ", aided " + formatNumber("%.3g", h.aidedRatio(upper)) : std::string())
          << (h.ratio(upper) >= 1.0 || (h.aid && h.aidedRatio(upper) >= 1.0)
                  ? "): they may be hazardous, whatever the peak above says; "
                  : "); ")
          << "raise accuracy.max_evaluations or accuracy.max_depth, or loosen the tolerance\n";
    }
  }
  if (surface_check != nullptr) printSurfaceCheck(err, scene, *surface_check);
  if (args.out_path != "-") err << "  wrote " << args.out_path << "\n";
}

// The hazard of each observer: its ratio (E / MPE), through the optical aid where the scene has
// one, one pulse's radiant exposure for a pulsed laser, and its ratio to each level.
std::vector<CsvColumn> hazardColumns(const HazardSpec& h, std::span<const ObserverResult> results) {
  std::vector<CsvColumn> columns;
  auto add = [&](const std::string& name, auto value) {
    CsvColumn c{name, {}};
    c.values.reserve(results.size());
    for (const ObserverResult& r : results) c.values.push_back(value(r.irradiance_w_m2));
    columns.push_back(std::move(c));
  };
  add("hazard_ratio", [&](double e) { return h.ratio(e); });
  if (h.aid) add("aided_hazard_ratio", [&](double e) { return h.aidedRatio(e); });
  if (h.pulse) {
    add("radiant_exposure_j_m2_per_pulse", [&](double e) { return h.pulseRadiantExposureJ_m2(e); });
  }
  for (const ExposureLevel& l : h.levels)
    add(output_names::levelRatio(l.name), [&](double e) { return l.ratio(e); });
  return columns;
}

// What to do when the target or the observers outgrow the memory budget.
constexpr std::string_view kAdvice =
    "Raise --memory, or lower the objects' segments, or decimate the meshes";

// The observer points, refused when they and their results would not fit @p budget_bytes.
std::vector<Vec3> loadObserverPoints(const std::string& path, std::uint64_t budget_bytes) {
  // The text, its points (24 bytes each) and their results (about 40) take about three times
  // the file's size at ~30 bytes a row: a quarter of the budget for the file keeps them in it.
  std::vector<Vec3> points = loadPoints(path, budget_bytes / 4);
  // The points are resident now, beside the program itself (its libraries take over 100 MB);
  // their results are yet to come.
  const std::uint64_t resident = residentBytes();
  requireWithinBudget(std::to_string(points.size()) +
                          " observer points and their results, beside "
                          "the " +
                          formatBytes(static_cast<double>(resident)) + " the program holds,",
                      resident + points.size() * sizeof(ObserverResult), budget_bytes,
                      "split the points file or raise --memory");
  return points;
}

// An output file in @p outputs, opened before the work: a missing folder, a device or an input
// named as the output should stop the run before the work, not after.
// @throw OutputError for such a path.
AtomicFile* openOutputFile(OutputSet& outputs, const std::string& path, const PointsArgs& args,
                           const Scene& scene) {
  if (const auto kind = nonRegularKind(path)) {
    throw OutputError(path + " is " + *kind +
                      ", not a regular file: glint never replaces one; name a new or regular "
                      "file, or write to standard output with --out -");
  }
  InputFiles inputs;
  inputs.addScene(args.scene_path, scene);
  inputs.add(args.points_path, "points file");
  inputs.requireNotAnInput(path);
  const std::filesystem::path folder = std::filesystem::path(path).parent_path();
  requireFolderNotHeld(folder.empty() ? std::filesystem::path(".") : folder);
  return &outputs.open(path);
}

// The table's file; none for standard output.
AtomicFile* openOutput(OutputSet& outputs, const PointsArgs& args, const Scene& scene) {
  if (args.out_path == "-") return nullptr;
  return openOutputFile(outputs, args.out_path, args, scene);
}

// The time series' file (with an engagement and --time-series), opened before the work as the
// table's is; it may not be the table's own file.
AtomicFile* openTimeSeries(OutputSet& outputs, const PointsArgs& args, const Scene& scene) {
  if (!args.time_series_path) return nullptr;
  if (!scene.engagement) {
    throw InputError("--time-series: " + scene.source +
                     " has no engagement: only an engagement has irradiance over time");
  }
  if (args.out_path != "-" && std::filesystem::path(*args.time_series_path).lexically_normal() ==
                                  std::filesystem::path(args.out_path).lexically_normal()) {
    throw InputError("--time-series names the table's own file (--out)");
  }
  return openOutputFile(outputs, *args.time_series_path, args, scene);
}

// Every observer's result and the seconds they took.
struct Evaluated {
  std::vector<ObserverResult> results;
  double seconds = 0.0;
};

// Evaluates every observer, with progress unless quiet, stopped by the memory watch before the
// next one once the budget is spent.
// @throw std::runtime_error when the budget is spent or a result is not finite.
Evaluated evaluateObservers(const FacetIntegrator& integrator, const std::vector<Vec3>& points,
                            const PointsArgs& args, const MemoryWatch& watch, std::ostream& err,
                            PointExchange* exchange) {
  PointScheme scheme;
  if (args.uniform_level) {
    scheme.uniform = true;
    scheme.uniform_level = *args.uniform_level;
  }
  WorkCounter counter;
  counter.stop = &watch.stopFlag();
  const auto start = std::chrono::steady_clock::now();
  Evaluated e;
  {
    std::unique_ptr<ProgressReporter> progress;
    if (!args.quiet) {
      // Under MPI this rank's share: every size-th point from its rank on.
      const std::size_t ranks =
          exchange != nullptr ? static_cast<std::size_t>(exchange->size()) : 1;
      progress = std::make_unique<ProgressReporter>(err, args.terminal, "observers",
                                                    (points.size() + ranks - 1) / ranks, counter);
    }
    try {
      e.results = evaluatePoints(integrator, points, scheme, &counter, exchange);
    } catch (const WorkStopped&) {
      if (progress) progress->stop();
      watch.check("the observer points", kAdvice);
      throw;
    }
  }
  watch.check("the observer points", kAdvice);
  e.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  requireFiniteResults(points, e.results);
  return e;
}

// Writes through @p write to @p file (committed with the command's other outputs), or to
// @p out.
template <class Write>
void writeTo(AtomicFile* file, std::ostream& out, Write write) {
  if (file != nullptr) {
    file->write(write);
  } else {
    write(out);
    out.flush();
  }
}

void writeTable(AtomicFile* file, std::ostream& out, const std::vector<Vec3>& points,
                const std::vector<ObserverResult>& results, const HazardSpec& hazard) {
  const std::vector<CsvColumn> columns = hazardColumns(hazard, results);
  writeTo(file, out, [&](std::ostream& s) { writePointsCsv(s, points, results, columns); });
}

// The summary on the terminal, with the meshes' surface model checked where it matters most:
// at the brightest observer.
void report(std::ostream& err, const PointsArgs& args, const Scene& scene,
            const FacetIntegrator& integrator, const std::vector<Vec3>& points,
            const Evaluated& evaluated, int threads) {
  std::optional<SurfaceModelCheck> surface_check;
  const std::size_t peak = brightest(evaluated.results);
  if (scene.hasMeshes() && !args.uniform_level && !points.empty()) {
    surface_check =
        checkSurfaceModel(scene, integrator, {{"row " + std::to_string(peak + 1), points[peak]}});
  }
  printSummary(err, args, scene, integrator, points, evaluated.results, peak, evaluated.seconds,
               threads, surface_check ? &*surface_check : nullptr);
}

}  // namespace

void runPoints(const PointsArgs& requested, std::ostream& out, std::ostream& err,
               PointExchange* exchange) {
  // Under MPI every rank computes its share of the observers and receives the others'; rank 0
  // alone reports and writes.
  const bool writer = exchange == nullptr || exchange->rank() == 0;
  PointsArgs args = requested;
  if (!writer) args.quiet = true;
  const std::uint64_t budget =
      args.memory_bytes > 0 ? args.memory_bytes : defaultMemoryBudgetBytes();
  // A mesh is refused before it is decoded, the target before it is built.
  Scene scene = loadScene(args.scene_path, budget);
  overrideAccuracy(scene.accuracy, args.normals, args.scheme, scene.source);
  const std::vector<Vec3> points = loadObserverPoints(args.points_path, budget);
  IntegratorOptions options = scene.accuracy;
  if (args.tolerance) options.tolerance = *args.tolerance;
  if (scene.engagement && args.uniform_level) {
    throw InputError("--uniform: " + scene.source +
                     " has an engagement, whose samples are each integrated adaptively");
  }
  // An engagement keeps every observer's samples: at least its first ones, each a time, an
  // irradiance and their sorting record (the watch covers the rest as they grow).
  const std::uint64_t held_bytes =
      pointsBytes(points) +
      (scene.engagement
           ? points.size() *
                 (static_cast<std::uint64_t>(scene.engagement->time.initial_intervals) + 1) * 32
           : 0);
  if (scene.engagement) {
    requireWithinBudget(std::to_string(points.size()) + " observers' first time samples",
                        held_bytes, budget,
                        "split the points file, lower engagement.time.initial_intervals or raise "
                        "--memory");
  }
  // The table and the time series appear together or not at all.
  OutputSet outputs;
  AtomicFile* file = nullptr;
  AtomicFile* series = nullptr;
  if (writer) {
    file = openOutput(outputs, args, scene);
    series = openTimeSeries(outputs, args, scene);
  }
  if (file != nullptr || series != nullptr) pauseForTestsAfterTemporaries(err);
  const auto commit = [&] {
    outputs.commit([&] { pauseForTestsAfterFirstOutput(err); });
    pauseForTestsAfterOutputs(err);
  };

  std::unique_ptr<tbb::global_control> thread_limit;
  if (args.threads > 0) {
    thread_limit = std::make_unique<tbb::global_control>(
        tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(args.threads));
  }
  const int threads = args.threads > 0 ? args.threads : tbb::info::default_concurrency();

  // The workspaces grow with what each observer sees, not with the scene: the watch covers
  // them (and whatever the estimate leaves out), stopping the points before their next one.
  MemoryWatch watch(budget);
  noteTerrain(watch, scene);
  watch.noteHeld(std::to_string(points.size()) + " observer points and their results",
                 pointsBytes(points), "split the points file");
  const FacetIntegrator integrator =
      buildIntegrator(scene, options,
                      {budget, held_bytes + terrainMemoryBytes(scene),
                       std::to_string(points.size()) + " observer points" +
                           (scene.terrain ? " and " + terrainMemoryWhat(scene) : "")});
  watch.check("building the target", kAdvice);
  if (scene.engagement) {
    const EngagementResults results = sampleEngagement(
        integrator, scene, points,
        WorkWatch{watch, "the observers", args.quiet ? nullptr : &err, args.terminal, exchange});
    if (!writer) return;
    const std::vector<CsvColumn> columns = engagementColumns(results, scene.hazard);
    if (series != nullptr) series->write([&](std::ostream& s) { writeTimeSeriesCsv(s, results); });
    writeTo(file, out, [&](std::ostream& s) { writeColumnsCsv(s, points, columns); });
    commit();
    if (!args.quiet) printEngagementSummary(err, scene, points, results, threads);
    return;
  }
  const Evaluated evaluated = evaluateObservers(integrator, points, args, watch, err, exchange);
  if (!writer) return;
  writeTable(file, out, points, evaluated.results, scene.hazard);
  // The table's columns of ratios took memory too: a budget passed while writing leaves the
  // folder as it was.
  watch.check("writing the table", "Split the points file or raise --memory");
  commit();
  if (!args.quiet) report(err, args, scene, integrator, points, evaluated, threads);
  // Even when quiet: an empty result that is not a safe one must not pass unremarked.
  for (const std::string& w : unlitTargetWarnings(scene, integrator.cullStats()))
    err << "glint points: warning: " << w << "\n";
}

}  // namespace glint
