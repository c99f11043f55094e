#include "pipeline/batch_command.h"

#include <tbb/global_control.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "export/atomic_file.h"
#include "export/exr_map.h"
#include "export/field_files.h"
#include "export/lattice_vdb.h"
#include "glint/version.h"
#include "pipeline/batch_report.h"
#include "pipeline/cluster.h"
#include "pipeline/input_error.h"
#include "pipeline/json_reader.h"
#include "pipeline/memory_budget.h"
#include "pipeline/output_names.h"
#include "pipeline/progress.h"
#include "pipeline/run_command.h"
#include "pipeline/study.h"
#include "pipeline/study_maps.h"
#include "pipeline/target_builder.h"

namespace glint {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

std::string scenarioDirName(std::size_t index) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "s%06zu", index);
  return buf;
}

// Computes one scenario on this rank, writes its folder (result.json last: its presence means
// the scenario is done) and adds it to the rank's aggregates. Returns result.json's text.
std::string runScenario(const Study& study, const Scenario& s, std::vector<StudyLattice>& lattices,
                        const fs::path& out_dir, const MemoryWatch& watch) {
  const auto start = Clock::now();
  // The scene from the base scene in memory; its file is the scenario's record.
  const Scene scene = scenarioScene(study, s);
  const std::string scene_json = scenarioSceneJson(study, s);
  const double mpe = scene.hazard.mpe_w_m2;
  const fs::path dir = out_dir / output_names::kScenariosFolder / scenarioDirName(s.index);
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw OutputError(dir.string() + ": cannot create the scenario folder: " + ec.message());

  AtomicFile scene_file(dir / output_names::kScenarioScene);
  scene_file.stream() << scene_json;
  scene_file.commit();

  const RunInfo info =
      runInfo(scene, (dir / output_names::kScenarioScene).string(), scene_json, "adaptive");

  nlohmann::json record = {{"study_fnv1a64", study.fnv1a64},
                           {"scenario", s.index},
                           {"parameters", scenarioParametersJson(s)}};
  nlohmann::json results = nlohmann::json::array();
  std::int64_t evaluations = 0, unconverged = 0;
  // The scenario's target, built and culled once for all its lattices.
  const SceneTarget target = sceneTarget(scene, lattices.front().spec);
  for (StudyLattice& r : lattices) {
    // The region's own lattice (the observers do not move with the target), so every
    // scenario's map adds point for point.
    const FieldProblem problem = fieldProblem(target, scene, r.spec);
    WorkCounter counter;
    counter.stop = &watch.stopFlag();
    ObserverField field = [&] {
      try {
        return computeField(problem.integrator, r.spec, problem.excluded, &counter);
      } catch (const WorkStopped&) {
        watch.check("scenario " + std::to_string(s.index) + ", region " + r.name);
        throw;
      }
    }();
    requireFinite(field, "scenario " + std::to_string(s.index) + ", region " + r.name);
    const FieldStats st = field.stats();
    AtomicFile map(dir / r.scenarioFile());
    std::vector<float> e;
    if (r.plane) {
      PlaneMap m = planeMap(field, scene.hazard);
      writeExr(map.stream(), m, {info.program_version, info.wavelength_nm, mpe});
      e = std::move(m.irradiance_w_m2);
    } else {
      e = field.irradianceLattice();
      writeVdb(map.stream(), std::move(field), info);
    }
    map.commit();
    results.push_back(scenarioRegionJson(r, st, scene.hazard, r.add(e, scene.hazard)));
    evaluations += st.evaluations;
    unconverged += st.unconverged_points;
  }
  record["regions"] = results;
  if (scene.far_field.enabled) {
    const FarField far =
        sceneFarField(target, scene, watch, "scenario " + std::to_string(s.index) + ", far field",
                      nullptr, false);
    record["far_field"] = scenarioFarFieldJson(far, scene.hazard);
    evaluations += far.stats().evaluations;
  }
  record["evaluations"] = evaluations;
  record["unconverged_points"] = unconverged;
  record["seconds"] = std::chrono::duration<double>(Clock::now() - start).count();
  const std::string text = record.dump(2) + "\n";
  AtomicFile result(dir / output_names::kScenarioResult);
  result.stream() << text;
  result.commit();
  return text;
}

