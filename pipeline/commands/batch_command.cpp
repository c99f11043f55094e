#include "pipeline/commands/batch_command.h"

#include <tbb/global_control.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>

#include "export/atomic_file.h"
#include "export/exr_map.h"
#include "export/field_files.h"
#include "export/fnv1a.h"
#include "export/lattice_vdb.h"
#include "glint/version.h"
#include "pipeline/base/input_error.h"
#include "pipeline/base/memory_budget.h"
#include "pipeline/base/number_format.h"
#include "pipeline/base/output_names.h"
#include "pipeline/base/phase_clock.h"
#include "pipeline/base/test_pause.h"
#include "pipeline/commands/cluster.h"
#include "pipeline/input/input_files.h"
#include "pipeline/input/json_reader.h"
#include "pipeline/input/study.h"
#include "pipeline/report/batch_report.h"
#include "pipeline/report/engagement_report.h"
#include "pipeline/report/hazard_report.h"
#include "pipeline/report/output_folder.h"
#include "pipeline/report/run_outputs.h"
#include "pipeline/report/run_report.h"
#include "pipeline/report/unlit_warning.h"
#include "pipeline/setup/scene_regions.h"
#include "pipeline/setup/study_maps.h"
#include "pipeline/setup/target_builder.h"

namespace glint {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

std::string scenarioDirName(std::size_t index) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "s%06zu", index);
  return buf;
}

bool isScenarioDirName(const std::string& name) {
  return name.size() == 7 && name[0] == 's' &&
         std::all_of(name.begin() + 1, name.end(), [](char c) { return c >= '0' && c <= '9'; });
}

// result.json vouches for its own figures and for the files beside it: a checksum of the record
// without this field, and one of each file's bytes (scene.json and the maps, by name).
constexpr const char* kRecordChecksum = "result_fnv1a64";
constexpr const char* kFileChecksums = "files_fnv1a64";

std::string hex64(std::uint64_t h) {
  char buf[20];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
  return buf;
}

// The record's own checksum: of its canonical text (nlohmann's dump, keys sorted, numbers in
// their shortest round-trip form), so a record read back gives the text it was written from.
std::string recordChecksum(nlohmann::json record) {
  record.erase(kRecordChecksum);
  return fnv1a64Hex(record.dump());
}

// FNV-1a 64 of a file's bytes.
// @throw OutputError when it cannot be read.
std::string fileChecksum(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw OutputError(path.string() + ": cannot be read");
  std::uint64_t h = kFnv1aOffsetBasis;
  std::array<char, 1 << 16> buf{};
  while (in) {
    in.read(buf.data(), static_cast<std::streamsize>(buf.size()));
    h = fnv1a64(std::string_view(buf.data(), static_cast<std::size_t>(in.gcount())), h);
  }
  if (in.bad()) throw OutputError(path.string() + ": cannot be read");
  return hex64(h);
}

// One of @p names, or a temporary of one (export/atomic_file.h: `.<name>.glint-<pid>-<random>`,
// and glint 0.1's `<name>.tmp.<pid>`).
bool isGlintFile(const std::string& file, const std::vector<std::string>& names) {
  return std::any_of(names.begin(), names.end(), [&](const std::string& n) {
    return file == n || file.rfind("." + n + ".glint-", 0) == 0 || file.rfind(n + ".tmp.", 0) == 0;
  });
}

// Removes the scenario folders (sNNNNNN) under @p scenarios with glint's files in them, and
// nothing else: a file or folder of someone else's stays, and so does the scenario folder
// holding it. Returns what stayed.
std::vector<fs::path> removeScenarioFolders(const fs::path& scenarios,
                                            const std::vector<std::string>& names) {
  std::vector<fs::path> kept;
  std::error_code ec;
  std::vector<fs::directory_entry> entries;
  for (fs::directory_iterator it(scenarios, ec), end; !ec && it != end; it.increment(ec))
    entries.push_back(*it);
  for (const fs::directory_entry& e : entries) {
    // symlink_status: a link named like a scenario folder is someone else's, never followed.
    if (!isScenarioDirName(e.path().filename().string()) ||
        e.symlink_status(ec).type() != fs::file_type::directory) {
      kept.push_back(e.path());
      continue;
    }
    std::vector<fs::directory_entry> files;
    for (fs::directory_iterator it(e.path(), ec), end; !ec && it != end; it.increment(ec))
      files.push_back(*it);
    for (const fs::directory_entry& f : files) {
      const bool ours = isGlintFile(f.path().filename().string(), names) &&
                        f.symlink_status(ec).type() != fs::file_type::directory;
      if (!ours || !fs::remove(f.path(), ec)) kept.push_back(f.path());
    }
    fs::remove(e.path(), ec);  // rmdir: stays if anything is left in it
  }
  return kept;
}

