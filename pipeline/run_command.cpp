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
#include "pipeline/json_reader.h"
#include "pipeline/memory_budget.h"
#include "pipeline/progress.h"
#include "pipeline/scene.h"
#include "pipeline/target_builder.h"

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

// What the summary says of the points whose integration stopped short of its tolerance: where
// they are (status 5 marks each) and whether any could be hazardous.
nlohmann::json unconvergedJson(const FieldStats& s, const HazardZone& zone) {
  return {{"points", s.unconverged_points},
          {"box",
           {{"min_m", {s.unconverged_min_m.x, s.unconverged_min_m.y, s.unconverged_min_m.z}},
            {"max_m", {s.unconverged_max_m.x, s.unconverged_max_m.y, s.unconverged_max_m.z}}}},
          {"max_irradiance_plus_error_w_m2", s.unconverged_max_upper_w_m2},
          {"max_hazard_ratio_plus_error", zone.unconverged_ratio_upper},
          {"may_be_hazardous", zone.unconvergedMayBeHazardous()}};
}

// One line on the points that did not converge: a note where none of them can reach the MPE,
// else a warning.
void printUnconverged(std::ostream& err, const FieldStats& s, const HazardZone& zone,
                      const char* indent) {
  if (s.unconverged_points == 0) return;
  const bool may = zone.unconvergedMayBeHazardous();
  err << indent << (may ? "warning: " : "note: ") << s.unconverged_points
      << " points did not reach the integration tolerance (status 5), within ("
      << s.unconverged_min_m.x << ", " << s.unconverged_min_m.y << ", " << s.unconverged_min_m.z
      << ") .. (" << s.unconverged_max_m.x << ", " << s.unconverged_max_m.y << ", "
      << s.unconverged_max_m.z << "); at each, irradiance plus its error estimate is at most "
      << formatNumber("%.3g", s.unconverged_max_upper_w_m2) << " W/m² ("
      << formatNumber("%.3g", zone.unconverged_ratio_upper) << " × the MPE)"
      << (may ? ": some may be hazardous; raise accuracy.max_depth or accuracy.max_evaluations"
              : ", so none of them can be hazardous")
      << "\n";
}

nlohmann::json targetJson(const CullStats& cull) {
  return {{"coarse_facets", cull.coarse_facets}, {"lit", cull.lit},
          {"facing_away", cull.facing_away},     {"outside_beam", cull.outside_beam},
          {"shadowed", cull.shadowed},           {"degenerate", cull.degenerate},
          {"occlusion_rays", cull.occlusion}};
}

// What became of each mesh's triangles (@p stats in the order of the scene's meshes).
nlohmann::json meshesJson(const Scene& scene, const std::vector<MeshStats>& stats) {
  nlohmann::json meshes = nlohmann::json::array();
  std::size_t k = 0;
  for (const ObjectSpec& o : scene.objects) {
    if (!o.mesh) continue;
    const MeshStats& s = stats[k++];
    meshes.push_back({{"file", o.mesh->file.string()},
                      {"triangles", s.triangles},
                      {"facets", s.facets},
                      {"degenerate_dropped", s.degenerate_dropped},
                      {"normals_computed", o.mesh->normals_computed},
                      {"normals_repaired", s.normals_repaired},
                      {"quadric_fits", s.quadric_fits},
                      {"quadric_fit_fallbacks_to_pn", s.fit_fallbacks},
                      {"crease_edges", s.crease_edges},
                      {"open_edges", s.open_edges},
                      {"primitives_skipped", o.mesh->primitives_skipped},
                      {"mirrored_instances", o.mesh->mirrored_instances}});
  }
  return meshes;
}