// A finished scenario of an earlier run: its record and maps, when they are whole and belong
// to this study. Nothing when the scenario must be (re)computed.
std::optional<nlohmann::json> resumeScenario(const Study& study, const Scenario& s,
                                             std::vector<StudyLattice>& lattices,
                                             const fs::path& out_dir, bool fresh, std::ostream& err,
                                             bool quiet) {
  const fs::path dir = out_dir / output_names::kScenariosFolder / scenarioDirName(s.index);
  std::error_code ec;
  if (!fs::is_regular_file(dir / output_names::kScenarioResult, ec)) return std::nullopt;
  nlohmann::json record;
  std::string fnv;
  bool matches = false;
  try {
    record =
        nlohmann::json::parse(readUserFile(dir / output_names::kScenarioResult, "scenario result"));
    fnv = record.at("study_fnv1a64").get<std::string>();
    matches =
        record.at("scenario").get<std::size_t>() == s.index &&
        record.at("regions").size() == lattices.size() &&
        record.contains("far_field") == study.base.far_field.enabled &&
        // A result from before the scene had an optical aid lacks the aided figures.
        (!study.base.hazard.aid || record.at("regions").at(0).contains("aided_peak_hazard_ratio"));
  } catch (const std::exception&) {
    if (!quiet)
      err << "glint batch: " << (dir / output_names::kScenarioResult).string()
          << " unreadable: redone\n";
    return std::nullopt;
  }
  if (fnv != study.fnv1a64) {
    if (fresh) return std::nullopt;
    throw InputError(out_dir.string() + ": holds results of another study (or of this study " +
                     "before it changed): " + (dir / output_names::kScenarioResult).string() +
                     " has study " + fnv + ", this study is " + study.fnv1a64 +
                     ". Use --fresh to discard them, or another --out folder");
  }
  if (!matches) {
    if (!quiet)
      err << "glint batch: " << (dir / output_names::kScenarioResult).string()
          << " does not match: redone\n";
    return std::nullopt;
  }
  // Maps read in full before any is added, so a damaged file leaves the aggregates untouched.
  std::vector<std::vector<float>> maps;
  try {
    for (const StudyLattice& r : lattices) {
      const std::string path = (dir / r.scenarioFile()).string();
      if (r.plane) {
        int w = 0, h = 0;
        maps.push_back(readExrChannel(path, "irradiance_w_m2", w, h));
        const auto n = r.spec.nodes();
        if (w != n[0] || h != n[1]) throw std::runtime_error(path + ": not this plane's size");
      } else {
        maps.push_back(readLatticeVdb(path, "irradiance_w_m2", r.spec));
      }
    }
  } catch (const std::exception& e) {
    if (!quiet) err << "glint batch: scenario " << s.index << " redone: " << e.what() << "\n";
    return std::nullopt;
  }
  for (std::size_t i = 0; i < lattices.size(); ++i) lattices[i].add(maps[i], study.base.hazard);
  return record;
}

}  // namespace