// "a, b, c and 4 more".
std::string listed(const std::vector<fs::path>& paths) {
  std::string s;
  const std::size_t shown = std::min<std::size_t>(paths.size(), 5);
  for (std::size_t i = 0; i < shown; ++i) s += (i > 0 ? ", " : "") + paths[i].string();
  if (paths.size() > shown) s += " and " + std::to_string(paths.size() - shown) + " more";
  return s;
}

// After a failed run: the folders it made go again, unless a scenario in them is finished (the
// next run resumes from it). Scenario folders only inside a scenarios/ this run made: every
// glint file in them is this run's (rank 0 holds the folder's lock).
void removeFailedRun(const OutputFolder& out, const std::vector<std::string>& names) noexcept {
  try {
    const fs::path scenarios = out.path() / output_names::kScenariosFolder;
    if (out.made(scenarios)) {
      std::error_code ec;
      for (fs::directory_iterator it(scenarios, ec), end; !ec && it != end; it.increment(ec)) {
        if (isScenarioDirName(it->path().filename().string()) &&
            fs::exists(it->path() / output_names::kScenarioResult, ec)) {
          return;
        }
      }
      removeScenarioFolders(scenarios, names);
    }
  } catch (...) {
    // Cleaning up after an error: the error is what the user must see.
  }
}

// A scenario's folder: scenarios/sNNNNNN.
fs::path scenarioDir(const fs::path& out_dir, std::size_t index) {
  return out_dir / output_names::kScenariosFolder / scenarioDirName(index);
}

// One scenario as this rank computes it: its scene, target and folder.
struct ScenarioWork {
  const Scene& scene;
  const SceneTarget& target;
  const RunInfo& info;
  const ScenarioMaps& maps;
  const fs::path& dir;
  const MemoryWatch& watch;
  std::string what;         // "scenario <index>", as the errors name it
  std::size_t combination;  // combinationOf() the scenario
};

// What the scenario's record adds up over its regions.
struct ScenarioTally {
  nlohmann::json files;  // each file's checksum, by name
  nlohmann::json regions = nlohmann::json::array();
  std::int64_t evaluations = 0;
  std::int64_t unconverged = 0;
};

// An engagement's scenario over a region: its maps over time, as glint run writes them of the
// scenario's scene, added to the rank's aggregates by each point's worst window.
void runEngagementRegion(const ScenarioWork& w, StudyLattice& r, ScenarioTally& tally) {
  const EngagementRegion e = engagementRegion(w.target.integrator, w.scene, r.spec,
                                              WorkWatch{w.watch, w.what + ", region " + r.name});
  std::vector<std::string> written;
  if (r.plane) {
    const std::vector<ExrChannel> channels = e.maps.channels();
    written =
        w.maps.writeEngagementPlane(r.plane_index, {e.maps.grid, channels, w.info, nullptr, {}});
  } else {
    const std::vector<LatticeChannel> channels = e.maps.latticeChannels();
    written = w.maps.writeEngagementBox({r.spec, channels, w.info});
  }
  for (const std::string& name : written) tally.files[name] = fileChecksum(w.dir / name);
  const HazardSpec& h = w.scene.hazard;
  const HazardousPoints n = r.add(engagementValues(e, h), h, w.combination);
  tally.regions.push_back(scenarioEngagementRegionJson(r, e, h, n));
  for (const ExposureHistory& history : e.results.histories)
    tally.evaluations += history.evaluations;
  tally.unconverged += e.maps.unconverged;
}