nlohmann::json summaryJson(const ObserverField& field, const HazardZone& zone, const RunInfo& info,
                           const CullStats& cull) {
  const FieldSpec& spec = field.spec();
  const FieldStats& s = field.stats();
  nlohmann::json j;
  j["program"] = info.program_version;
  j["scene_file"] = info.scene_file;
  j["scene_fnv1a64"] = info.scene_fnv1a64;
  j["scheme"] = info.scheme;
  j["integration_scheme"] = info.integration_scheme;
  j["box"] = {{"min_m", {spec.min_m.x, spec.min_m.y, spec.min_m.z}},
              {"max_m",
               {spec.position(s.nodes[0] - 1, 0, 0).x, spec.position(0, s.nodes[1] - 1, 0).y,
                spec.position(0, 0, s.nodes[2] - 1).z}},
              {"voxel_m", spec.voxel_m},
              {"block_m", spec.voxel_m * spec.block_voxels},
              {"lattice_points", {s.nodes[0], s.nodes[1], s.nodes[2]}}};
  j["tolerance"] = spec.tolerance;
  j["floor_w_m2"] = spec.floor_w_m2;
  j["target"] = targetJson(cull);
  j["points"] = {{"in_box", s.lattice_points},
                 {"evaluated", s.evaluated_points},
                 {"interpolated", s.interpolated_points},
                 {"proven_below_floor", s.below_floor_points},
                 {"inside_target", s.excluded_points},
                 {"unconverged", s.unconverged_points}};
  if (s.unconverged_points > 0) j["unconverged"] = unconvergedJson(s, zone);
  j["blocks"] = {{"skipped", s.blocks_skipped},
                 {"accepted", s.blocks_accepted},
                 {"accepted_interpolating_e_r_or_e_r2", s.blocks_accepted_spread},
                 {"refined", s.blocks_refined},
                 {"finest", s.blocks_finest},
                 {"levels", s.levels + 1}};
  j["evaluations"] = s.evaluations;
  j["bound_evaluations"] = s.bound_evaluations;
  j["seconds"] = s.seconds;
  j["peak_irradiance_w_m2"] = s.peak_w_m2;
  j["peak_at_m"] = {s.peak_at_m.x, s.peak_at_m.y, s.peak_at_m.z};
  nlohmann::json volumes = nlohmann::json::array();
  for (double fraction : {0.01, 0.1, 0.5}) {
    const double t = fraction * s.peak_w_m2;
    volumes.push_back({{"fraction_of_peak", fraction},
                       {"threshold_w_m2", t},
                       {"volume_m3", s.peak_w_m2 > 0.0 ? field.volumeAbove(t) : 0.0}});
  }
  j["volumes_above"] = volumes;
  j["memory"] = {{"grid_bytes", s.grid_bytes},
                 {"active_voxels", s.active_voxels},
                 {"bytes_per_active_voxel",
                  s.active_voxels > 0
                      ? static_cast<double>(s.grid_bytes) / static_cast<double>(s.active_voxels)
                      : 0.0}};
  return j;
}

