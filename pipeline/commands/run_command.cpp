#include "pipeline/commands/run_command.h"

#include <tbb/global_control.h>
#include <tbb/info.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "export/field_files.h"
#include "export/geo_files.h"
#include "export/lattice_vdb.h"
#include "observers/exposure.h"
#include "pipeline/base/input_error.h"
#include "pipeline/base/memory_budget.h"
#include "pipeline/base/number_format.h"
#include "pipeline/base/output_names.h"
#include "pipeline/base/phase_clock.h"
#include "pipeline/base/progress.h"
#include "pipeline/base/test_pause.h"
#include "pipeline/input/input_files.h"
#include "pipeline/input/json_reader.h"
#include "pipeline/input/scene.h"
#include "pipeline/report/engagement_report.h"
#include "pipeline/report/output_folder.h"
#include "pipeline/report/run_folder.h"
#include "pipeline/report/run_outputs.h"
#include "pipeline/report/run_report.h"
#include "pipeline/report/unlit_warning.h"
#include "pipeline/setup/scene_regions.h"
#include "pipeline/setup/surface_check.h"
#include "pipeline/setup/target_builder.h"

namespace glint {
namespace {

// Refuses a region whose memory floor (its field, and the scratch of the writer of its
// largest file, @p files) exceeds the budget before any of it is allocated, and tells the user
// at once what the run is about to do. Returns the floor.
std::uint64_t checkRegionMemory(const FieldSpec& spec, const std::string& what, const RunArgs& args,
                                bool dense, const WriterScratch& files, std::uint64_t budget_bytes,
                                std::ostream& err) {
  const std::array<int, 3> n = spec.nodes();
  const std::string lattice = std::to_string(n[0]) + "×" + std::to_string(n[1]) +
                              (spec.plane ? "" : "×" + std::to_string(n[2]));
  const std::uint64_t floor_bytes = fieldMemoryFloorBytes(spec, dense) + files.bytes;
  // The writer named where its share is one a user may not expect: a tenth or more.
  const bool named = files.bytes > 0 && 10 * files.bytes >= floor_bytes;
  const std::string writing =
      named ? ", " + formatBytes(static_cast<double>(files.bytes)) + " of it to write " + files.file
            : "";
  requireWithinBudget(
      what + " (" + lattice + " lattice points at " + formatNumber("%g", spec.voxel_m) + " m" +
          (dense ? ", dense" : "") + writing + ")",
      floor_bytes, budget_bytes,
      named && !files.advice.empty()
          ? files.advice + ", or raise --memory"
          : "coarsen voxel_m or pixel_m, enlarge block_m, shrink the region, or raise --memory");
  if (!args.quiet) {
    err << "glint run: " << what << ", " << lattice << " lattice points at "
        << formatNumber("%g", spec.voxel_m) << " m; memory: at least "
        << formatBytes(static_cast<double>(floor_bytes)) << " of the "
        << formatBytes(static_cast<double>(budget_bytes)) << " budget\n";
  }
  return floor_bytes;
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
  // Only the writing rank allocates what its writers make.
  const auto writing = [&](OutputRegion region, const FieldSpec* lattice = nullptr,
                           const std::string& plane = "") {
    return writer ? writerScratch(scene, region, lattice, plane) : WriterScratch{};
  };
  std::uint64_t region_bytes = 0;
  if (scene.observers) {
    const FieldSpec box = fieldSpec(scene);
    const WriterScratch files =
        writing(scene.engagement ? OutputRegion::EngagementBox : OutputRegion::Box, &box);
    region_bytes = checkRegionMemory(box, "observer box", args, dense, files, budget, err);
  }
  for (const PlaneSpec& plane : scene.planes) {
    const FieldSpec spec = planeFieldSpec(scene, plane);
    const WriterScratch files = writing(
        scene.engagement ? OutputRegion::EngagementPlane : OutputRegion::Plane, &spec, plane.name);
    region_bytes = std::max(region_bytes, checkRegionMemory(spec, "plane " + plane.name, args,
                                                            dense, files, budget, err));
  }
  std::uint64_t far_bytes = 0;
  if (scene.far_field.enabled) {
    const FarFieldSpec lattice = farFieldLattice(scene);
    // The reach's files are written after the far field's, while it is held.
    const std::uint64_t far_writers = writing(OutputRegion::Far).bytes;
    const std::uint64_t reach_writers = writing(OutputRegion::Reach).bytes;
    far_bytes = farFieldMemoryFloorBytes(lattice, std::max(far_writers, reach_writers));
    // Where the far field fits but not the reach's files beside it (a footprint of many
    // pixels), the advice is the footprint's.
    if (far_bytes > budget && reach_writers > far_writers &&
        farFieldMemoryFloorBytes(lattice, far_writers) <= budget) {
      requireWithinBudget("the reach's maps and footprint, written while " +
                              farFieldDescription(lattice) + " is held",
                          far_bytes, budget,
                          "coarsen reach.footprint.pixel_m or shrink reach.footprint.radius_m, "
                          "or raise --memory");
    }
    requireWithinBudget(farFieldDescription(lattice), far_bytes, budget,
                        "lower far_field.face_pixels, or raise --memory");
    if (!args.quiet) {
      err << "glint run: " << farFieldDescription(lattice) << "; memory: at least "
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
  PhaseClock& clock;  // summary.json's `timing`

  // How the run watches and shows the computation named @p what.
  [[nodiscard]] WorkWatch work(std::string what) const {
    return {watch, std::move(what), args.quiet ? nullptr : &err, args.terminal, exchange};
  }
};

// The summary as the regions add to it, and the brightest observer of each, where the meshes'
// surface model is checked.
struct RunSummary {
  nlohmann::json j;
  std::vector<std::pair<std::string, Vec3>> probes;
  std::vector<std::string> warnings;  // summary.json's, said again on the terminal at the end
  bool unlit = false;                 // the beam lights no facet: an empty result is no verdict

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
  const FieldSpec spec = fieldSpec(c.scene);
  PhaseClock::Scope computing = c.clock.phase("the observer box");
  const FieldProblem problem = fieldProblem(c.target, c.scene, spec);
  ObserverField field =
      sceneField(problem, spec, c.args.uniform, c.work("the observer box"), "points");
  const FacetIntegrator& integrator = problem.integrator;
  const HazardZone zone = hazardZone(field, c.scene.hazard, targetCentre(integrator.target()));
  if (field.stats().peak_w_m2 > 0.0)
    s.probes.emplace_back("the box's peak", field.stats().peak_at_m);
  s.j = volumeSummaryJson(field, zone, c.info, integrator.cullStats());
  s.describeTarget(c.scene, problem);
  s.j["hazard"] = hazardJson(c.scene.hazard, &zone);
  if (!c.args.quiet) {
    printVolume(c.err, field, c.scene, zone, c.info, c.args.uniform,
                far.far ? beyondTheBox(*far.far, far.hazard) : std::string());
  }
  computing.stop();
  const PhaseClock::Scope writing = c.clock.phase("writing the observer box's files");
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
  const PhaseClock::Scope phase = c.clock.phase("the planes and their files");
  nlohmann::json planes = nlohmann::json::array();
  const std::unique_ptr<SiteFrame> site =
      c.scene.site ? std::make_unique<SiteFrame>(*c.scene.site) : nullptr;
  for (std::size_t p = 0; p < c.scene.planes.size(); ++p) {
    const PlaneSpec& plane = c.scene.planes[p];
    const FieldSpec spec = planeFieldSpec(c.scene, plane);
    const FieldProblem problem = fieldProblem(c.target, c.scene, spec);
    const ObserverField field = sceneField(problem, spec, c.args.uniform,
                                           c.work("plane " + plane.name), plane.name.c_str());
    c.outputs.writePlane(p, {field, c.scene.hazard, c.info, nullptr, {}});
    const HazardZone zone =
        hazardZone(field, c.scene.hazard, targetCentre(problem.integrator.target()));
    planes.push_back(planeJson(plane, field, zone, c.scene.hazard));
    if (site) planes.back()["map"] = planeMapJson(plane, field, *site);
    if (field.stats().peak_w_m2 > 0.0) {
      s.probes.emplace_back("plane " + plane.name + "'s peak", field.stats().peak_at_m);
    }
    s.describeTarget(c.scene, problem);
    if (!c.args.quiet) printPlane(c.err, plane, field, zone, c.scene.hazard);
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
    const EngagementRegion box =
        engagementRegion(c.target.integrator, c.scene, spec,
                         WorkWatch{c.watch, "the box", progress, c.args.terminal, c.exchange});
    const std::vector<LatticeChannel> channels = box.maps.latticeChannels();
    c.outputs.writeEngagementBox({spec, channels, c.info});
    s.j["box"] =
        engagementRegionJson("box", output_names::kEngagementVdb, spec, box, c.scene.hazard);
    if (!c.args.quiet) printEngagementRegion(c.err, "the box", spec, box, c.scene.hazard);
  }
  nlohmann::json planes = nlohmann::json::array();
  for (std::size_t p = 0; p < c.scene.planes.size(); ++p) {
    const PlaneSpec& plane = c.scene.planes[p];
    const FieldSpec spec = planeFieldSpec(c.scene, plane);
    const std::string what = "plane " + plane.name;
    const EngagementRegion m =
        engagementRegion(c.target.integrator, c.scene, spec,
                         WorkWatch{c.watch, what, progress, c.args.terminal, c.exchange});
    const std::vector<ExrChannel> channels = m.maps.channels();
    c.outputs.writeEngagementPlane(p, {m.maps.grid, channels, c.info, nullptr, {}});
    planes.push_back(engagementRegionJson(plane.name, output_names::planeExr(plane.name), spec, m,
                                          c.scene.hazard));
    if (!c.args.quiet) printEngagementRegion(c.err, what, spec, m, c.scene.hazard);
  }
  s.j["engagement"] = engagementJson(e);
  if (!planes.empty()) s.j["planes"] = planes;
}

// The footprint at each flight altitude: its reference and the area each threshold covers.
nlohmann::json footprintAltitudesJson(const ReachFootprint& f, const FootprintSpec& spec,
                                      const HazardSpec& h) {
  nlohmann::json list = nlohmann::json::array();
  const double cell_m2 = f.grid.pixel_m * f.grid.pixel_m;
  for (const ReachFootprint::Altitude& a : f.altitudes) {
    nlohmann::json j = {{"altitude_m", a.altitude_m},
                        {"reference", spec.altitudes_above_ellipsoid ? "ellipsoid" : "ground"},
                        {"area_m2", a.area_m2.at(0)},
                        {"hidden_by_ground_m2", static_cast<double>(a.hidden_pixels) * cell_m2}};
    if (h.aid) j["aided_area_m2"] = a.area_m2.at(1);
    for (std::size_t k = 0; k < h.levels.size(); ++k)
      j["levels"][h.levels[k].name]["area_m2"] = a.area_m2.at(h.firstLevelThreshold() + k);
    list.push_back(j);
  }
  return list;
}

// The hazard reach, its files, its entry in the summary and its line on the terminal.
void runReach(const RunContext& c, const FarResult& far, RunSummary& s) {
  const SceneReach reach =
      sceneReach(c.target, c.scene, *far.far, far.hazard, c.work("the hazard reach"));
  c.clock.add("the hazard reach: its lattice", reach.seconds);
  c.clock.add("the hazard reach: each threshold's distance and volume", reach.summary_seconds);
  s.j["hazard_reach"] = reachJson(reach.near, reach.summaries, reach.seconds, c.scene.hazard);
  if (!c.args.quiet)
    printReach(c.err, reach.near, reach.summaries, reach.seconds, c.scene.hazard, !s.unlit);
  std::optional<ReachFootprint> footprint;
  if (const std::optional<FootprintSpec>& spec = c.scene.reach.footprint) {
    const PhaseClock::Scope phase = c.clock.phase("the hazard reach: its footprint on the ground");
    const SiteFrame site(*c.scene.site);
    try {
      WorkCounter counter;
      std::optional<ProgressReporter> progress;
      if (!c.args.quiet) {
        progress.emplace(c.err, c.args.terminal, "rows of the footprint", footprintRows(*spec),
                         counter);
      }
      footprint = reachFootprint(reach.near, *far.far, c.scene.hazard.atmosphere.extinction_per_m,
                                 site, c.scene.terrain.get(), *spec, &counter);
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
    const HazardSpec& h = c.scene.hazard;
    if (h.aid) f["aided_area_m2"] = footprint->area_m2.at(1);
    for (std::size_t k = 0; k < h.levels.size(); ++k)
      f["levels"][h.levels[k].name]["area_m2"] = footprint->area_m2.at(h.firstLevelThreshold() + k);
    f["altitudes"] = footprintAltitudesJson(*footprint, *spec, h);
    s.j["hazard_reach"]["footprint"] = f;
  }
  const PhaseClock::Scope writing = c.clock.phase("writing the hazard reach's files");
  c.outputs.writeReach(
      {reach.near, *far.far, c.scene.hazard, c.info, footprint ? &*footprint : nullptr, nullptr,
       c.scene.reach.footprint && c.scene.reach.footprint->altitudes_above_ellipsoid});
}

// The meshes' surface model against the alternatives, at the regions' peaks and the far
// field's (rank 0).
void checkSurfaces(const RunContext& c, const FarResult& far, RunSummary& s) {
  if (far.far && far.far->peak().intensity_w_sr > 0.0) {
    s.probes.emplace_back(
        "the far field's peak",
        far.far->ball().centre_m + far.far->mapDistance() * far.far->peak().direction);
  }
  const PhaseClock::Scope phase = c.clock.phase("the meshes' surface model checked");
  const SurfaceModelCheck check = checkSurfaceModel(c.scene, c.target.integrator, s.probes);
  s.j["surface_check"] = surfaceCheckJson(c.scene, check);
  if (!c.args.quiet) printSurfaceCheck(c.err, c.scene, check);
}

// summary.json, and every output committed together, summary.json last (rank 0).
// What makes a run's files smaller, in the keys of the regions the scene has.
std::string writingAdvice(const Scene& scene) {
  std::vector<std::string> ways;
  if (scene.observers) ways.emplace_back("coarsen observers.voxel_m or shrink the box");
  if (!scene.planes.empty()) ways.emplace_back("coarsen the planes' pixel_m");
  if (scene.reach.footprint) {
    ways.emplace_back("coarsen reach.footprint.pixel_m or shrink reach.footprint.radius_m");
  }
  if (scene.far_field.enabled) ways.emplace_back("lower far_field.face_pixels");
  std::string advice = "Raise --memory";
  for (const std::string& w : ways) advice += ", or " + w;
  return advice;
}

void finishRun(const RunContext& c, const std::filesystem::path& dir,
               const std::vector<std::string>& stale, RunSummary& s) {
  s.j["scene_path"] = sceneIdentity(c.args.scene_path);
  s.j["laser"] = laserJson(c.scene.laser, c.scene.hazard);
  s.j["materials"] = materialsJson(c.scene);
  if (c.scene.site) s.j["site"] = siteJson(SiteFrame(*c.scene.site));
  s.j["files"] = c.outputs.names();
  if (!stale.empty()) s.j["earlier_files_kept"] = stale;
  s.j["warnings"] = s.warnings;
  // Spent once per lit facet, outside every region's count (FacetIntegrator).
  s.j["diffuse_moment_evaluations"] = c.target.integrator.diffuseMomentEvaluations();
  s.j["timing"] = timingJson(c.clock);
  *c.outputs.summary() << s.j.dump(2) << "\n";
  // A file written short of memory is not committed.
  c.watch.check("writing the outputs", writingAdvice(c.scene));
  c.outputs.commit([&] { pauseForTestsAfterFirstOutput(c.err); });
  pauseForTestsAfterOutputs(c.err);
  // Even when quiet: an empty result that is not a safe one must not pass unremarked.
  for (const std::string& w : s.warnings) c.err << "glint run: warning: " << w << "\n";
  if (c.args.quiet) return;
  std::string list;
  for (const std::string& w : c.outputs.names()) list += (list.empty() ? "" : ", ") + w;
  c.err << "  wrote " << dir.string() << "/{" << list << "}\n";
}

}  // namespace

void runScene(const RunArgs& requested, std::ostream& err, PointExchange* exchange) {
  // Under MPI every rank computes the same field, sharing the points; rank 0 alone reports
  // and writes.
  const bool writer = exchange == nullptr || exchange->rank() == 0;
  PhaseClock clock;
  PhaseClock::Scope reading = clock.phase("reading the scene and checking its memory");
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
  if (!args.quiet) outputs.showProgress(&err, args.terminal);
  const std::vector<std::string> stale = noteEarlierFiles(dir, earlier, outputs, args.quiet, err);
  if (writer) pauseForTestsAfterTemporaries(err);

  std::unique_ptr<tbb::global_control> thread_limit;
  if (args.threads > 0) {
    thread_limit = std::make_unique<tbb::global_control>(
        tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(args.threads));
  }
  const RunInfo info = runInfo(scene, args.scene_path, readUserFile(args.scene_path, "scene file"),
                               args.uniform ? "uniform" : "adaptive");
  // The laser and its limits as read, before the work: a slip of units shows at once.
  if (!args.quiet) {
    err << "glint run: laser " << laserLine(scene.laser, scene.hazard) << "\n"
        << "glint run: limits " << hazardLine(scene.hazard) << "\n";
  }
  const TargetBudget target_budget = checkRunMemory(scene, args, budget, writer, err);
  MemoryWatch watch(budget);
  noteTerrain(watch, scene);
  reading.stop();

  // Built and culled once, shared by the box and the planes.
  PhaseClock::Scope building = clock.phase("building the target");
  const SceneTarget target = sceneTarget(scene, firstRegion(scene), target_budget);
  watch.check("building the target",
              "Raise --memory, or lower the objects' segments, or decimate the meshes");
  building.stop();
  const RunContext c{args, scene, info, target, watch, outputs, err, exchange, clock};
  FarResult far;
  if (scene.far_field.enabled) {
    PhaseClock::Scope map = clock.phase("the far field and its far radius");
    far.far.emplace(sceneFarField(target, scene, c.work("the far field")));
    map.stop();
    const PhaseClock::Scope distances = clock.phase("the far field's hazard distances");
    far.hazard = farHazard(*far.far, scene.hazard);
  }
  RunSummary summary;
  // Over an engagement the target moves through the beam: its pose at the start says nothing.
  if (!scene.engagement)
    summary.warnings = unlitTargetWarnings(scene, target.integrator.cullStats());
  summary.unlit = !summary.warnings.empty();
  if (!args.quiet) {
    for (const std::string& w : summary.warnings) err << "glint run: warning: " << w << "\n";
  }
  if (scene.engagement) {
    summary.j = runJson(info);
    summary.j["hazard"] = hazardJson(scene.hazard, nullptr);
    PhaseClock::Scope engagement = clock.phase("the engagement");
    runEngagement(c, summary);
    engagement.stop();
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
    const PhaseClock::Scope writing = clock.phase("writing the far field's files");
    outputs.writeFar({*far.far, scene.hazard, info});
    summary.j["far_field"] = farFieldJson(*far.far, far.hazard, outputs.farNames(), scene.hazard);
    if (!args.quiet) printFarField(err, *far.far, far.hazard, scene.hazard);
  }
  if (scene.wantsReach()) runReach(c, far, summary);
  if (scene.hasMeshes() && writer) checkSurfaces(c, far, summary);
  if (writer) finishRun(c, dir, stale, summary);
}

}  // namespace glint