// Computes one region of the scenario, writes its maps (the run's writers, ScenarioMaps) and
// adds it to the rank's aggregates and to @p tally.
void runScenarioRegion(const ScenarioWork& w, StudyLattice& r, ScenarioTally& tally) {
  if (w.scene.engagement) {
    runEngagementRegion(w, r, tally);
    return;
  }
  const FieldProblem problem = fieldProblem(w.target, w.scene, r.spec);
  // On the region's own lattice: the observers do not move with the target, so every
  // scenario's map adds point for point.
  ObserverField field =
      sceneField(problem, r.spec, false, {w.watch, w.what + ", region " + r.name}, "points");
  const FieldStats st = field.stats();
  // As the maps hold it, and taken before the VDB takes the grids.
  const RegionValues e{r.plane ? planeIrradiance(field) : field.irradianceLattice(), {}, {}};
  std::vector<std::string> written;
  if (r.plane) {
    written = w.maps.writePlane(r.plane_index, {field, w.scene.hazard, w.info, nullptr, {}});
  } else {
    BoxResults box{field, problem.integrator, w.info};
    written = w.maps.writeBox(box);
  }
  for (const std::string& name : written) tally.files[name] = fileChecksum(w.dir / name);
  tally.regions.push_back(
      scenarioRegionJson(r, st, w.scene.hazard, r.add(e, w.scene.hazard, w.combination)));
  tally.evaluations += st.evaluations;
  tally.unconverged += st.unconverged_points;
}

// The scenario's scene.json, its record of the scene (written first). Returns its text.
std::string writeScenarioScene(const Study& study, const Scenario& s, const fs::path& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw OutputError(dir.string() + ": cannot create the scenario folder: " + ec.message());
  const std::string scene_json = scenarioSceneJson(study, s);
  AtomicFile scene_file(dir / output_names::kScenarioScene);
  scene_file.stream() << scene_json;
  scene_file.commit();
  return scene_json;
}

// result.json, written last (its presence means the scenario is done), with its own checksum.
// Returns its text.
std::string writeScenarioResult(nlohmann::json record, const fs::path& dir) {
  record[kRecordChecksum] = recordChecksum(record);
  const std::string text = record.dump(2) + "\n";
  AtomicFile result(dir / output_names::kScenarioResult);
  result.stream() << text;
  result.commit();
  return text;
}

// Computes one scenario on this rank, writes its folder (scene.json, the maps, result.json
// last) and adds it to the rank's aggregates. Returns result.json's text.
std::string runScenario(const Study& study, const Scenario& s, std::vector<StudyLattice>& lattices,
                        const fs::path& out_dir, const MemoryWatch& watch) {
  const auto start = Clock::now();
  // The scene from the base scene in memory; its file is the scenario's record.
  const Scene scene = scenarioScene(study, s);
  const fs::path dir = scenarioDir(out_dir, s.index);
  const std::string scene_json = writeScenarioScene(study, s, dir);
  const RunInfo info =
      runInfo(scene, (dir / output_names::kScenarioScene).string(), scene_json, "adaptive");
  // The scenario's target, built and culled once for all its lattices.
  const SceneTarget target = sceneTarget(scene, lattices.front().spec);
  const ScenarioMaps maps(scene, dir);
  const ScenarioWork w{scene,
                       target,
                       info,
                       maps,
                       dir,
                       watch,
                       "scenario " + std::to_string(s.index),
                       combinationOf(study, s)};
  ScenarioTally tally;
  tally.files[output_names::kScenarioScene] = fnv1a64Hex(scene_json);
  for (StudyLattice& r : lattices) runScenarioRegion(w, r, tally);

  nlohmann::json record = {{"study_fnv1a64", study.fnv1a64},
                           {"scenario", s.index},
                           {"parameters", scenarioParametersJson(study, s)},
                           {"regions", tally.regions}};
  if (scene.far_field.enabled) {
    const FarField far = sceneFarField(target, scene, {watch, w.what + ", far field"});
    const FarHazard far_hazard = farHazard(far, scene.hazard);
    record["far_field"] = scenarioFarFieldJson(far, far_hazard, scene.hazard);
    tally.evaluations += far.stats().evaluations;
    if (scene.wantsReach()) {
      const SceneReach reach =
          sceneReach(target, scene, far, far_hazard, {watch, w.what + ", hazard reach"});
      record["hazard_reach"] = reachSummaryJson(reach.summaries, scene.hazard);
      tally.evaluations += reach.near.evaluations();
    }
  }
  // Over an engagement the target moves through the beam: its pose at the start says nothing.
  if (!scene.engagement) {
    const std::vector<std::string> warnings =
        unlitTargetWarnings(scene, target.integrator.cullStats());
    if (!warnings.empty()) record["warnings"] = warnings;
  }
  record["evaluations"] = tally.evaluations;
  record["unconverged_points"] = tally.unconverged;
  record["seconds"] = std::chrono::duration<double>(Clock::now() - start).count();
  record[kFileChecksums] = tally.files;
  return writeScenarioResult(std::move(record), dir);
}

