#include "pipeline/run_command.h"

#include <tbb/global_control.h>
#include <tbb/info.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>

#include "export/atomic_file.h"
#include "export/exr_map.h"
#include "export/field_files.h"
#include "export/vtk_files.h"
#include "glint/version.h"
#include "pipeline/input_error.h"
#include "pipeline/input_files.h"
#include "pipeline/json_reader.h"
#include "pipeline/memory_budget.h"
#include "pipeline/output_folder.h"
#include "pipeline/output_names.h"
#include "pipeline/progress.h"
#include "pipeline/run_folder.h"
#include "pipeline/run_report.h"
#include "pipeline/scene.h"
#include "pipeline/surface_check.h"
#include "pipeline/target_builder.h"
#include "pipeline/test_pause.h"

namespace glint {
namespace {

// The largest power-of-two stride that keeps the .vti resample under 16.7 M points.
int vtiStride(const FieldSpec& spec) {
  const auto n = spec.nodes();
  int stride = 1;
  auto points = [&](int s) {
    double p = 1.0;
    for (int a = 0; a < 3; ++a) p *= (n[a] - 1) / s + 1;
    return p;
  };
  while (points(stride) > 16.7e6 && stride < spec.block_voxels) stride *= 2;
  return stride;
}

// The centre of the target's bounding box: the nominal hazard zone's reach is measured from it.
Vec3 targetCentre(const Target& target) {
  Vec3 lo(std::numeric_limits<double>::infinity()), hi(-lo);
  for (std::size_t f = 0; f < target.facetCount(); ++f) {
    const Vec3 origin = target.objects[target.object[f]].origin_m;
    for (const Vec3& c : target.corners_m[f]) {
      lo = glm::min(lo, origin + c);
      hi = glm::max(hi, origin + c);
    }
  }
  return target.facetCount() > 0 ? 0.5 * (lo + hi) : Vec3(0.0);
}

// Computes one observer field (the box or a plane) with its own integrator settings, with
// progress on stderr unless quiet.
struct FieldResult {
  FieldProblem problem;
  std::unique_ptr<ObserverField> field;
};

FieldResult computeObserverField(const SceneTarget& target, const Scene& scene,
                                 const FieldSpec& spec, const RunArgs& args, const char* what,
                                 const MemoryWatch& watch, std::ostream& err,
                                 PointExchange* exchange) {
  FieldResult r{fieldProblem(target, scene, spec), nullptr};
  WorkCounter counter;
  counter.stop = &watch.stopFlag();
  std::unique_ptr<ProgressReporter> progress;
  if (!args.quiet)
    progress = std::make_unique<ProgressReporter>(err, args.terminal, what, 0, counter);
  try {
    r.field = std::make_unique<ObserverField>(
        args.uniform
            ? computeDenseField(r.problem.integrator, spec, r.problem.excluded, &counter)
            : computeField(r.problem.integrator, spec, r.problem.excluded, &counter, exchange));
  } catch (const WorkStopped&) {
    if (progress) progress->stop();
    watch.check(spec.plane ? std::string("plane ") + what : std::string("the observer box"));
    throw;
  }
  return r;
}

// Refuses a region whose memory floor exceeds the budget before any of it is allocated, and
// tells the user at once what the run is about to do. Returns the floor.
std::uint64_t checkRegionMemory(const FieldSpec& spec, const std::string& what, const RunArgs& args,
                                std::uint64_t budget_bytes, std::ostream& err) {
  const std::array<int, 3> n = spec.nodes();
  const std::string lattice = std::to_string(n[0]) + "×" + std::to_string(n[1]) +
                              (spec.plane ? "" : "×" + std::to_string(n[2]));
  const std::uint64_t floor_bytes = fieldMemoryFloorBytes(spec, args.uniform);
  requireWithinBudget(what + " (" + lattice + " lattice points at " +
                          formatNumber("%g", spec.voxel_m) + " m" +
                          (args.uniform ? ", dense" : "") + ")",
                      floor_bytes, budget_bytes,
                      "coarsen voxel_m or pixel_m, enlarge block_m, shrink the region, or raise "
                      "--memory");
  if (!args.quiet) {
    err << "glint run: " << what << ", " << lattice << " lattice points at "
        << formatNumber("%g", spec.voxel_m) << " m; memory: at least "
        << formatBytes(static_cast<double>(floor_bytes)) << " of the "
        << formatBytes(static_cast<double>(budget_bytes)) << " budget\n";
  }
  return floor_bytes;
}

// The lat-long map glint run writes of the far field: about as fine as the faces' centres.
int latLongHeight(const FarFieldSpec& spec) { return std::min(spec.face_pixels, 2048); }

// The far field's faces (farFieldMemoryFloorBytes()), refused before any is computed.
std::string farFieldWhat(const FarFieldSpec& spec) {
  return "the far field (6 × " + std::to_string(spec.face_pixels + 1) + "² directions)";
}

}  // namespace

FarField sceneFarField(const SceneTarget& target, const Scene& scene, const MemoryWatch& watch,
                       const std::string& what, std::ostream* progress_to, bool terminal,
                       PointExchange* exchange) {
  const FarFieldSpec spec = farFieldSpec(scene, target.integrator);
  requireWithinBudget(farFieldWhat(spec), farFieldMemoryFloorBytes(spec), watch.budgetBytes(),
                      "lower far_field.face_pixels, or raise --memory");

  WorkCounter counter;
  counter.stop = &watch.stopFlag();
  std::unique_ptr<ProgressReporter> progress;
  if (progress_to != nullptr) {
    progress = std::make_unique<ProgressReporter>(*progress_to, terminal, "directions", 0, counter);
  }
  FarField far = [&] {
    try {
      return computeFarField(target.integrator, spec, &counter, exchange);
    } catch (const WorkStopped&) {
      if (progress) progress->stop();
      watch.check(what);
      throw;
    }
  }();
  if (far.stats().non_finite_points > 0) {
    throw std::runtime_error("the far field: " + std::to_string(far.stats().non_finite_points) +
                             " directions have a non-finite intensity; nothing was written");
  }
  // A narrow glint's block a thousand far radii out never reaches the target: an unbounded
  // one is a fault, not a bound to report.
  if (!std::isfinite(far.peak().intensity_w_sr)) {
    throw std::runtime_error(
        "the far field: the peak intensity is not a finite number; nothing was written");
  }
  return far;
}

void requireFinite(const ObserverField& field, const std::string& region) {
  const FieldStats& s = field.stats();
  if (s.non_finite_points > 0) {
    const Vec3& x = s.non_finite_at_m;
    throw std::runtime_error(region + ": " + std::to_string(s.non_finite_points) +
                             " points have a non-finite irradiance, one at (" +
                             formatNumber("%g", x.x) + ", " + formatNumber("%g", x.y) + ", " +
                             formatNumber("%g", x.z) + "); nothing was written");
  }
  if (!std::isfinite(s.peak_w_m2) || !(s.peak_w_m2 >= 0.0) ||
      std::isnan(s.unconverged_max_upper_w_m2)) {
    throw std::runtime_error(region +
                             ": the peak irradiance is not a finite number; nothing "
                             "was written");
  }
}

RunInfo runInfo(const Scene& scene, const std::string& scene_file, std::string_view scene_text,
                const std::string& scheme) {
  RunInfo info;
  info.program_version = std::string("glint ") + GLINT_VERSION;
  info.scene_file = scene_file;
  info.scene_fnv1a64 = fnv1a64Hex(scene_text);
  info.scheme = scheme;
  info.integration_scheme =
      integrationSchemeNames()[static_cast<std::size_t>(scene.accuracy.scheme)];
  info.wavelength_nm = scene.laser.wavelength_nm;
  info.power_w = scene.laser.power_w;
  info.exposure_s = scene.hazard.exposure_s;
  info.mpe_w_m2 = scene.hazard.mpe_w_m2;
  info.mpe_rule = hazardCitation(scene.hazard);
  info.optical_aid_gain = scene.hazard.aid ? scene.hazard.aid->gain : 0.0;
  info.scaled = hazardArrays(scene.hazard);
  return info;
}

void runField(const RunArgs& requested, std::ostream& err, PointExchange* exchange) {
  // Under MPI every rank computes the same field, sharing the points; rank 0 alone reports
  // and writes.
  const bool writer = exchange == nullptr || exchange->rank() == 0;
  RunArgs args = requested;
  if (!writer) args.quiet = true;
  const std::uint64_t budget =
      args.memory_bytes > 0 ? args.memory_bytes : defaultMemoryBudgetBytes();
  // A mesh is refused before it is decoded, the target before it is built.
  Scene scene = loadScene(args.scene_path, budget);
  overrideAccuracy(scene.accuracy, std::nullopt, args.scheme, scene.source);
  if (!scene.observers && scene.planes.empty()) {
    throw InputError(scene.source +
                     ": /observers: missing (glint run needs an observer box or `planes`)");
  }
  std::filesystem::path dir = args.out_dir;
  if (dir.empty()) {
    dir = std::filesystem::path("out") / (std::filesystem::path(args.scene_path).stem().string() +
                                          (args.uniform ? "_uniform" : ""));
  }
  InputFiles inputs;
  inputs.addScene(args.scene_path, scene);
  // Rank 0 holds the folder while it runs, so that another run's files and this one's never
  // mix; declared before the outputs, whose temporaries go first when the run fails.
  std::optional<OutputFolder> folder;
  EarlierRun earlier;
  if (writer) {
    folder.emplace(dir, inputs, "glint run");
    earlier = earlierRun(dir);
    requireSameScene(dir, earlier, args.scene_path);
  }
  // Opened before the work, so an unwritable folder stops the run at once (rank 0 only; the
  // other ranks' pointers stay null and they write nothing).
  std::vector<std::unique_ptr<AtomicFile>> files;
  std::vector<std::string> written;
  auto open = [&](const std::string& name) -> AtomicFile* {
    written.push_back(name);
    if (!writer) return nullptr;
    inputs.requireNotAnInput(dir / name);  // a hard link to an input, named otherwise
    files.push_back(std::make_unique<AtomicFile>(dir / name));
    return files.back().get();
  };
  AtomicFile* summary = open(output_names::kSummary);
  AtomicFile *vdb = nullptr, *vti = nullptr, *vtu = nullptr, *vtp = nullptr;
  if (scene.observers) {
    vdb = open(output_names::kIrradianceVdb);
    vti = open(output_names::kIrradianceVti);
    vtu = open(output_names::kBlocksVtu);
    vtp = open(output_names::kTargetVtp);
  }
  std::optional<StagedAmr> amr;  // irradiance.vthb and its folder, committed with the files
  if (scene.observers) written.push_back(output_names::kIrradianceAmr);
  AtomicFile *far_exr = nullptr, *far_vtp = nullptr, *far_aided_vtp = nullptr;
  std::vector<std::string> far_files;  // as summary.json lists them
  auto openFar = [&](const char* name) {
    far_files.emplace_back(name);
    return open(name);
  };
  if (scene.far_field.enabled) {
    far_exr = openFar(output_names::kFarFieldExr);
    far_vtp = openFar(output_names::kFarFieldVtp);
    if (scene.hazard.aid) far_aided_vtp = openFar(output_names::kFarFieldAidedVtp);
  }
  std::vector<AtomicFile*> exrs;
  for (const PlaneSpec& plane : scene.planes)
    exrs.push_back(open(output_names::planeExr(plane.name)));
  // An earlier run of this scene may have written files this one will not (a plane since
  // renamed): said, so that no stale map passes for a new one.
  const std::vector<std::string> stale = staleOutputs(dir, earlier, written);
  if (!stale.empty() && !args.quiet) {
    std::string list;
    for (const std::string& name : stale) list += (list.empty() ? "" : ", ") + name;
    err << "glint run: note: " << dir.string() << " keeps " << list
        << " from an earlier run of this scene, which this run does not rewrite\n";
  }
  if (writer) pauseForTestsAfterTemporaries(err);

  std::unique_ptr<tbb::global_control> thread_limit;
  if (args.threads > 0) {
    thread_limit = std::make_unique<tbb::global_control>(
        tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(args.threads));
  }

  const RunInfo info = runInfo(scene, args.scene_path, readUserFile(args.scene_path, "scene file"),
                               args.uniform ? "uniform" : "adaptive");

  // Every large allocation reckoned before the first is made: one region's field at a time
  // (the box's is gone before the planes'), the far field kept throughout, and the target.
  std::uint64_t region_bytes = 0;
  if (scene.observers) {
    region_bytes = checkRegionMemory(fieldSpec(scene), "observer box", args, budget, err);
  }
  for (const PlaneSpec& plane : scene.planes) {
    region_bytes = std::max(
        region_bytes,
        checkRegionMemory(planeFieldSpec(scene, plane), "plane " + plane.name, args, budget, err));
  }
  std::uint64_t far_bytes = 0;
  if (scene.far_field.enabled) {
    const FarFieldSpec lattice = farFieldLattice(scene);
    far_bytes = farFieldMemoryFloorBytes(lattice, writer ? latLongHeight(lattice) : 0);
    requireWithinBudget(farFieldWhat(lattice), far_bytes, budget,
                        "lower far_field.face_pixels, or raise --memory");
    if (!args.quiet) {
      err << "glint run: " << farFieldWhat(lattice) << "; memory: at least "
          << formatBytes(static_cast<double>(far_bytes)) << " of the "
          << formatBytes(static_cast<double>(budget)) << " budget\n";
    }
  }
  const FieldSpec first =
      scene.observers ? fieldSpec(scene) : planeFieldSpec(scene, scene.planes.front());
  const TargetMemory target_memory = targetMemory(scene, fieldIntegratorOptions(scene, first));
  const TargetBudget target_budget{
      budget, far_bytes + region_bytes,
      far_bytes > 0 ? "the far field and the largest region" : "the largest region"};
  requireTargetWithinBudget(target_memory, target_budget);
  if (!args.quiet) {
    err << "glint run: target, " << target_memory.facets << " coarse facets; memory: at least "
        << formatBytes(static_cast<double>(target_memory.floor_bytes)) << " of the "
        << formatBytes(static_cast<double>(budget)) << " budget\n";
  }
  const MemoryWatch watch(budget);

  // Built and culled once, shared by the box and the planes.
  const SceneTarget target = sceneTarget(scene, first, target_budget);
  watch.check("building the target",
              "Raise --memory, or lower the objects' segments, or decimate the meshes");
  std::optional<FarField> far;
  FarHazard far_hazard;
  if (scene.far_field.enabled) {
    far.emplace(sceneFarField(target, scene, watch, "the far field", args.quiet ? nullptr : &err,
                              args.terminal, exchange));
    far_hazard = farHazard(*far, scene.hazard);
  }
  nlohmann::json j;
  // The brightest observer of each region, where the meshes' surface model is checked.
  std::vector<std::pair<std::string, Vec3>> probes;
  // The target as the first lattice's problem describes it (all share the same one).
  const bool has_meshes = scene.hasMeshes();
  auto describeTarget = [&](const FieldProblem& problem) {
    if (!j.contains("target")) j["target"] = targetJson(problem.integrator.cullStats());
    if (has_meshes && !j.contains("meshes")) j["meshes"] = meshesJson(scene, problem.mesh_stats);
  };
  if (scene.observers) {
    const FieldSpec spec = fieldSpec(scene);
    FieldResult box =
        computeObserverField(target, scene, spec, args, "points", watch, err, exchange);
    const ObserverField& field = *box.field;
    requireFinite(field, "the observer box");
    const FacetIntegrator& integrator = box.problem.integrator;
    if (writer) {
      writeVti(vti->stream(), field, vtiStride(spec), info.scaled);
      writeBlocksVtu(vtu->stream(), field, info.scaled);
      writeTargetVtp(vtp->stream(), integrator, 2);
      amr.emplace(writeAmr(dir / output_names::kIrradianceAmr, field, info.scaled));
    }
    const HazardZone zone = hazardZone(field, scene.hazard, targetCentre(integrator.target()));
    if (field.stats().peak_w_m2 > 0.0)
      probes.emplace_back("the box's peak", field.stats().peak_at_m);
    j = volumeSummaryJson(field, zone, info, integrator.cullStats());
    describeTarget(box.problem);
    j["hazard"] = hazardJson(scene.hazard, &zone);
    if (!args.quiet) {
      std::string beyond_box;
      if (far) {
        beyond_box =
            "; beyond " + formatNumber("%.4g", far->spec().far_radius_m) +
            " m the far field bounds it: " +
            (far_hazard.farthest().nohd_m > 0.0
                 ? "it reaches " + formatNumber("%.4g", far_hazard.farthest().nohd_m) + " m"
                 : std::string("no direction is hazardous there"));
      }
      printVolume(err, field, scene, zone, info, args.uniform, beyond_box);
    }
    // Last: it consumes the field.
    if (writer) writeVdb(vdb->stream(), std::move(*box.field), info);
  } else {
    j = runJson(info);
    j["hazard"] = hazardJson(scene.hazard, nullptr);
  }

  if (!scene.planes.empty()) {
    nlohmann::json planes = nlohmann::json::array();
    for (std::size_t p = 0; p < scene.planes.size(); ++p) {
      const PlaneSpec& plane = scene.planes[p];
      const FieldSpec spec = planeFieldSpec(scene, plane);
      const FieldResult r =
          computeObserverField(target, scene, spec, args, plane.name.c_str(), watch, err, exchange);
      const ObserverField& field = *r.field;
      requireFinite(field, "plane " + plane.name);
      if (writer) {
        writeExr(exrs[p]->stream(), planeMap(field, scene.hazard),
                 {info.program_version, info.wavelength_nm, info.mpe_w_m2});
      }
      const HazardZone zone =
          hazardZone(field, scene.hazard, targetCentre(r.problem.integrator.target()));
      planes.push_back(planeJson(plane, field, zone));
      if (field.stats().peak_w_m2 > 0.0) {
        probes.emplace_back("plane " + plane.name + "'s peak", field.stats().peak_at_m);
      }
      describeTarget(r.problem);
      if (!args.quiet) printPlane(err, plane, field, zone);
    }
    j["planes"] = planes;
  }
  if (far && writer) {
    const double mpe = info.mpe_w_m2;
    const double mu = scene.hazard.atmosphere.extinction_per_m;
    // 2:1 lat-long, about as fine as the cube faces' centres, at most 4096 × 2048 pixels.
    const int height = std::min(far->spec().face_pixels, 2048);
    const LatLongMap map =
        latLongMap(*far, height, mpe, mu, scene.hazard.aid ? scene.hazard.aidedMpeW_m2() : 0.0);
    std::vector<ExrChannel> channels = {{"intensity_w_sr", &map.intensity_w_sr},
                                        {"nohd_m", &map.nohd_m}};
    if (scene.hazard.aid) channels.push_back({"aided_nohd_m", &map.aided_nohd_m});
    writeLatLongExr(far_exr->stream(),
                    {map.width, map.height, far->ball().centre_m, far->spec().far_radius_m},
                    channels, {info.program_version, info.wavelength_nm, mpe});
    const int surface_pixels = std::min(far->spec().face_pixels, 128);
    writeHazardSurfaceVtp(far_vtp->stream(), hazardSurface(*far, surface_pixels, mpe, mu));
    if (far_aided_vtp != nullptr) {
      writeHazardSurfaceVtp(far_aided_vtp->stream(),
                            hazardSurface(*far, surface_pixels, scene.hazard.aidedMpeW_m2(), mu));
    }
    j["far_field"] = farFieldJson(*far, far_hazard, far_files);
    if (!args.quiet) printFarField(err, *far, far_hazard);
  }
  if (has_meshes && writer) {
    if (far && far->peak().intensity_w_sr > 0.0) {
      probes.emplace_back("the far field's peak",
                          far->ball().centre_m + far->mapDistance() * far->peak().direction);
    }
    const SurfaceModelCheck check = checkSurfaceModel(scene, target.integrator, probes);
    j["surface_check"] = surfaceCheckJson(scene, check);
    if (!args.quiet) printSurfaceCheck(err, scene, check);
  }
  if (!writer) return;
  j["scene_path"] = sceneIdentity(args.scene_path);
  j["files"] = written;
  if (!stale.empty()) j["earlier_files_kept"] = stale;
  summary->stream() << j.dump(2) << "\n";
  watch.check("writing the outputs");  // a file written short of memory is not committed
  for (const auto& f : files) f->commit();
  if (amr) amr->commit();
  if (args.quiet) return;
  std::string list;
  for (const std::string& w : written) list += (list.empty() ? "" : ", ") + w;
  err << "  wrote " << dir.string() << "/{" << list << "}\n";
}

}  // namespace glint
