#include "pipeline/run_command.h"

#include <tbb/global_control.h>
#include <tbb/info.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>

#include "export/field_files.h"
#include "export/geo_files.h"
#include "export/lattice_vdb.h"
#include "glint/version.h"
#include "observers/exposure.h"
#include "pipeline/engagement_report.h"
#include "pipeline/input_error.h"
#include "pipeline/input_files.h"
#include "pipeline/json_reader.h"
#include "pipeline/memory_budget.h"
#include "pipeline/output_folder.h"
#include "pipeline/output_names.h"
#include "pipeline/progress.h"
#include "pipeline/run_folder.h"
#include "pipeline/run_outputs.h"
#include "pipeline/run_report.h"
#include "pipeline/scene.h"
#include "pipeline/surface_check.h"
#include "pipeline/target_builder.h"
#include "pipeline/test_pause.h"
#include "pipeline/unlit_warning.h"

namespace glint {
namespace {

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
                                bool dense, std::uint64_t budget_bytes, std::ostream& err) {
  const std::array<int, 3> n = spec.nodes();
  const std::string lattice = std::to_string(n[0]) + "×" + std::to_string(n[1]) +
                              (spec.plane ? "" : "×" + std::to_string(n[2]));
  const std::uint64_t floor_bytes = fieldMemoryFloorBytes(spec, dense);
  requireWithinBudget(what + " (" + lattice + " lattice points at " +
                          formatNumber("%g", spec.voxel_m) + " m" + (dense ? ", dense" : "") + ")",
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

// The far field's faces (farFieldMemoryFloorBytes()), refused before any is computed.
std::string farFieldWhat(const FarFieldSpec& spec) {
  return "the far field (6 × " + std::to_string(spec.face_pixels + 1) + "² directions)";
}

// The region whose accuracy the shared target is built for: the box, else the first plane,
// else the reach's lattices.
FieldSpec firstRegion(const Scene& scene) {
  if (scene.observers) return fieldSpec(scene);
  if (!scene.planes.empty()) return planeFieldSpec(scene, scene.planes.front());
  return reachAccuracy(scene);
}

// Every large allocation of a run reckoned before the first is made: one region's field at a
// time (the box's is gone before the planes'), the far field kept throughout, and the target.
// Returns what the target is checked against once its facets are made.
TargetBudget checkRunMemory(const Scene& scene, const RunArgs& args, std::uint64_t budget,
                            bool writer, std::ostream& err) {
  // An engagement's maps are arrays over the whole lattice, as the dense twin's grids are.
  const bool dense = args.uniform || scene.engagement.has_value();
  std::uint64_t region_bytes = 0;
  if (scene.observers) {
    region_bytes = checkRegionMemory(fieldSpec(scene), "observer box", args, dense, budget, err);
  }
  for (const PlaneSpec& plane : scene.planes) {
    region_bytes =
        std::max(region_bytes, checkRegionMemory(planeFieldSpec(scene, plane),
                                                 "plane " + plane.name, args, dense, budget, err));
  }
  std::uint64_t far_bytes = 0;
  if (scene.far_field.enabled) {
    const FarFieldSpec lattice = farFieldLattice(scene);
    far_bytes = farFieldMemoryFloorBytes(lattice, writer ? farMapHeight(lattice.face_pixels) : 0);
    requireWithinBudget(farFieldWhat(lattice), far_bytes, budget,
                        "lower far_field.face_pixels, or raise --memory");
    if (!args.quiet) {
      err << "glint run: " << farFieldWhat(lattice) << "; memory: at least "
          << formatBytes(static_cast<double>(far_bytes)) << " of the "
          << formatBytes(static_cast<double>(budget)) << " budget\n";
    }
  }
  // The terrain was read with the scene and is held throughout.
  const std::uint64_t terrain_bytes = terrainMemoryBytes(scene);
  if (scene.terrain && !args.quiet) {
    err << "glint run: " << terrainMemoryWhat(scene) << "; memory: at least "
        << formatBytes(static_cast<double>(terrain_bytes)) << " of the "
        << formatBytes(static_cast<double>(budget)) << " budget\n";
  }
  const TargetMemory target_memory =
      targetMemory(scene, fieldIntegratorOptions(scene, firstRegion(scene)));
  const TargetBudget target_budget{
      budget, far_bytes + region_bytes + terrain_bytes,
      std::string(scene.terrain ? "the terrain, " : "") +
          (far_bytes > 0 ? "the far field and the largest region" : "the largest region")};
  requireTargetWithinBudget(target_memory, target_budget);
  if (!args.quiet) {
    err << "glint run: target, " << target_memory.facets << " coarse facets; memory: at least "
        << formatBytes(static_cast<double>(target_memory.floor_bytes)) << " of the "
        << formatBytes(static_cast<double>(budget)) << " budget\n";
  }
  return target_budget;
}

// What the terminal's box line adds about the far field beyond the box.
std::string beyondTheBox(const FarField& far, const FarHazard& hazard) {
  return "; beyond " + formatNumber("%.4g", far.spec().far_radius_m) +
         " m the far field bounds it: " +
         (hazard.farthest().nohd_m > 0.0
              ? "it reaches " + formatNumber("%.4g", hazard.farthest().nohd_m) + " m"
              : std::string("no direction is hazardous there"));
}

// The default output folder: out/<scene name>, out/<scene name>_uniform.
std::filesystem::path outputFolder(const RunArgs& args) {
  if (!args.out_dir.empty()) return args.out_dir;
  return std::filesystem::path("out") / (std::filesystem::path(args.scene_path).stem().string() +
                                         (args.uniform ? "_uniform" : ""));
}

// An earlier run of this scene may have written files this one will not (a plane since
// renamed): said, so that no stale map passes for a new one. Returns them.
std::vector<std::string> noteEarlierFiles(const std::filesystem::path& dir,
                                          const EarlierRun& earlier, const RunOutputs& outputs,
                                          bool quiet, std::ostream& err) {
  std::vector<std::string> stale = staleOutputs(dir, earlier, outputs.names());
  if (!stale.empty() && !quiet) {
    std::string list;
    for (const std::string& name : stale) list += (list.empty() ? "" : ", ") + name;
    err << "glint run: note: " << dir.string() << " keeps " << list
        << " from an earlier run of this scene, which this run does not rewrite\n";
  }
  return stale;
}

}  // namespace

FarField sceneFarField(const SceneTarget& target, const Scene& scene, const MemoryWatch& watch,
                       const std::string& what, std::ostream* progress_to, bool terminal,
                       PointExchange* exchange) {
  // The reach hands over to the far field as near as a check lets it speak.
  const FarFieldSpec spec = scene.wantsReach() ? checkedFarFieldSpec(scene, target.integrator)
                                               : farFieldSpec(scene, target.integrator);
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

SceneReach sceneReach(const SceneTarget& target, const Scene& scene, const FarField& far,
                      const MemoryWatch& watch, const std::string& what, std::ostream* progress_to,
                      bool terminal, PointExchange* exchange) {
  const ReachSpec spec = reachSpec(scene, far);
  const FieldSpec face = reachFaceSpec(0, spec);
  const std::uint64_t far_bytes = farFieldMemoryFloorBytes(far.spec());
  const std::uint64_t face_bytes = fieldMemoryFloorBytes(face, false);
  const std::string lattice = "6 × " + std::to_string(spec.face_cells + 1) + "² rays × " +
                              std::to_string(face.radial->layers + 1) + " layers from " +
                              formatNumber("%.3g", reachStartM(spec)) + " to " +
                              formatNumber("%.4g", spec.far_m) + " m";
  requireWithinBudget(what + " (" + lattice + ") beside the far field", far_bytes + face_bytes,
                      watch.budgetBytes(),
                      "lower reach.face_cells, raise reach.layer_ratio, or raise --memory");
  WorkCounter counter;
  counter.stop = &watch.stopFlag();
  std::unique_ptr<ProgressReporter> progress;
  if (progress_to != nullptr) {
    *progress_to << "glint run: " << what << ", " << lattice << "; memory: at least "
                 << formatBytes(static_cast<double>(far_bytes + face_bytes)) << " of the "
                 << formatBytes(static_cast<double>(watch.budgetBytes())) << " budget\n";
    progress =
        std::make_unique<ProgressReporter>(*progress_to, terminal, "reach points", 0, counter);
  }
  const FieldProblem problem = fieldProblem(target, scene, face);
  const auto start = std::chrono::steady_clock::now();
  SceneReach reach{[&] {
                     try {
                       return computeNearReach(problem.integrator, spec, problem.excluded, &counter,
                                               exchange);
                     } catch (const WorkStopped&) {
                       if (progress) progress->stop();
                       watch.check(what,
                                   "Raise --memory, or lower reach.face_cells, or raise "
                                   "reach.layer_ratio");
                       throw;
                     }
                   }(),
                   {},
                   0.0};
  if (progress) progress->stop();
  reach.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const double mu = scene.hazard.atmosphere.extinction_per_m;
  for (std::size_t t = 0; t < spec.thresholds_w_m2.size(); ++t)
    reach.summaries.push_back(summarizeReach(reach.near, far, t, mu));
  return reach;
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
  info.wavelength_nm = scene.hazard.wavelength_nm;
  info.power_w = scene.laser.power_w;
  info.exposure_s = scene.hazard.exposure_s;
  info.mpe_w_m2 = scene.hazard.mpe_w_m2;
  info.mpe_rule = hazardCitation(scene.hazard);
  info.optical_aid_gain = scene.hazard.aid ? scene.hazard.aid->gain : 0.0;
  info.scaled = hazardArrays(scene.hazard);
  return info;
}

namespace {

// What the regions of one run share while they are computed and written.
struct RunContext {
  const RunArgs& args;
  const Scene& scene;
  const RunInfo& info;
  const SceneTarget& target;
  const MemoryWatch& watch;
  RunOutputs& outputs;
  std::ostream& err;
  PointExchange* exchange;
};

// The summary as the regions add to it, and the brightest observer of each, where the meshes'
// surface model is checked.
struct RunSummary {
  nlohmann::json j;
  std::vector<std::pair<std::string, Vec3>> probes;
  std::vector<std::string> warnings;  // summary.json's, said again on the terminal at the end

  // The target as the first region's problem describes it (all share the same one).
  void describeTarget(const Scene& scene, const FieldProblem& problem) {
    if (!j.contains("target")) j["target"] = targetJson(problem.integrator.cullStats());
    if (scene.hasMeshes() && !j.contains("meshes"))
      j["meshes"] = meshesJson(scene, problem.mesh_stats);
  }
};

// The far field, where the scene asks for it, and its reach against the hazard.
struct FarResult {
  std::optional<FarField> far;
  FarHazard hazard;
};

void runBox(const RunContext& c, const FarResult& far, RunSummary& s) {
  FieldResult box = computeObserverField(c.target, c.scene, fieldSpec(c.scene), c.args, "points",
                                         c.watch, c.err, c.exchange);
  ObserverField& field = *box.field;
  requireFinite(field, "the observer box");
  const FacetIntegrator& integrator = box.problem.integrator;
  const HazardZone zone = hazardZone(field, c.scene.hazard, targetCentre(integrator.target()));
  if (field.stats().peak_w_m2 > 0.0)
    s.probes.emplace_back("the box's peak", field.stats().peak_at_m);
  s.j = volumeSummaryJson(field, zone, c.info, integrator.cullStats());
  s.describeTarget(c.scene, box.problem);
  s.j["hazard"] = hazardJson(c.scene.hazard, &zone);
  if (!c.args.quiet) {
    printVolume(c.err, field, c.scene, zone, c.info, c.args.uniform,
                far.far ? beyondTheBox(*far.far, far.hazard) : std::string());
  }
  BoxResults results{field, integrator, c.info};
  c.outputs.writeBox(results);  // last: the VDB takes the field's grids
}

// Where a plane's map lies on the site's map, or why it has none.
nlohmann::json planeMapJson(const PlaneSpec& plane, const ObserverField& field,
                            const SiteFrame& site) {
  if (!mappable(plane.u_axis, plane.v_axis)) {
    return {{"written", false},
            {"reason", "the plane is tilted more than " + formatNumber("%g", kMaxMapTiltDeg) +
                           " degrees from the horizontal: seen from above it is a sliver"}};
  }
  const auto n = field.spec().nodes();
  PlaneGrid grid;
  grid.width = n[0];
  grid.height = n[1];
  grid.origin_m = field.spec().min_m;
  grid.u_axis = field.spec().axes[0];
  grid.v_axis = field.spec().axes[1];
  grid.pixel_m = field.spec().voxel_m;
  const GeoPlacement p = placeOnMap(grid, site);
  return {{"written", true},
          {"geotiff", output_names::planeGeoTiff(plane.name)},
          {"zones",
           {output_names::planeZonesGeoJson(plane.name), output_names::planeZonesKml(plane.name)}},
          {"geotransform", p.geotransform},
          {"affine_error_m", p.affine_error_m}};
}

nlohmann::json siteJson(const SiteFrame& site) {
  const SiteSpec& s = site.spec();
  nlohmann::json j = {{"latitude_deg", s.latitude_deg}, {"longitude_deg", s.longitude_deg},
                      {"height_m", s.height_m},         {"bearing_deg", s.bearing_deg},
                      {"map_crs", site.mapName()},      {"map_proj", site.mapProj()}};
  if (site.mapEpsg() > 0) j["map_epsg"] = site.mapEpsg();
  return j;
}

void runPlanes(const RunContext& c, RunSummary& s) {
  nlohmann::json planes = nlohmann::json::array();
  const std::unique_ptr<SiteFrame> site =
      c.scene.site ? std::make_unique<SiteFrame>(*c.scene.site) : nullptr;
  for (std::size_t p = 0; p < c.scene.planes.size(); ++p) {
    const PlaneSpec& plane = c.scene.planes[p];
    const FieldResult r =
        computeObserverField(c.target, c.scene, planeFieldSpec(c.scene, plane), c.args,
                             plane.name.c_str(), c.watch, c.err, c.exchange);
    const ObserverField& field = *r.field;
    requireFinite(field, "plane " + plane.name);
    c.outputs.writePlane(p, {field, c.scene.hazard, c.info, nullptr, {}});
    const HazardZone zone =
        hazardZone(field, c.scene.hazard, targetCentre(r.problem.integrator.target()));
    planes.push_back(planeJson(plane, field, zone));
    if (site) planes.back()["map"] = planeMapJson(plane, field, *site);
    if (field.stats().peak_w_m2 > 0.0) {
      s.probes.emplace_back("plane " + plane.name + "'s peak", field.stats().peak_at_m);
    }
    s.describeTarget(c.scene, r.problem);
    if (!c.args.quiet) printPlane(c.err, plane, field, zone);
  }
  s.j["planes"] = planes;
}

// An engagement over the box and each plane: the points no bound can prove dark over the span
// are sampled in time, and each region's maps, summary entry and lines written.
void runEngagement(const RunContext& c, RunSummary& s) {
  const EngagementSpec& e = *c.scene.engagement;
  const Motion motion(e.motion, c.scene.laser);
  if (!c.args.quiet) {
    const std::size_t regions = c.scene.planes.size() + (c.scene.observers ? 1 : 0);
    c.err << "glint run: an engagement of " << formatNumber("%g", motion.durationS()) << " s over "
          << regions << (regions == 1 ? " region" : " regions")
          << "; the far field and the reach judge one pose and are left out\n";
  }
  std::ostream* progress = c.args.quiet ? nullptr : &c.err;
  if (c.scene.observers) {
    const FieldSpec spec = fieldSpec(c.scene);
    const EngagementRegion box = engagementRegion(c.target.integrator, c.scene, spec, c.watch,
                                                  progress, c.args.terminal, "the box", c.exchange);
    const std::vector<LatticeChannel> channels = box.maps.latticeChannels();
    c.outputs.writeEngagementBox({spec, channels, c.info});
    s.j["box"] =
        engagementRegionJson("box", output_names::kEngagementVdb, spec, box, c.scene.hazard);
    if (!c.args.quiet) printEngagementRegion(c.err, "the box", spec, box);
  }
  nlohmann::json planes = nlohmann::json::array();
  for (std::size_t p = 0; p < c.scene.planes.size(); ++p) {
    const PlaneSpec& plane = c.scene.planes[p];
    const FieldSpec spec = planeFieldSpec(c.scene, plane);
    const std::string what = "plane " + plane.name;
    const EngagementRegion m = engagementRegion(c.target.integrator, c.scene, spec, c.watch,
                                                progress, c.args.terminal, what, c.exchange);
    const std::vector<ExrChannel> channels = m.maps.channels();
    c.outputs.writeEngagementPlane(p, {m.maps.grid, channels, c.info, nullptr, {}});
    planes.push_back(engagementRegionJson(plane.name, output_names::planeExr(plane.name), spec, m,
                                          c.scene.hazard));
    if (!c.args.quiet) printEngagementRegion(c.err, what, spec, m);
  }
  s.j["engagement"] = engagementJson(e);
  if (!planes.empty()) s.j["planes"] = planes;
}

// The hazard reach, its files, its entry in the summary and its line on the terminal.
void runReach(const RunContext& c, const FarResult& far, RunSummary& s) {
  const SceneReach reach = sceneReach(c.target, c.scene, *far.far, c.watch, "the hazard reach",
                                      c.args.quiet ? nullptr : &c.err, c.args.terminal, c.exchange);
  s.j["hazard_reach"] = reachJson(reach.near, reach.summaries, reach.seconds);
  if (!c.args.quiet) printReach(c.err, reach.near, reach.summaries, reach.seconds);
  std::optional<ReachFootprint> footprint;
  if (const std::optional<FootprintSpec>& spec = c.scene.reach.footprint) {
    const SiteFrame site(*c.scene.site);
    try {
      footprint = reachFootprint(reach.near, *far.far, c.scene.hazard.atmosphere.extinction_per_m,
                                 site, c.scene.terrain.get(), *spec);
    } catch (const std::invalid_argument& e) {
      throw InputError(c.scene.source + ": /reach/footprint: " + e.what());
    }
    nlohmann::json f = {
        {"radius_m", spec->radius_m},
        {"pixel_m", footprint->grid.pixel_m},
        {"above_ground_m", spec->above_ground_m},
        {"area_m2", footprint->area_m2[0]},
        {"hidden_by_ground_m2", static_cast<double>(footprint->hidden_pixels) *
                                    footprint->grid.pixel_m * footprint->grid.pixel_m},
        {"files",
         {output_names::kReachFootprintTif, output_names::kReachFootprintGeoJson,
          output_names::kReachFootprintKml}}};
    if (footprint->area_m2.size() > 1) f["aided_area_m2"] = footprint->area_m2[1];
    s.j["hazard_reach"]["footprint"] = f;
  }
  c.outputs.writeReach(
      {reach.near, *far.far, c.scene.hazard, c.info, footprint ? &*footprint : nullptr, nullptr});
}

// The meshes' surface model against the alternatives, at the regions' peaks and the far
// field's (rank 0).
void checkSurfaces(const RunContext& c, const FarResult& far, RunSummary& s) {
  if (far.far && far.far->peak().intensity_w_sr > 0.0) {
    s.probes.emplace_back(
        "the far field's peak",
        far.far->ball().centre_m + far.far->mapDistance() * far.far->peak().direction);
  }
  const SurfaceModelCheck check = checkSurfaceModel(c.scene, c.target.integrator, s.probes);
  s.j["surface_check"] = surfaceCheckJson(c.scene, check);
  if (!c.args.quiet) printSurfaceCheck(c.err, c.scene, check);
}

// summary.json, and every output committed together, summary.json last (rank 0).
void finishRun(const RunContext& c, const std::filesystem::path& dir,
               const std::vector<std::string>& stale, RunSummary& s) {
  s.j["scene_path"] = sceneIdentity(c.args.scene_path);
  if (c.scene.site) s.j["site"] = siteJson(SiteFrame(*c.scene.site));
  s.j["files"] = c.outputs.names();
  if (!stale.empty()) s.j["earlier_files_kept"] = stale;
  s.j["warnings"] = s.warnings;
  // Spent once per lit facet, outside every region's count (FacetIntegrator).
  s.j["diffuse_moment_evaluations"] = c.target.integrator.diffuseMomentEvaluations();
  *c.outputs.summary() << s.j.dump(2) << "\n";
  c.watch.check("writing the outputs");  // a file written short of memory is not committed
  c.outputs.commit([&] { pauseForTestsAfterFirstOutput(c.err); });
  // Even when quiet: an empty result that is not a safe one must not pass unremarked.
  for (const std::string& w : s.warnings) c.err << "glint run: warning: " << w << "\n";
  if (c.args.quiet) return;
  std::string list;
  for (const std::string& w : c.outputs.names()) list += (list.empty() ? "" : ", ") + w;
  c.err << "  wrote " << dir.string() << "/{" << list << "}\n";
}

}  // namespace

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
  if (scene.engagement) {
    // Over an engagement glint run maps its box and planes; the far field and the reach judge
    // one pose.
    if (!scene.observers && scene.planes.empty()) {
      throw InputError(scene.source +
                       ": /engagement: glint run integrates an engagement over `observers` (a "
                       "box) or `planes`: give one, or list the observers for glint points");
    }
    scene.far_field.enabled = false;
    scene.reach.enabled = false;
  }
  if (!scene.observers && scene.planes.empty() && !scene.wantsReach()) {
    throw InputError(scene.source +
                     ": /reach/enabled: false, and there is neither `observers` nor `planes`: "
                     "glint run has nothing to compute");
  }
  if (scene.wantsReach() && !scene.far_field.enabled) {
    throw InputError(scene.source +
                     ": /far_field/enabled: false, but the hazard reach needs the far field "
                     "beyond its lattice (give `observers` or `planes`, or enable the far field)");
  }
  const std::filesystem::path dir = outputFolder(args);
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
  RunOutputs outputs(scene, dir, inputs, writer);
  const std::vector<std::string> stale = noteEarlierFiles(dir, earlier, outputs, args.quiet, err);
  if (writer) pauseForTestsAfterTemporaries(err);

  std::unique_ptr<tbb::global_control> thread_limit;
  if (args.threads > 0) {
    thread_limit = std::make_unique<tbb::global_control>(
        tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(args.threads));
  }
  const RunInfo info = runInfo(scene, args.scene_path, readUserFile(args.scene_path, "scene file"),
                               args.uniform ? "uniform" : "adaptive");
  const TargetBudget target_budget = checkRunMemory(scene, args, budget, writer, err);
  MemoryWatch watch(budget);
  noteTerrain(watch, scene);

  // Built and culled once, shared by the box and the planes.
  const SceneTarget target = sceneTarget(scene, firstRegion(scene), target_budget);
  watch.check("building the target",
              "Raise --memory, or lower the objects' segments, or decimate the meshes");
  const RunContext c{args, scene, info, target, watch, outputs, err, exchange};
  FarResult far;
  if (scene.far_field.enabled) {
    far.far.emplace(sceneFarField(target, scene, watch, "the far field",
                                  args.quiet ? nullptr : &err, args.terminal, exchange));
    far.hazard = farHazard(*far.far, scene.hazard);
  }
  RunSummary summary;
  // Over an engagement the target moves through the beam: its pose at the start says nothing.
  if (!scene.engagement)
    summary.warnings = unlitTargetWarnings(scene, target.integrator.cullStats());
  if (!args.quiet) {
    for (const std::string& w : summary.warnings) err << "glint run: warning: " << w << "\n";
  }
  if (scene.engagement) {
    summary.j = runJson(info);
    summary.j["hazard"] = hazardJson(scene.hazard, nullptr);
    runEngagement(c, summary);
    if (writer) finishRun(c, dir, stale, summary);
    return;
  }
  if (scene.observers) {
    runBox(c, far, summary);
  } else {
    summary.j = runJson(info);
    summary.j["hazard"] = hazardJson(scene.hazard, nullptr);
  }
  if (!scene.planes.empty()) runPlanes(c, summary);
  if (far.far && writer) {
    outputs.writeFar({*far.far, scene.hazard, info});
    summary.j["far_field"] = farFieldJson(*far.far, far.hazard, outputs.farNames());
    if (!args.quiet) printFarField(err, *far.far, far.hazard);
  }
  if (scene.wantsReach()) runReach(c, far, summary);
  if (scene.hasMeshes() && writer) checkSurfaces(c, far, summary);
  if (writer) finishRun(c, dir, stale, summary);
}

}  // namespace glint