// A finished scenario's result.json in @p dir, when it is whole, unedited, of this study and of
// its shape. Otherwise nothing, with @p why it is redone (empty: recomputed without a word,
// --fresh's other study).
// @throw InputError when it is another study's and not @p fresh.
std::optional<nlohmann::json> readScenarioRecord(const Study& study, const Scenario& s,
                                                 std::size_t regions, const fs::path& out_dir,
                                                 const fs::path& dir, bool fresh,
                                                 std::string& why) {
  const std::string path = (dir / output_names::kScenarioResult).string();
  nlohmann::json record;
  std::string fnv;
  bool matches = false;
  try {
    record = nlohmann::json::parse(readUserFile(path, "scenario result"));
    fnv = record.at("study_fnv1a64").get<std::string>();
    matches =
        record.at("scenario").get<std::size_t>() == s.index &&
        record.at("regions").size() == regions &&
        record.contains("far_field") == study.base.far_field.enabled &&
        record.contains("hazard_reach") == study.base.wantsReach() &&
        // A result from before the scene had an optical aid lacks the aided figures.
        (!study.base.hazard.aid || record.at("regions").at(0).contains("aided_peak_hazard_ratio"));
  } catch (const std::exception&) {
    why = path + " unreadable";
    return std::nullopt;
  }
  if (fnv != study.fnv1a64) {
    if (fresh) return std::nullopt;
    throw InputError(out_dir.string() + ": holds results of another study (or of this study " +
                     "before it changed): " + path + " has study " + printable(fnv) +
                     ", this study is " + study.fnv1a64 +
                     ". Use --fresh to discard them, or another --out folder");
  }
  // Its figures as written: an edited number (or a record of a glint without checksums) is not
  // carried into the study's table and summary.
  const auto stated = record.find(kRecordChecksum);
  if (stated == record.end() || !stated->is_string()) {
    why = path + " has no checksum (written by an older glint)";
  } else if (stated->get<std::string>() != recordChecksum(record)) {
    why = path + " does not match its checksum (edited or damaged)";
  } else if (!matches) {
    why = path + " does not match";
  } else {
    return record;
  }
  return std::nullopt;
}

// Why one of the files @p record vouches for (@p names, in @p dir) is not as written, if one
// is not: a map edited, damaged or swapped for another scenario's would otherwise enter the
// aggregates while the record's figures say something else.
std::optional<std::string> unvouchedFile(const nlohmann::json& record, const fs::path& dir,
                                         const std::vector<std::string>& names) {
  const nlohmann::json* files = nullptr;
  if (const auto it = record.find(kFileChecksums); it != record.end() && it->is_object())
    files = &*it;
  for (const std::string& name : names) {
    const fs::path path = dir / name;
    std::string actual;
    try {
      actual = fileChecksum(path);
    } catch (const std::exception& e) {
      return e.what();
    }
    const bool vouched = files != nullptr && files->contains(name) && files->at(name).is_string() &&
                         files->at(name).get<std::string>() == actual;
    if (!vouched) {
      return path.string() + " does not match its checksum in " + output_names::kScenarioResult +
             " (edited, damaged or replaced)";
    }
  }
  return std::nullopt;
}