// The one-screen summary of the volume.
// @p beyond_box: what the far field says of the hazard beyond the box ("" without one).
void printVolume(std::ostream& err, const ObserverField& field, const Scene& scene,
                 const HazardZone& zone, const RunInfo& info, bool uniform,
                 const std::string& beyond_box) {
  const FieldSpec& spec = field.spec();
  const FieldStats& s = field.stats();
  const double box_points = static_cast<double>(s.lattice_points);
  err << "glint run: " << info.scheme << ", " << s.nodes[0] << "×" << s.nodes[1] << "×"
      << s.nodes[2] << " lattice points at " << spec.voxel_m << " m, tolerance " << spec.tolerance
      << ", floor " << formatNumber("%.3g", spec.floor_w_m2) << " W/m²\n";
  err << "  points: " << s.evaluated_points << " evaluated ("
      << formatNumber("%.3g", 100.0 * static_cast<double>(s.evaluated_points) / box_points)
      << " %), " << s.interpolated_points << " interpolated, " << s.below_floor_points
      << " proven below the floor, " << s.excluded_points << " inside the target\n";
  if (!uniform) {
    err << "  blocks: " << s.blocks_skipped << " skipped, " << s.blocks_accepted << " accepted ("
        << s.blocks_accepted_spread << " as E·r or E·r²), " << s.blocks_refined << " refined, "
        << s.blocks_finest << " at the finest level (" << s.levels + 1 << " levels)\n";
  }
  err << "  evaluations: " << formatNumber("%.4g", static_cast<double>(s.evaluations)) << " in "
      << formatDuration(s.seconds) << "\n";
  err << "  peak irradiance: " << formatNumber("%.6g", s.peak_w_m2) << " W/m² at (" << s.peak_at_m.x
      << ", " << s.peak_at_m.y << ", " << s.peak_at_m.z << ")\n";
  err << "  hazard: " << hazardLine(scene.hazard) << "; peak hazard ratio "
      << formatNumber("%.3g", zone.peak_ratio);
  if (scene.hazard.aid) err << ", aided " << formatNumber("%.3g", zone.aided_peak_ratio);
  if (scene.hazard.pulse) {
    err << "; peak " << formatNumber("%.3g", zone.peak_pulse_j_m2) << " J/m² a pulse";
  }
  err << "\n";
  auto printZone = [&](const ObserverField::Exceedance& r, const char* name) {
    if (r.points == 0) {
      err << "  " << name << ": none in the box (no point reaches the MPE)\n";
      return;
    }
    err << "  " << name << ": " << formatNumber("%.4g", r.volume_m3) << " m³, reaching "
        << formatNumber("%.4g", r.farthest_m) << " m from the target centre, at ("
        << r.farthest_at_m.x << ", " << r.farthest_at_m.y << ", " << r.farthest_at_m.z << ")\n";
    if (r.reaches_edge) {
      err << "  warning: the " << name
          << " reaches the edge of the observer box and may go on "
             "beyond it"
          << (beyond_box.empty() ? ": enlarge the box to see its full extent" : beyond_box) << "\n";
    }
  };
  printZone(zone.above_mpe, "nominal hazard zone (ratio ≥ 1)");
  if (zone.aided_above_mpe) printZone(*zone.aided_above_mpe, "aided hazard zone (aided ratio ≥ 1)");
  printUnconverged(err, s, zone, "  ");
  err << "  memory: " << formatNumber("%.3g", static_cast<double>(s.grid_bytes) / 1e6)
      << " MB of grids, "
      << formatNumber("%.3g", s.active_voxels > 0 ? static_cast<double>(s.grid_bytes) /
                                                        static_cast<double>(s.active_voxels)
                                                  : 0.0)
      << " bytes per active voxel\n";
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
// tells the user at once what the run is about to do.
void checkRegionMemory(const FieldSpec& spec, const std::string& what, const RunArgs& args,
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
}

// A plane's lattice points stand for pixel_m² each.
double hazardousArea(const ObserverField& field, const ObserverField::Exceedance& zone) {
  return static_cast<double>(zone.points) * field.spec().voxel_m * field.spec().voxel_m;
}

nlohmann::json planeJson(const PlaneSpec& plane, const ObserverField& field,
                         const HazardZone& zone) {
  const FieldStats& s = field.stats();
  const FieldSpec& spec = field.spec();
  const ObserverField::Exceedance& r = zone.above_mpe;
  nlohmann::json j = {{"name", plane.name},
                      {"file", plane.name + ".exr"},
                      {"pixels", {s.nodes[0], s.nodes[1]}},
                      {"pixel_m", spec.voxel_m},
                      {"tolerance", spec.tolerance},
                      {"floor_w_m2", spec.floor_w_m2},
                      {"points",
                       {{"evaluated", s.evaluated_points},
                        {"interpolated", s.interpolated_points},
                        {"proven_below_floor", s.below_floor_points},
                        {"inside_target", s.excluded_points},
                        {"unconverged", s.unconverged_points}}},
                      {"evaluations", s.evaluations},
                      {"seconds", s.seconds},
                      {"peak_irradiance_w_m2", s.peak_w_m2},
                      {"peak_at_m", {s.peak_at_m.x, s.peak_at_m.y, s.peak_at_m.z}},
                      {"peak_hazard_ratio", zone.peak_ratio},
                      {"hazardous_area_m2", hazardousArea(field, zone.above_mpe)}};
  if (zone.aided_above_mpe) {
    j["aided_peak_hazard_ratio"] = zone.aided_peak_ratio;
    j["aided_hazardous_area_m2"] = hazardousArea(field, *zone.aided_above_mpe);
  }
  if (s.unconverged_points > 0) j["unconverged"] = unconvergedJson(s, zone);
  if (r.points > 0) {
    j["hazard_farthest_from_target_m"] = r.farthest_m;
    j["hazard_farthest_at_m"] = {r.farthest_at_m.x, r.farthest_at_m.y, r.farthest_at_m.z};
  }
  return j;
}

nlohmann::json farFieldJson(const FarField& field, const FarHazard& hazard) {
  const FarFieldSpec& spec = field.spec();
  const FieldStats& s = field.stats();
  const Vec3& c = field.ball().centre_m;
  const Vec3& d = field.peak().direction;
  const double azimuth_deg = std::atan2(d.y, d.x) * 180.0 / kPi;
  const double elevation_deg = std::asin(std::clamp(d.z, -1.0, 1.0)) * 180.0 / kPi;
  nlohmann::json j = {
      {"files", {"far_field.exr", "far_field.vtp"}},
      {"centre_m", {c.x, c.y, c.z}},
      {"lit_radius_m", field.ball().radius_m},
      {"far_radius_m", spec.far_radius_m},
      {"map_distance_m", field.mapDistance()},
      {"tolerance", spec.tolerance},
      {"floor_w_sr", spec.floor_w_sr},
      {"face_pixels", spec.face_pixels},
      {"directions",
       {{"in_map", s.lattice_points},
        {"evaluated", s.evaluated_points},
        {"interpolated", s.interpolated_points},
        {"proven_below_floor", s.below_floor_points},
        {"unconverged", s.unconverged_points}}},
      {"evaluations", s.evaluations},
      {"seconds", s.seconds},
      {"peak_intensity_w_sr", field.peak().intensity_w_sr},
      {"peak_direction", {d.x, d.y, d.z}},
      {"peak_azimuth_deg", azimuth_deg},
      {"peak_elevation_deg", elevation_deg},
      {"beam_direction", {spec.beam_direction.x, spec.beam_direction.y, spec.beam_direction.z}},
      {"far_radius_rule",
       "lit_radius_m (1 + (3 + g / sigma) / tolerance), g = max(1, 0.43 / sin(psi / 2)), psi "
       "the angle from beam_direction: far_radius_m beyond 51 degrees, growing into the "
       "forward cone"}};
  j.update(farHazardJson(hazard));
  if (s.unconverged_points > 0) {
    j["unconverged_max_intensity_plus_error_w_sr"] = s.unconverged_max_upper_w_m2;
  }
  return j;
}

void printFarField(std::ostream& err, const FarField& field, const FarHazard& far_hazard) {
  const FarReach& hazard = far_hazard.unaided;
  const FarFieldSpec& spec = field.spec();
  const FieldStats& s = field.stats();
  err << "far field: 6 × " << spec.face_pixels + 1 << "² directions, " << s.evaluated_points
      << " evaluated, " << formatNumber("%.4g", static_cast<double>(s.evaluations))
      << " evaluations in " << formatDuration(s.seconds) << "; E = I/r² within "
      << formatNumber("%g", spec.tolerance) << " of the peak beyond "
      << formatNumber("%.4g", spec.far_radius_m)
      << " m (farther within 51° of the beam's direction)\n";
  const Vec3& peak = field.peak().direction;
  err << "  peak intensity " << formatNumber("%.4g", field.peak().intensity_w_sr)
      << " W/sr toward (" << formatNumber("%.4f", peak.x) << ", " << formatNumber("%.4f", peak.y)
      << ", " << formatNumber("%.4f", peak.z) << ")";
  if (hazard.nohd_m > 0.0) {
    err << "; the hazard reaches " << formatNumber("%.4g", hazard.nohd_m)
        << " m from the target centre toward (" << formatNumber("%.4f", hazard.direction.x) << ", "
        << formatNumber("%.4f", hazard.direction.y) << ", "
        << formatNumber("%.4f", hazard.direction.z) << ") (far-field NOHD)\n";
  } else {
    err << ": no direction is hazardous beyond the far radius\n";
  }
  if (far_hazard.aided) {
    const FarReach& a = *far_hazard.aided;
    err << "  through the optical aid: "
        << (a.nohd_m > 0.0 ? "the hazard reaches " + formatNumber("%.4g", a.nohd_m) +
                                 " m toward (" + formatNumber("%.4f", a.direction.x) + ", " +
                                 formatNumber("%.4f", a.direction.y) + ", " +
                                 formatNumber("%.4f", a.direction.z) + ") (aided NOHD)"
                           : std::string("no direction is hazardous beyond the far radius"))
        << "\n";
  }
  if (s.unconverged_points > 0) {
    err << "  note: " << s.unconverged_points
        << " directions did not reach the integration tolerance; intensity plus error at most "
        << formatNumber("%.3g", s.unconverged_max_upper_w_m2) << " W/sr\n";
  }
}
}  // namespace