void runBatch(const BatchArgs& args, Cluster& cluster, std::ostream& err) {
  const auto wall_start = Clock::now();
  const bool root = cluster.rank() == 0;
  const bool talk = root && !args.quiet;
  const Study study = loadStudy(args.study_path);
  fs::path out_dir = args.out_dir;
  if (out_dir.empty()) out_dir = fs::path("out") / fs::path(args.study_path).stem();

  std::unique_ptr<tbb::global_control> thread_limit;
  if (args.threads > 0) {
    thread_limit = std::make_unique<tbb::global_control>(
        tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(args.threads));
  }

  std::vector<StudyLattice> lattices = studyLattices(study.base);
  // Each region keeps its dense maps over the scenarios besides one scenario's field at a time:
  // refused before any of them is allocated.
  const std::uint64_t budget =
      args.memory_bytes > 0 ? args.memory_bytes : defaultMemoryBudgetBytes();
  std::uint64_t floor_bytes = 0;
  for (const StudyLattice& r : lattices) {
    floor_bytes += r.mapBytes() + fieldMemoryFloorBytes(r.spec, false);
  }
  requireWithinBudget("the study's regions (" + std::to_string(lattices.size()) + ")", floor_bytes,
                      budget,
                      "coarsen the base scene's voxel_m or pixel_m, shrink its regions, or "
                      "raise --memory");
  // A scenario moves the base scene's objects and never adds facets: its target and far field
  // are the base scene's, besides the maps.
  const std::uint64_t far_bytes =
      study.base.far_field.enabled ? farFieldMemoryFloorBytes(farFieldLattice(study.base)) : 0;
  requireTargetWithinBudget(
      targetMemory(study.base, fieldIntegratorOptions(study.base, lattices.front().spec)),
      {budget, floor_bytes + far_bytes, "the study's regions and far field"});
  for (StudyLattice& r : lattices) r.allocate();
  const MemoryWatch watch(budget);
  std::map<std::size_t, nlohmann::json> records;  // rank 0: every scenario's result
  std::vector<std::size_t> todo;
  std::size_t resumed = 0;
  if (root) {
    std::error_code ec;
    if (args.fresh) fs::remove_all(out_dir / output_names::kScenariosFolder, ec);
    fs::create_directories(out_dir / output_names::kScenariosFolder, ec);
    if (ec)
      throw OutputError(out_dir.string() + ": cannot create the output folder: " + ec.message());
    for (const Scenario& s : study.scenarios) {
      if (auto rec = resumeScenario(study, s, lattices, out_dir, args.fresh, err, args.quiet)) {
        records[s.index] = std::move(*rec);
        ++resumed;
      } else {
        todo.push_back(s.index);
      }
    }
    if (talk) {
      err << "glint batch: " << study.scenarios.size() << " scenarios of " << study.source;
      if (resumed > 0) err << " (" << resumed << " done before, " << todo.size() << " to run)";
      err << " on " << cluster.size() << (cluster.size() == 1 ? " process" : " MPI ranks")
          << "; scenario folders in " << (out_dir / output_names::kScenariosFolder).string()
          << "\n";
    }
  }

  const auto run_start = Clock::now();
  auto last_print = run_start;
  std::size_t finished = 0;
  cluster.shareOut(
      todo,
      [&](std::size_t index) {
        return runScenario(study, study.scenarios[index], lattices, out_dir, watch);
      },
      [&](std::size_t index, const std::string& record) {
        records[index] = nlohmann::json::parse(record);
        ++finished;
        if (!talk) return;
        const auto now = Clock::now();
        const bool last = finished == todo.size();
        if (!args.terminal && !last && now - last_print < std::chrono::seconds(10)) return;
        last_print = now;
        const double elapsed = std::chrono::duration<double>(now - run_start).count();
        const double left =
            elapsed / static_cast<double>(finished) * static_cast<double>(todo.size() - finished);
        double peak = 0.0;
        for (const auto& r : records[index].at("regions"))
          peak = std::max(peak, r.at("peak_hazard_ratio").get<double>());
        std::string line = "batch: " + std::to_string(finished) + "/" +
                           std::to_string(todo.size()) + " scenarios, " + formatDuration(elapsed) +
                           (last ? "" : ", about " + formatDuration(left) + " left") +
                           "; scenario " + std::to_string(index) + ": peak hazard ratio " +
                           formatNumber("%.3g", peak);
        if (args.terminal) {
          err << "\r\033[K" << line << (last ? "\n" : "") << std::flush;
        } else {
          err << line << "\n";
        }
      });

  for (StudyLattice& r : lattices) {
    cluster.maxToRoot(r.max_w_m2);
    cluster.sumToRoot(r.hazardous);
    if (r.aided) cluster.sumToRoot(r.aided_hazardous);
  }
  if (!root) return;

  const std::size_t n = study.scenarios.size();
  AtomicFile csv(out_dir / output_names::kScenariosCsv);
  csv.stream() << scenariosCsv(lattices, records, study.base.far_field.enabled,
                               study.base.hazard.aid.has_value());
  csv.commit();
  for (const StudyLattice& r : lattices) writeStudyMap(out_dir / r.studyFile(), r, study, n);
  const double wall_s = std::chrono::duration<double>(Clock::now() - wall_start).count();
  const nlohmann::json summary =
      batchSummaryJson(study, lattices, records, resumed, cluster.size(), wall_s);
  AtomicFile summary_file(out_dir / output_names::kSummary);
  summary_file.stream() << summary.dump(2) << "\n";
  summary_file.commit();
  if (talk) printBatchSummary(err, summary, lattices, out_dir, wall_s);
}

}  // namespace glint