// Each region's values read back from the scenario's map of it (StudyLattice::scenarioFile()):
// a pose's irradiance, an engagement's peak irradiance and worst windows' ratios.
// @throw std::runtime_error when one cannot be read or does not fit its lattice.
std::vector<RegionValues> readScenarioMaps(const std::vector<StudyLattice>& lattices,
                                           const fs::path& dir) {
  std::vector<RegionValues> maps;
  for (const StudyLattice& r : lattices) {
    const std::string path = (dir / r.scenarioFile()).string();
    RegionValues& v = maps.emplace_back();
    const auto n = r.spec.nodes();
    auto channel = [&](const char* name) {
      if (!r.plane) return readLatticeVdb(path, name, r.spec);
      int w = 0, h = 0;
      std::vector<float> values = readExrChannel(path, name, w, h);
      if (w != n[0] || h != n[1]) throw std::runtime_error(path + ": not this plane's size");
      return values;
    };
    if (!r.engagement) {
      v.irradiance_w_m2 = channel("irradiance_w_m2");
      continue;
    }
    v.irradiance_w_m2 = channel("peak_irradiance_w_m2");
    v.hazard_ratio = channel("hazard_ratio");
    if (r.aided) v.aided_hazard_ratio = channel("aided_hazard_ratio");
  }
  return maps;
}

// A finished scenario of an earlier run: its record and maps, when they are whole, unedited and
// belong to this study, its maps added to the aggregates. Nothing when the scenario must be
// (re)computed.
std::optional<nlohmann::json> resumeScenario(const Study& study, const Scenario& s,
                                             std::vector<StudyLattice>& lattices,
                                             const fs::path& out_dir, bool fresh, std::ostream& err,
                                             bool quiet) {
  const fs::path dir = scenarioDir(out_dir, s.index);
  std::string why;
  auto redo = [&]() -> std::optional<nlohmann::json> {
    if (!quiet && !why.empty())
      err << "glint batch: scenario " << s.index << " redone: " << why << "\n";
    return std::nullopt;
  };
  std::error_code ec;
  if (!fs::is_regular_file(dir / output_names::kScenarioResult, ec)) return std::nullopt;
  std::optional<nlohmann::json> record =
      readScenarioRecord(study, s, lattices.size(), out_dir, dir, fresh, why);
  if (!record) return redo();
  std::vector<std::string> names = {output_names::kScenarioScene};
  for (const std::string& map : ScenarioMaps(study.base, dir).names()) names.push_back(map);
  if (auto unvouched = unvouchedFile(*record, dir, names)) {
    why = std::move(*unvouched);
    return redo();
  }
  // Maps read in full before any is added, so a damaged file leaves the aggregates untouched.
  std::vector<RegionValues> maps;
  try {
    maps = readScenarioMaps(lattices, dir);
  } catch (const std::exception& e) {
    why = e.what();
    return redo();
  }
  for (std::size_t i = 0; i < lattices.size(); ++i)
    lattices[i].add(maps[i], study.base.hazard, combinationOf(study, s));
  return record;
}

// Refuses a study whose maps, one scenario's field and target exceed the budget, before any of
// them is allocated.
void checkStudyMemory(const Study& study, const std::vector<StudyLattice>& lattices,
                      std::uint64_t budget) {
  // Each region keeps its dense maps over the scenarios besides one scenario's field at a time,
  // and the writer of one of its maps.
  std::uint64_t floor_bytes = 0;
  for (const StudyLattice& r : lattices) {
    const OutputRegion region =
        r.plane ? (r.engagement ? OutputRegion::EngagementPlane : OutputRegion::Plane)
                : (r.engagement ? OutputRegion::EngagementBox : OutputRegion::Box);
    // An engagement's maps are arrays over the whole lattice, as the dense twin's grids are.
    floor_bytes += r.mapBytes() + fieldMemoryFloorBytes(r.spec, r.engagement) +
                   writerScratch(study.base, region, &r.spec, r.name, true).bytes;
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
      {budget, floor_bytes + far_bytes + terrainMemoryBytes(study.base),
       std::string("the study's regions and far field") +
           (study.base.terrain ? " and " + terrainMemoryWhat(study.base) : "")});
}