FarField sceneFarField(const SceneTarget& target, const Scene& scene, const MemoryWatch& watch,
                       const std::string& what, std::ostream* progress_to, bool terminal,
                       PointExchange* exchange) {
  const FarFieldSpec spec = farFieldSpec(scene, target.integrator);
  std::uint64_t floor_bytes = 0;
  for (int f = 0; f < FarField::kFaces; ++f) {
    floor_bytes += fieldMemoryFloorBytes(cubeFaceSpec(f, Vec3(0.0), 1.0, spec), false);
  }
  requireWithinBudget(
      "the far field (6 × " + std::to_string(spec.face_pixels + 1) + "² directions)", floor_bytes,
      watch.budgetBytes(), "lower far_field.face_pixels, or raise --memory");

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
  return far;
}

PlaneMap planeMap(const ObserverField& field, const HazardSpec& hazard) {
  const FieldSpec& spec = field.spec();
  const auto n = spec.nodes();
  PlaneMap m;
  m.width = n[0];
  m.height = n[1];
  m.origin_m = spec.min_m;
  m.u_axis = spec.axes[0];
  m.v_axis = spec.axes[1];
  m.pixel_m = spec.voxel_m;
  const std::size_t count = static_cast<std::size_t>(n[0]) * static_cast<std::size_t>(n[1]);
  for (auto* channel : {&m.irradiance_w_m2, &m.hazard_ratio, &m.level, &m.status})
    channel->reserve(count);
  if (hazard.aid) m.aided_hazard_ratio.reserve(count);
  for (int j = 0; j < n[1]; ++j)
    for (int i = 0; i < n[0]; ++i) {
      const double e = field.irradiance(i, j, 0);
      m.irradiance_w_m2.push_back(static_cast<float>(e));
      m.hazard_ratio.push_back(static_cast<float>(hazard.ratio(e)));
      if (hazard.aid) m.aided_hazard_ratio.push_back(static_cast<float>(hazard.aidedRatio(e)));
      m.level.push_back(static_cast<float>(field.level(i, j, 0)));
      m.status.push_back(static_cast<float>(static_cast<int>(field.status(i, j, 0))));
    }
  return m;
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
  info.aid_gain = scene.hazard.aid ? scene.hazard.aid->gain : 0.0;
  return info;
}