// What the study's scenarios come to on rank 0 (besides the aggregates, in the lattices).
struct StudyResults {
  std::map<std::size_t, nlohmann::json> records;  // every scenario's result
  std::vector<std::size_t> todo;                  // the scenarios this run computes
  std::size_t resumed = 0;
};

// Readies the study's folder on rank 0: --fresh's clearing, scenarios/.
void prepareStudyFolder(const BatchArgs& args, OutputFolder& out,
                        const std::vector<std::string>& own_files, std::ostream& err) {
  const fs::path scenarios = out.path() / output_names::kScenariosFolder;
  if (args.fresh) {
    const std::vector<fs::path> kept = removeScenarioFolders(scenarios, own_files);
    if (!args.quiet && !kept.empty()) {
      err << "glint batch: --fresh kept " << kept.size() << " file(s) or folder(s) glint did "
          << "not write (and the scenario folders holding them): " << listed(kept) << "\n";
    }
  }
  out.create(scenarios);
}

// Takes up the scenarios [begin, end) finished before (rank 0), into @p results; the others
// become its todo.
void resumeRound(const BatchArgs& args, const Study& study, std::vector<StudyLattice>& lattices,
                 const fs::path& out_dir, std::size_t begin, std::size_t end, StudyResults& results,
                 std::ostream& err) {
  results.todo.clear();
  for (std::size_t i = begin; i < end; ++i) {
    const Scenario& s = study.scenarios[i];
    if (auto rec = resumeScenario(study, s, lattices, out_dir, args.fresh, err, args.quiet)) {
      results.records[s.index] = std::move(*rec);
      ++results.resumed;
    } else {
      results.todo.push_back(s.index);
    }
  }
}

// The line that says the batch has begun (after its first round's scenarios are taken up).
void printStart(std::ostream& err, const Study& study, const StudyResults& results,
                const fs::path& out_dir, int ranks) {
  err << "glint batch: ";
  if (study.precision_half_width) {
    err << "up to " << study.scenarios.size() << " scenarios (jitter samples from "
        << study.first_round_samples << ", doubling until every point's interval is within ±"
        << formatNumber("%g", *study.precision_half_width) << ")";
  } else {
    err << study.scenarios.size() << " scenarios";
  }
  err << " of " << study.source;
  if (results.resumed > 0)
    err << " (" << results.resumed << " done before, " << results.todo.size() << " to run)";
  err << " on " << ranks << (ranks == 1 ? " process" : " MPI ranks") << "; scenario folders in "
      << (out_dir / output_names::kScenariosFolder).string() << "\n";
}

// The progress of the scenarios this run computes, on rank 0: a line at least every 10 s
// (redrawn in place on a terminal), and the last.
class BatchProgress {
 public:
  BatchProgress(std::ostream& err, bool terminal, std::size_t todo)
      : err_(err), terminal_(terminal), todo_(todo), start_(Clock::now()), last_print_(start_) {}

  // Scenario @p index is done, with @p record.
  void done(std::size_t index, const nlohmann::json& record) {
    ++finished_;
    const auto now = Clock::now();
    const bool last = finished_ == todo_;
    if (!terminal_ && !last && now - last_print_ < std::chrono::seconds(10)) return;
    last_print_ = now;
    const double elapsed = std::chrono::duration<double>(now - start_).count();
    const double left =
        elapsed / static_cast<double>(finished_) * static_cast<double>(todo_ - finished_);
    double peak = 0.0;
    for (const auto& r : record.at("regions"))
      peak = std::max(peak, r.at("peak_hazard_ratio").get<double>());
    std::string line = "batch: " + std::to_string(finished_) + "/" + std::to_string(todo_) +
                       " scenarios, " + formatDuration(elapsed) +
                       (last ? "" : ", about " + formatDuration(left) + " left") + "; scenario " +
                       std::to_string(index) + ": peak hazard ratio " + formatNumber("%.3g", peak);
    if (terminal_) {
      err_ << "\r\033[K" << line << (last ? "\n" : "") << std::flush;
    } else {
      err_ << line << "\n";
    }
  }

 private:
  std::ostream& err_;
  bool terminal_;
  std::size_t todo_;
  std::size_t finished_ = 0;
  Clock::time_point start_;
  Clock::time_point last_print_;
};

// Computes the scenarios rank 0 hands out, on every rank; rank 0 gathers their records into
// @p results. Then every rank's aggregates are reduced into rank 0's.
void runScenarios(const BatchArgs& args, const Study& study, std::vector<StudyLattice>& lattices,
                  const fs::path& out_dir, const MemoryWatch& watch, Cluster& cluster,
                  StudyResults& results, bool talk, std::ostream& err) {
  BatchProgress progress(err, args.terminal, results.todo.size());
  cluster.shareOut(
      results.todo,
      [&](std::size_t index) {
        return runScenario(study, study.scenarios[index], lattices, out_dir, watch);
      },
      [&](std::size_t index, const std::string& record) {
        results.records[index] = nlohmann::json::parse(record);
        if (talk) progress.done(index, results.records[index]);
      });
  for (StudyLattice& r : lattices) {
    cluster.maxToRoot(r.max_w_m2);
    cluster.sumToRoot(r.hazardous);
    if (r.aided) cluster.sumToRoot(r.aided_hazardous);
    if (r.engagement) {
      cluster.maxToRoot(r.max_ratio);
      if (r.aided) cluster.maxToRoot(r.aided_max_ratio);
    }
    if (r.combinations > 1) {
      cluster.sumToRoot(r.hazardous_by_combination);
      if (r.aided) cluster.sumToRoot(r.aided_hazardous_by_combination);
    }
    for (std::size_t k = 0; k < r.level_reached.size(); ++k) {
      cluster.sumToRoot(r.level_reached[k]);
      if (r.combinations > 1) cluster.sumToRoot(r.level_reached_by_combination[k]);
    }
    // Rank 0 holds them all now: the others start the next round from nothing, or they would
    // add their share again.
    if (cluster.rank() != 0) r.allocate();
  }
}

// Whether the study may stop after @p scenarios: every round's the same on every rank, rank 0's
// word (it alone holds the aggregates) sent to all.
bool studyMayStop(const Study& study, const std::vector<StudyLattice>& lattices,
                  std::size_t scenarios, Cluster& cluster, bool talk, std::ostream& err) {
  std::vector<std::byte> word;
  if (cluster.rank() == 0) {
    const double widest = widestCoverageHalfWidth(lattices, scenarios, study.coverage_confidence);
    const bool reached = widest <= *study.precision_half_width;
    if (talk) {
      err << "glint batch: " << scenarios / study.scenarios_per_sample
          << " jitter samples: the widest interval is ±" << formatNumber("%.3g", widest)
          << (reached ? ", within" : ", beyond") << " the ±"
          << formatNumber("%g", *study.precision_half_width) << " asked"
          << (reached ? "" : "; more samples") << "\n";
    }
    word.push_back(std::byte{reached ? std::uint8_t{1} : std::uint8_t{0}});
  }
  const std::vector<std::vector<std::byte>> all = cluster.allGather(word);
  return !all.empty() && !all[0].empty() && all[0][0] == std::byte{1};
}