void runField(const RunArgs& requested, std::ostream& err, PointExchange* exchange) {
  // Under MPI every rank computes the same field, sharing the points; rank 0 alone reports
  // and writes.
  const bool writer = exchange == nullptr || exchange->rank() == 0;
  RunArgs args = requested;
  if (!writer) args.quiet = true;
  Scene scene = loadScene(args.scene_path);
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
  if (writer) {
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (ec) throw OutputError(dir.string() + ": cannot create the output folder: " + ec.message());
  }
  // Opened before the work, so an unwritable folder stops the run at once (rank 0 only; the
  // other ranks' pointers stay null and they write nothing).
  std::vector<std::unique_ptr<AtomicFile>> files;
  std::vector<std::string> written;
  auto open = [&](const std::string& name) -> AtomicFile* {
    written.push_back(name);
    if (!writer) return nullptr;
    files.push_back(std::make_unique<AtomicFile>(dir / name));
    return files.back().get();
  };
  AtomicFile* summary = open("summary.json");
  AtomicFile *vdb = nullptr, *vti = nullptr, *vtu = nullptr, *vtp = nullptr;
  if (scene.observers) {
    vdb = open("irradiance.vdb");
    vti = open("irradiance.vti");
    vtu = open("blocks.vtu");
    vtp = open("target.vtp");
  }
  std::optional<StagedAmr> amr;  // irradiance.vthb and its folder, committed with the files
  if (scene.observers) written.push_back("irradiance.vthb");
  AtomicFile *far_exr = nullptr, *far_vtp = nullptr;
  if (scene.far_field.enabled) {
    far_exr = open("far_field.exr");
    far_vtp = open("far_field.vtp");
  }
  std::vector<AtomicFile*> exrs;
  for (const PlaneSpec& plane : scene.planes) exrs.push_back(open(plane.name + ".exr"));

  std::unique_ptr<tbb::global_control> thread_limit;
  if (args.threads > 0) {
    thread_limit = std::make_unique<tbb::global_control>(
        tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(args.threads));
  }

  const RunInfo info = runInfo(scene, args.scene_path, readUserFile(args.scene_path, "scene file"),
                               args.uniform ? "uniform" : "adaptive");

  const std::uint64_t budget =
      args.memory_bytes > 0 ? args.memory_bytes : defaultMemoryBudgetBytes();
  if (scene.observers) checkRegionMemory(fieldSpec(scene), "observer box", args, budget, err);
  for (const PlaneSpec& plane : scene.planes) {
    checkRegionMemory(planeFieldSpec(scene, plane), "plane " + plane.name, args, budget, err);
  }
  const MemoryWatch watch(budget);

  // Built and culled once, shared by the box and the planes.
  const SceneTarget target = sceneTarget(
      scene, scene.observers ? fieldSpec(scene) : planeFieldSpec(scene, scene.planes.front()));
  std::optional<FarField> far;
  FarHazard far_hazard;
  if (scene.far_field.enabled) {
    far.emplace(sceneFarField(target, scene, watch, "the far field", args.quiet ? nullptr : &err,
                              args.terminal, exchange));
    far_hazard = farHazard(*far, scene.hazard);
  }
  nlohmann::json j;
  // The target as the first lattice's problem describes it (all share the same one).
  const bool has_meshes = std::any_of(scene.objects.begin(), scene.objects.end(),
                                      [](const ObjectSpec& o) { return o.mesh.has_value(); });
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
      writeVti(vti->stream(), field, vtiStride(spec), info.mpe_w_m2);
      writeBlocksVtu(vtu->stream(), field, info.mpe_w_m2);
      writeTargetVtp(vtp->stream(), integrator, 2);
      amr.emplace(writeAmr(dir / "irradiance.vthb", field, info.mpe_w_m2));
    }
    const HazardZone zone = hazardZone(field, scene.hazard, targetCentre(integrator.target()));
    j = summaryJson(field, zone, info, integrator.cullStats());
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
    j = {{"program", info.program_version},
         {"scene_file", info.scene_file},
         {"scene_fnv1a64", info.scene_fnv1a64},
         {"scheme", info.scheme},
         {"integration_scheme", info.integration_scheme}};
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
      describeTarget(r.problem);
      if (!args.quiet) {
        const FieldStats& s = field.stats();
        err << "plane " << plane.name << ": " << s.nodes[0] << "×" << s.nodes[1] << " pixels at "
            << spec.voxel_m << " m, " << s.evaluated_points << " evaluated, "
            << formatNumber("%.4g", static_cast<double>(s.evaluations)) << " evaluations in "
            << formatDuration(s.seconds) << "; peak hazard ratio "
            << formatNumber("%.3g", zone.peak_ratio) << ", hazardous area "
            << formatNumber("%.4g", hazardousArea(field, zone.above_mpe)) << " m²\n";
        printUnconverged(err, s, zone, "  ");
      }
    }
    j["planes"] = planes;
  }
  if (far && writer) {
    const double mpe = info.mpe_w_m2;
    const double mu = scene.hazard.atmosphere.extinction_per_m;
    // 2:1 lat-long, about as fine as the cube faces' centres, at most 4096 × 2048 pixels.
    const int height = std::min(far->spec().face_pixels, 2048);
    const LatLongMap map =
        latLongMap(*far, height, mpe, mu, scene.hazard.aid ? mpe / scene.hazard.aid->gain : 0.0);
    std::vector<ExrChannel> channels = {{"intensity_w_sr", &map.intensity_w_sr},
                                        {"nohd_m", &map.nohd_m}};
    if (scene.hazard.aid) channels.push_back({"aided_nohd_m", &map.aided_nohd_m});
    writeLatLongExr(far_exr->stream(),
                    {map.width, map.height, far->ball().centre_m, far->spec().far_radius_m},
                    channels, {info.program_version, info.wavelength_nm, mpe});
    writeHazardSurfaceVtp(far_vtp->stream(),
                          hazardSurface(*far, std::min(far->spec().face_pixels, 128), mpe, mu));
    j["far_field"] = farFieldJson(*far, far_hazard);
    if (!args.quiet) printFarField(err, *far, far_hazard);
  }
  if (!writer) return;
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