// The study's own files (rank 0): scenarios.csv, each region's aggregated map and summary.json
// (with the run's time until then), all in place together, summary.json last, or none; then its
// summary on the terminal unless quiet.
void writeStudy(const BatchArgs& args, const Study& study,
                const std::vector<StudyLattice>& lattices, const StudyResults& results,
                const fs::path& out_dir, int ranks, PhaseClock& clock, std::ostream& err) {
  PhaseClock::Scope writing = clock.phase("writing the study's files");
  OutputSet outputs;
  outputs.open(out_dir / output_names::kScenariosCsv).write([&](std::ostream& out) {
    out << scenariosCsv(lattices, results.records, study.base.far_field.enabled,
                        study.base.wantsReach(), study.base.hazard.aid.has_value());
  });
  for (const StudyLattice& r : lattices)
    writeStudyMap(outputs, out_dir / r.studyFile(), r, study, results.records.size());
  writing.stop();
  const nlohmann::json timing = timingJson(clock);
  const double wall_s = timing.at("wall_seconds").get<double>();
  nlohmann::json summary =
      batchSummaryJson(study, lattices, results.records, results.resumed, ranks, wall_s);
  summary["timing"] = timing;
  outputs.open(out_dir / output_names::kSummary, true).write([&](std::ostream& out) {
    out << summary.dump(2) << "\n";
  });
  outputs.commit([&] { pauseForTestsAfterFirstOutput(err); });
  if (!args.quiet) {
    printBatchSummary(err, summary, lattices, out_dir, wall_s);
  } else {
    // Even when quiet: empty maps that are not safe ones must not pass unremarked.
    for (const nlohmann::json& w : summary.at("warnings"))
      err << "glint batch: warning: " << w.get<std::string>() << "\n";
  }
}

}  // namespace

void runBatch(const BatchArgs& args, Cluster& cluster, std::ostream& err) {
  PhaseClock clock;  // summary.json's `timing`
  PhaseClock::Scope reading = clock.phase("reading the study and checking its memory");
  const bool root = cluster.rank() == 0;
  const bool talk = root && !args.quiet;
  const std::uint64_t budget =
      args.memory_bytes > 0 ? args.memory_bytes : defaultMemoryBudgetBytes();
  const Study study = loadStudy(args.study_path, budget);
  fs::path out_dir = args.out_dir;
  if (out_dir.empty()) out_dir = fs::path("out") / fs::path(args.study_path).stem();

  std::unique_ptr<tbb::global_control> thread_limit;
  if (args.threads > 0) {
    thread_limit = std::make_unique<tbb::global_control>(
        tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(args.threads));
  }

  std::vector<StudyLattice> lattices = studyLattices(study.base);
  for (StudyLattice& r : lattices) r.combinations = jitterSharingCombinations(study);
  checkStudyMemory(study, lattices, budget);
  for (StudyLattice& r : lattices) r.allocate();
  reading.stop();
  MemoryWatch watch(budget);
  noteTerrain(watch, study.base);
  // Rank 0 holds the folder for the whole run (the other ranks write only the scenarios it hands
  // them), and on failure takes away the folders the run made, if nothing in them is worth
  // resuming from.
  const std::vector<std::string> own_files = ScenarioMaps::folderNames(study.base);
  std::optional<OutputFolder> out;
  StudyResults results;
  if (root) {
    InputFiles inputs;
    inputs.add(args.study_path, "study file");
    inputs.addScene(study.scene_path, study.base);
    out.emplace(out_dir, inputs, "glint batch",
                [&](const OutputFolder& f) { removeFailedRun(f, own_files); });
    prepareStudyFolder(args, *out, own_files, err);
  }
  // One round, or with a precision rounds of doubling jitter samples until it is reached.
  const std::vector<std::size_t> rounds = studyRounds(study);
  std::size_t begin = 0;
  for (std::size_t round = 0; round < rounds.size(); ++round) {
    if (root) {
      const PhaseClock::Scope resuming = clock.phase("reading the scenarios already done");
      resumeRound(args, study, lattices, out_dir, begin, rounds[round], results, err);
      if (talk && round == 0) printStart(err, study, results, out_dir, cluster.size());
    }
    {
      const PhaseClock::Scope scenarios = clock.phase("the scenarios");
      runScenarios(args, study, lattices, out_dir, watch, cluster, results, talk, err);
    }
    begin = rounds[round];
    if (round + 1 < rounds.size() && studyMayStop(study, lattices, begin, cluster, talk, err))
      break;
  }
  if (!root) return;
  writeStudy(args, study, lattices, results, out_dir, cluster.size(), clock, err);
}

}  // namespace glint
