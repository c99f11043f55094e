#include "pipeline/report/run_report.h"

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

#include "glint/version.h"
#include "pipeline/base/number_format.h"
#include "pipeline/base/output_names.h"
#include "pipeline/input/json_reader.h"

namespace glint {
namespace {

// What the summary says of the points whose integration stopped short of its tolerance: where
// they are (status 5 marks each) and whether any could be hazardous.
nlohmann::json unconvergedJson(const FieldStats& s, const HazardZone& zone) {
  nlohmann::json j = {
      {"points", s.unconverged_points},
      {"box",
       {{"min_m", {s.unconverged_min_m.x, s.unconverged_min_m.y, s.unconverged_min_m.z}},
        {"max_m", {s.unconverged_max_m.x, s.unconverged_max_m.y, s.unconverged_max_m.z}}}},
      {"max_irradiance_plus_error_w_m2", s.unconverged_max_upper_w_m2},
      {"max_hazard_ratio_plus_error", zone.unconverged_ratio_upper},
      {"may_be_hazardous", zone.unconvergedMayBeHazardous()},
      // Counted in the hazard zone by their value plus error alone (ObserverField::Exceedance).
      {"counted_hazardous_points", zone.above_mpe.by_error_points}};
  if (zone.aided_above_mpe) {
    j["counted_aided_hazardous_points"] = zone.aided_above_mpe->by_error_points;
  }
  return j;
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
              : ", so none of them can be hazardous");
  if (zone.above_mpe.by_error_points > 0) {
    err << "; " << zone.above_mpe.by_error_points
        << " of them are counted hazardous by their value plus error";
  }
  err << "\n";
}

// What the summary says of the points a glint narrower than the lattice may pass unseen:
// where they are (status 6 marks each), the bound of the brightest and the lattice that
// would resolve them.
nlohmann::json narrowGlintsJson(const FieldStats& s, const HazardZone& zone) {
  const Vec3& at = s.unresolved_bound_at_m;
  return {{"points", s.unresolved_points},
          {"blocks", s.unresolved_blocks},
          {"box",
           {{"min_m", {s.unresolved_min_m.x, s.unresolved_min_m.y, s.unresolved_min_m.z}},
            {"max_m", {s.unresolved_max_m.x, s.unresolved_max_m.y, s.unresolved_max_m.z}}}},
          {"max_bound_w_m2", s.unresolved_max_bound_w_m2},
          {"max_bound_hazard_ratio", zone.narrow_glint_ratio_bound},
          {"max_bound_block_centre_m", {at.x, at.y, at.z}},
          {"blocks_without_finite_bound", s.unresolved_unbounded_blocks},
          {"resolving_voxel_m", s.unresolved_resolving_voxel_m}};
}

// One warning on the points where a glint narrower than the lattice may pass above the MPE.
void printNarrowGlints(std::ostream& err, const FieldStats& s, const HazardZone& zone,
                       const char* spacing_key) {
  if (s.unresolved_points == 0) return;
  err << "  warning: a glint narrower than the lattice may pass unseen between the points of "
      << s.unresolved_points << " voxels (status 6), within (" << s.unresolved_min_m.x << ", "
      << s.unresolved_min_m.y << ", " << s.unresolved_min_m.z << ") .. (" << s.unresolved_max_m.x
      << ", " << s.unresolved_max_m.y << ", " << s.unresolved_max_m.z << ")";
  if (s.unresolved_max_bound_w_m2 > 0.0) {
    const Vec3& at = s.unresolved_bound_at_m;
    err << ": its bound allows hazard ratio " << formatNumber("%.3g", zone.narrow_glint_ratio_bound)
        << " (block at (" << at.x << ", " << at.y << ", " << at.z << "))";
  }
  if (s.unresolved_unbounded_blocks > 0) {
    err << "; " << s.unresolved_unbounded_blocks
        << " blocks next to the target have no finite bound";
  }
  if (s.unresolved_resolving_voxel_m > 0.0) {
    err << "; " << spacing_key << " ≤ " << formatNumber("%.3g", s.unresolved_resolving_voxel_m)
        << " m resolves it";
  }
  err << "\n";
}

// One line per level beside the MPE: how much of the box (m³) or plane (m², @p cell_m2 a pixel)
// reaches it and how far from the target, or why none may still be short of proof.
void printLevelZones(std::ostream& err, const HazardSpec& h, const HazardZone& zone,
                     const char* unit, double cell_m2 = 0.0) {
  for (std::size_t k = 0; k < zone.levels.size(); ++k) {
    const HazardZone::Level& l = zone.levels[k];
    err << "  " << levelLine(h.levels.at(k)) << ": ";
    if (l.above.points == 0) {
      err << (l.narrow_glint_may_reach || l.unconverged_may_reach
                  ? "none at the lattice points, but not proven (a narrow glint or an "
                    "unconverged point may reach it)\n"
                  : "not reached\n");
      continue;
    }
    const double extent =
        cell_m2 > 0.0 ? static_cast<double>(l.above.points) * cell_m2 : l.above.volume_m3;
    err << formatNumber("%.4g", extent) << " " << unit << ", out to "
        << formatNumber("%.4g", l.above.farthest_m) << " m from the target centre, peak ratio "
        << formatNumber("%.3g", l.peak_ratio)
        << (l.above.reaches_edge ? "; it reaches the edge and may go on beyond it" : "") << "\n";
  }
}

}  // namespace

nlohmann::json runJson(const RunInfo& info) {
  return {{"program", info.program_version},
          {"scene_file", info.scene_file},
          {"scene_fnv1a64", info.scene_fnv1a64},
          {"scheme", info.scheme},
          {"integration_scheme", info.integration_scheme}};
}

nlohmann::json targetJson(const CullStats& cull) {
  return {{"coarse_facets", cull.coarse_facets}, {"lit", cull.lit},
          {"facing_away", cull.facing_away},     {"outside_beam", cull.outside_beam},
          {"shadowed", cull.shadowed},           {"degenerate", cull.degenerate},
          {"occlusion_rays", cull.occlusion}};
}

namespace {

// What a material's model is, in words: its lobes, ABg, its table and its Lambertian part.
std::string materialModel(const Material& m) {
  std::size_t lobes = m.specular_reflectance > 0.0 ? 1 : 0;
  for (const SpecularLobe& l : m.more_lobes) lobes += l.reflectance > 0.0 ? 1 : 0;
  std::string model = lobes == 0   ? ""
                      : lobes == 1 ? "Beckmann lobe"
                                   : std::to_string(lobes) + " Beckmann lobes";
  const auto add = [&model](const char* part) {
    model += model.empty() ? part : " + " + std::string(part);
  };
  if (m.abg) add("ABg");
  if (m.table) add("measured table");
  if (m.diffuse_reflectance > 0.0) add("Lambertian");
  return model.empty() ? "black (reflects nothing)" : model;
}

}  // namespace

nlohmann::json materialsJson(const Scene& scene) {
  nlohmann::json j = nlohmann::json::object();
  for (std::size_t i = 0; i < scene.materials.size(); ++i) {
    const Material& m = scene.materials[i];
    nlohmann::json lobes = nlohmann::json::array();
    // A material of ABg or a table alone has no first lobe to list.
    if (m.specular_reflectance > 0.0 || !m.more_lobes.empty() || !m.sampledOnly())
      lobes.push_back({{"reflectance", m.specular_reflectance}, {"sigma", m.lobe.sigma}});
    for (const SpecularLobe& l : m.more_lobes)
      lobes.push_back({{"reflectance", l.reflectance}, {"sigma", l.shape.sigma}});
    nlohmann::json entry = {{"model", materialModel(m)},
                            {"lobes", lobes},
                            {"diffuse_reflectance", m.diffuse_reflectance}};
    if (m.abg) {
      entry["abg"] = {{"a_per_sr", m.abg->a_per_sr},
                      {"b", m.abg->b},
                      {"g", m.abg->g},
                      {"total_integrated_scatter", m.abg->totalIntegratedScatter()}};
    }
    if (m.table) {
      const BrdfTable::Reflectance r = m.table->maxHemisphericalReflectance();
      nlohmann::json table = {
          {"nodes", {m.table->givenNodes(0), m.table->givenNodes(1), m.table->givenNodes(2)}},
          {"max_hemispherical_reflectance", r.value},
          {"at_theta_i_deg", r.theta_i_rad * 180.0 / kPi}};
      if (i < scene.material_table_files.size())
        table["file"] = scene.material_table_files[i].string();
      entry["table"] = table;
    }
    j[scene.material_names[i]] = entry;
  }
  return j;
}

nlohmann::json meshesJson(const Scene& scene, const std::vector<MeshStats>& stats) {
  nlohmann::json meshes = nlohmann::json::array();
  std::size_t k = 0;
  for (const ObjectSpec& o : scene.objects) {
    if (!o.mesh()) continue;
    const MeshStats& s = stats[k++];
    meshes.push_back({{"file", o.mesh()->file.string()},
                      {"surface", toString(o.mesh()->surface)},
                      {"triangles", s.triangles},
                      {"facets", s.facets},
                      {"degenerate_dropped", s.degenerate_dropped},
                      {"normals_computed", o.mesh()->normals_computed},
                      {"normals_repaired", s.normals_repaired},
                      {"quadric_fits", s.quadric_fits},
                      {"quadric_fit_fallbacks_to_pn", s.fit_fallbacks},
                      {"crease_edges", s.crease_edges},
                      {"open_edges", s.open_edges},
                      {"primitives_skipped", o.mesh()->primitives_skipped},
                      {"mirrored_instances", o.mesh()->mirrored_instances}});
  }
  return meshes;
}

namespace {

// "pn against quadric_fit, nagata" for each distinct surface of the scene's meshes.
std::string comparedSurfaces(const Scene& scene) {
  std::vector<std::string> pairs;
  for (const ObjectSpec& o : scene.objects) {
    if (!o.mesh()) continue;
    std::string pair = std::string(toString(o.mesh()->surface)) + " against ";
    const std::vector<MeshSurface> others = alternativeSurfaces(o.mesh()->surface);
    for (std::size_t k = 0; k < others.size(); ++k)
      pair += (k ? ", " : "") + std::string(toString(others[k]));
    if (std::find(pairs.begin(), pairs.end(), pair) == pairs.end()) pairs.push_back(pair);
  }
  std::string list;
  for (const std::string& p : pairs) list += (list.empty() ? "" : "; ") + p;
  return list;
}

// A relative change for JSON, which has no infinity: null where only the alternative is lit.
nlohmann::json changeJson(double change) {
  return std::isfinite(change) ? nlohmann::json(change) : nlohmann::json(nullptr);
}

}  // namespace

nlohmann::json surfaceCheckJson(const Scene& scene, const SurfaceModelCheck& check) {
  nlohmann::json j = {{"compared", comparedSurfaces(scene)}};
  if (!check.skipped.empty()) {
    j["skipped"] = check.skipped;
    return j;
  }
  nlohmann::json probes = nlohmann::json::array();
  for (const SurfaceProbe& p : check.probes) {
    probes.push_back({{"where", p.where},
                      {"at_m", {p.at_m.x, p.at_m.y, p.at_m.z}},
                      {"irradiance_w_m2", p.irradiance_w_m2},
                      {"alternative", p.alternative.empty() ? nlohmann::json(nullptr)
                                                            : nlohmann::json(p.alternative)},
                      {"alternative_w_m2", p.alternative_w_m2},
                      {"relative_change", changeJson(p.relativeChange())}});
  }
  j["probes"] = probes;
  j["max_relative_change"] = changeJson(check.max_relative_change);
  return j;
}

void printSurfaceCheck(std::ostream& err, const Scene& scene, const SurfaceModelCheck& check) {
  if (!scene.hasMeshes()) return;
  err << "  mesh surface (" << comparedSurfaces(scene) << "): ";
  if (!check.skipped.empty()) {
    err << "not checked: " << check.skipped << "\n";
    return;
  }
  // Below a few percent the mesh resolves the glint; beyond, its curvature is a guess.
  const auto worst = std::max_element(check.probes.begin(), check.probes.end(),
                                      [](const SurfaceProbe& a, const SurfaceProbe& b) {
                                        return a.relativeChange() < b.relativeChange();
                                      });
  const double change = worst->relativeChange();
  if (worst->alternative.empty()) {
    err << "no other surface converged at the brightest observers\n";
    return;
  }
  err << worst->alternative << " changes " << worst->where << " by "
      << (std::isfinite(change) ? formatNumber("%.2g", 100.0 * change) + " %" : "all it sees")
      << (check.probes.size() > 1 ? " (the most of " + std::to_string(check.probes.size()) + ")"
                                  : std::string())
      << ", an estimate of the tessellation's own error"
      << (change > 0.05 ? ": ask for a finer mesh, or normals from the true surface" : "") << "\n";
}

nlohmann::json volumeSummaryJson(const ObserverField& field, const HazardZone& zone,
                                 const RunInfo& info, const CullStats& cull) {
  const FieldSpec& spec = field.spec();
  const FieldStats& s = field.stats();
  nlohmann::json j = runJson(info);
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
                 {"unconverged", s.unconverged_points},
                 {"narrow_glint_unresolved", s.unresolved_points}};
  if (s.unconverged_points > 0) j["unconverged"] = unconvergedJson(s, zone);
  if (s.unresolved_points > 0) j["narrow_glints"] = narrowGlintsJson(s, zone);
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
      err << "  " << name
          << (zone.narrow_glint_may_be_hazardous
                  ? ": none at the lattice points, but not proven: see the narrow glint below\n"
                  : ": none in the box (no point reaches the MPE)\n");
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
  printLevelZones(err, scene.hazard, zone, "m³");
  printUnconverged(err, s, zone, "  ");
  printNarrowGlints(err, s, zone, "voxel_m");
  err << "  memory: " << formatNumber("%.3g", static_cast<double>(s.grid_bytes) / 1e6)
      << " MB of grids, "
      << formatNumber("%.3g", s.active_voxels > 0 ? static_cast<double>(s.grid_bytes) /
                                                        static_cast<double>(s.active_voxels)
                                                  : 0.0)
      << " bytes per active voxel\n";
}

void printPlane(std::ostream& err, const PlaneSpec& plane, const ObserverField& field,
                const HazardZone& zone, const HazardSpec& h) {
  const FieldStats& s = field.stats();
  err << "plane " << plane.name << ": " << s.nodes[0] << "×" << s.nodes[1] << " pixels at "
      << field.spec().voxel_m << " m, " << s.evaluated_points << " evaluated, "
      << formatNumber("%.4g", static_cast<double>(s.evaluations)) << " evaluations in "
      << formatDuration(s.seconds) << "; peak hazard ratio "
      << formatNumber("%.3g", zone.peak_ratio) << ", hazardous area "
      << formatNumber("%.4g", hazardousArea(field, zone.above_mpe)) << " m²\n";
  // The aided verdict beside the naked eye's: through binoculars it may be the only hazard.
  if (zone.aided_above_mpe) {
    err << "  through the optical aid (gain " << formatNumber("%.3g", h.aidGain())
        << "): peak hazard ratio " << formatNumber("%.3g", zone.aided_peak_ratio)
        << ", hazardous area " << formatNumber("%.4g", hazardousArea(field, *zone.aided_above_mpe))
        << " m²\n";
  }
  printLevelZones(err, h, zone, "m²", field.spec().voxel_m * field.spec().voxel_m);
  printUnconverged(err, s, zone, "  ");
  printNarrowGlints(err, s, zone, "pixel_m");
}

nlohmann::json planeJson(const PlaneSpec& plane, const ObserverField& field, const HazardZone& zone,
                         const HazardSpec& h) {
  const FieldStats& s = field.stats();
  const FieldSpec& spec = field.spec();
  const ObserverField::Exceedance& r = zone.above_mpe;
  nlohmann::json j = {{"name", plane.name},
                      {"file", output_names::planeExr(plane.name)},
                      {"pixels", {s.nodes[0], s.nodes[1]}},
                      {"pixel_m", spec.voxel_m},
                      {"tolerance", spec.tolerance},
                      {"floor_w_m2", spec.floor_w_m2},
                      {"points",
                       {{"evaluated", s.evaluated_points},
                        {"interpolated", s.interpolated_points},
                        {"proven_below_floor", s.below_floor_points},
                        {"inside_target", s.excluded_points},
                        {"unconverged", s.unconverged_points},
                        {"narrow_glint_unresolved", s.unresolved_points}}},
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
  for (std::size_t k = 0; k < zone.levels.size(); ++k) {
    const HazardZone::Level& l = zone.levels[k];
    nlohmann::json level = {{"peak_ratio", l.peak_ratio},
                            {"area_m2", hazardousArea(field, l.above)},
                            {"unconverged_may_reach", l.unconverged_may_reach},
                            {"unconverged_counted_points", l.above.by_error_points},
                            {"narrow_glint_may_reach", l.narrow_glint_may_reach}};
    if (l.above.points > 0) {
      level["farthest_from_target_m"] = l.above.farthest_m;
      level["farthest_at_m"] = {l.above.farthest_at_m.x, l.above.farthest_at_m.y,
                                l.above.farthest_at_m.z};
    }
    j["levels"][h.levels.at(k).name] = level;
  }
  if (s.unconverged_points > 0) j["unconverged"] = unconvergedJson(s, zone);
  if (s.unresolved_points > 0) j["narrow_glints"] = narrowGlintsJson(s, zone);
  if (r.points > 0) {
    j["hazard_farthest_from_target_m"] = r.farthest_m;
    j["hazard_farthest_at_m"] = {r.farthest_at_m.x, r.farthest_at_m.y, r.farthest_at_m.z};
  }
  return j;
}

// The spheres the far radius was checked on, outside in (verifyFarRadius()).
nlohmann::json farRadiusCheckJson(const FarRadiusCheck& check) {
  nlohmann::json spheres = nlohmann::json::array();
  for (const FarRadiusCheck::Sphere& s : check.spheres) {
    const Vec3& d = s.worst_direction;
    spheres.push_back({{"radius_m", s.radius_m},
                       {"holds", s.holds},
                       {"worst_share_of_allowance", s.worst_share},
                       {"worst_direction", {d.x, d.y, d.z}}});
  }
  return {{"directions", check.directions},
          {"spheres", spheres},
          {"evaluations", check.evaluations},
          {"seconds", check.seconds},
          {"allowance",
           "|E r^2 - I| <= tolerance x max(the brightest lattice intensity within the parallax "
           "angle lit_radius_m / (r - lit_radius_m), the lowest hazardous irradiance x r^2) + "
           "floor_w_sr"}};
}

nlohmann::json farFieldJson(const FarField& field, const FarHazard& hazard,
                            const std::vector<std::string>& files, const HazardSpec& h) {
  const FarFieldSpec& spec = field.spec();
  const FieldStats& s = field.stats();
  const Vec3& c = field.ball().centre_m;
  const Vec3& d = field.peak().direction;
  const double azimuth_deg = std::atan2(d.y, d.x) * 180.0 / kPi;
  const double elevation_deg = std::asin(std::clamp(d.z, -1.0, 1.0)) * 180.0 / kPi;
  nlohmann::json j = {
      {"files", files},
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
      {"peak_intensity_basis", FarField::basisName(field.peak().basis)},
      {"peak_intensity_is_bound", field.peak().basis != FarField::Basis::Located},
      {"lattice_peak_intensity_w_sr", field.latticePeak().intensity_w_sr},
      {"lobe_tops_located", field.located().size()},
      {"narrow_glint_blocks", field.narrowGlints().size()},
      {"peak_direction", {d.x, d.y, d.z}},
      {"peak_azimuth_deg", azimuth_deg},
      {"peak_elevation_deg", elevation_deg},
      {"beam_direction", {spec.beam_direction.x, spec.beam_direction.y, spec.beam_direction.z}},
      {"far_radius_rule", spec.far_radius_verified
                              ? "verified: the innermost of the spheres checked by direct "
                                "integration, outside in by halves from the first-order radius, "
                                "on which every direction held (far_radius_check): E r^2 within "
                                "the allowance of I at the lattice's directions, and at most I "
                                "(plus the allowance) at each located lobe top, where the near "
                                "field may still fall short of I (a cusp narrower than the "
                                "parallax: the far field over-states it there, never under)"
                              : "first order: lit_radius_m (1 + (3 + g / sigma) / tolerance), "
                                "g = max(1, 0.43 / sin(psi / 2)), psi the angle from "
                                "beam_direction: far_radius_m beyond 51 degrees, growing into "
                                "the forward cone"},
      {"first_order_far_radius_m", spec.first_order_far_radius_m},
      {"far_radius_check", farRadiusCheckJson(field.farRadiusCheck())}};
  j.update(farHazardJson(hazard, h));
  if (s.unconverged_points > 0) {
    j["unconverged_max_intensity_plus_error_w_sr"] = s.unconverged_max_upper_w_m2;
  }
  return j;
}

void printFarField(std::ostream& err, const FarField& field, const FarHazard& far_hazard,
                   const HazardSpec& h) {
  const FarReach& hazard = far_hazard.unaided;
  const FarFieldSpec& spec = field.spec();
  const FieldStats& s = field.stats();
  err << "far field: 6 × " << spec.face_pixels + 1 << "² directions, " << s.evaluated_points
      << " evaluated, " << formatNumber("%.4g", static_cast<double>(s.evaluations))
      << " evaluations in " << formatDuration(s.seconds);
  const FarRadiusCheck& check = field.farRadiusCheck();
  if (spec.far_radius_verified) {
    err << "; E = I/r² within " << formatNumber("%g", spec.tolerance)
        << " of the brightest direction in reach (or of the MPE there) beyond "
        << formatNumber("%.4g", spec.far_radius_m) << " m, checked at " << check.directions
        << " directions on " << check.spheres.size() << " spheres in "
        << formatDuration(check.seconds) << " (at the located lobe tops: E r² at most I; "
        << "first-order rule: " << formatNumber("%.4g", spec.first_order_far_radius_m) << " m)\n";
  } else {
    err << "; E = I/r² within " << formatNumber("%g", spec.tolerance) << " of the peak beyond "
        << formatNumber("%.4g", spec.far_radius_m)
        << " m (farther within 51° of the beam's direction"
        << (check.spheres.empty() ? "" : "; the check found the first sphere short of it") << ")\n";
  }
  const FarField::Peak& peak = field.peak();
  const Vec3& toward = peak.direction;
  switch (peak.basis) {
    case FarField::Basis::Located:
      err << "  peak intensity " << formatNumber("%.4g", peak.intensity_w_sr)
          << " W/sr, located toward (";
      break;
    case FarField::Basis::NarrowGlintBound:
      err << "  peak intensity at most " << formatNumber("%.4g", peak.intensity_w_sr)
          << " W/sr, a bound: a glint narrower than the map's directions may pass in "
          << field.narrowGlints().size() << " blocks, the brightest toward (";
      break;
    case FarField::Basis::Floor:
      err << "  peak intensity at most the floor, " << formatNumber("%.4g", peak.intensity_w_sr)
          << " W/sr (no direction was found above it)";
      break;
  }
  if (peak.basis != FarField::Basis::Floor) {
    err << formatNumber("%.4f", toward.x) << ", " << formatNumber("%.4f", toward.y) << ", "
        << formatNumber("%.4f", toward.z) << ")";
  }
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
  for (std::size_t k = 0; k < far_hazard.levels.size(); ++k) {
    const FarReach& a = far_hazard.levels[k];
    err << "  " << h.levels.at(k).label << ": "
        << (a.nohd_m > 0.0 ? "reached out to " + formatNumber("%.4g", a.nohd_m) + " m toward (" +
                                 formatNumber("%.4f", a.direction.x) + ", " +
                                 formatNumber("%.4f", a.direction.y) + ", " +
                                 formatNumber("%.4f", a.direction.z) + ")"
                           : std::string("not reached beyond the far radius"))
        << "\n";
  }
  if (s.unconverged_points > 0) {
    err << "  note: " << s.unconverged_points
        << " directions did not reach the integration tolerance; intensity plus error at most "
        << formatNumber("%.3g", s.unconverged_max_upper_w_m2) << " W/sr\n";
  }
}

namespace {

nlohmann::json reachEntry(const ReachSummary& r) {
  const Vec3& d = r.direction;
  nlohmann::json j = {
      {"threshold_w_m2", r.threshold_w_m2},
      {"distance_m", std::isfinite(r.distance_m) ? nlohmann::json(r.distance_m) : nlohmann::json()},
      {"direction", {d.x, d.y, d.z}},
      {"azimuth_deg", std::atan2(d.y, d.x) * 180.0 / kPi},
      {"elevation_deg", std::asin(std::clamp(d.z, -1.0, 1.0)) * 180.0 / kPi},
      {"from",
       r.distance_m > 0.0 ? (r.from_far_field ? "far field" : "lattice") : "nothing hazardous"},
      {"closed", r.closed},
      {"farthest_point_m", {r.farthest_point_m.x, r.farthest_point_m.y, r.farthest_point_m.z}},
      {"volume_m3", std::isfinite(r.volume_m3) ? nlohmann::json(r.volume_m3) : nlohmann::json()},
      {"unclassified",
       {{"half_edge_m", r.unclassified_half_edge_m},
        {"volume_m3", r.unclassified_m3},
        {"region",
         "the cube of this half-edge about the lit centre, inside the lattice's first "
         "layer: no point of it is sampled, and volume_m3 counts it hazardous"}}}};
  if (!std::isfinite(r.distance_m)) {
    j["unbounded"] = "a glint narrower than the far field's directions has no finite bound";
  }
  return j;
}

}  // namespace

nlohmann::json reachSummaryJson(const std::vector<ReachSummary>& reach, const HazardSpec& h) {
  nlohmann::json j = reachEntry(reach.at(0));
  if (h.aid) j["aided"] = reachEntry(reach.at(1));
  for (std::size_t k = 0; k < h.levels.size(); ++k) {
    nlohmann::json level = reachEntry(reach.at(h.firstLevelThreshold() + k));
    level.update(levelJson(h.levels[k]));
    j["levels"][h.levels[k].name] = level;
  }
  return j;
}

nlohmann::json reachJson(const NearReach& near, const std::vector<ReachSummary>& reach,
                         double seconds, const HazardSpec& h) {
  const ReachSpec& spec = near.spec;
  const RadialLattice& lattice = *near.faces[0].spec.radial;
  nlohmann::json j = reachSummaryJson(reach, h);
  j["centre_m"] = {spec.centre_m.x, spec.centre_m.y, spec.centre_m.z};
  j["lattice"] = {{"face_cells", spec.face_cells},
                  {"layer_ratio", spec.ratio},
                  {"layers", lattice.layers + 1},
                  {"first_layer_m", lattice.layerDistance(0)},
                  {"inner_layers", lattice.inner_layers},
                  {"near_m", spec.near_m},
                  {"last_layer_m", lattice.layerDistance(lattice.layers)},
                  {"far_radius_m", spec.far_m},
                  {"tolerance", spec.tolerance},
                  {"evaluated_points", near.evaluatedPoints()},
                  {"unresolved_points", near.unresolvedPoints()},
                  {"between_ray_points", near.betweenPoints()},
                  {"evaluations", near.evaluations()},
                  {"seconds", seconds}};
  j["rule"] =
      "per direction from the lit centre: the lattice's farthest hazardous point (at (1 - "
      "tolerance) x the threshold, or unresolved with a bound that reaches it) one layer out; "
      "between the rays the farthest of those layers of the four rays around a direction, or "
      "of a layer where a peak between them may reach the threshold (their largest plus an "
      "allowance for their concave second differences, sampled between them down to a "
      "sixteenth of their spacing where that may reach it); beyond the far radius the far "
      "field's hazard distance with its error allowance. "
      "The lattice runs from first_layer_m (even steps to near_m, the lit ball's radius, then "
      "growing by layer_ratio) and leaves out only the target's inside: the one region not "
      "classified is the cube of half-edge first_layer_m about the lit centre (unclassified)";
  return j;
}

void printReach(std::ostream& err, const NearReach& near, const std::vector<ReachSummary>& reach,
                double seconds, const HazardSpec& h, bool lit) {
  const auto line = [&](const ReachSummary& r, const char* who) {
    err << who;
    if (!std::isfinite(r.distance_m)) {
      err << "unbounded: a glint narrower than the far field's directions has no finite bound\n";
      return;
    }
    const std::string unclassified = "the " + formatNumber("%.3g", r.unclassified_m3) +
                                     " m³ cube within " +
                                     formatNumber("%.3g", r.unclassified_half_edge_m) +
                                     " m of the lit centre not classified, counted hazardous";
    if (!(r.distance_m > 0.0) && !lit) {
      err << "no verdict: the beam lights no facet of the target, so this empty reach is not a "
             "safe one (see the warning)\n";
      return;
    }
    if (!(r.distance_m > 0.0)) {
      err << "nothing is hazardous outside the target (" << unclassified << ")"
          << (r.closed ? ", closed" : ", NOT closed") << "\n";
      return;
    }
    err << formatNumber("%.4g", r.distance_m) << " m from the lit centre toward ("
        << formatNumber("%.4f", r.direction.x) << ", " << formatNumber("%.4f", r.direction.y)
        << ", " << formatNumber("%.4f", r.direction.z) << ") ("
        << (r.from_far_field ? "far field" : "lattice") << "), "
        << (r.closed ? "closed" : "NOT closed: the far radius is not verified")
        << "; hazardous volume " << formatNumber("%.3g", r.volume_m3) << " m³ (" << unclassified
        << ")\n";
  };
  line(reach.at(0), "hazard reach: ");
  if (h.aid) line(reach.at(1), "  through the optical aid: ");
  for (std::size_t k = 0; k < h.levels.size(); ++k) {
    line(reach.at(h.firstLevelThreshold() + k), ("  " + h.levels[k].label + ": ").c_str());
  }
  err << "  " << near.evaluatedPoints() << " points evaluated (" << near.betweenPoints()
      << " of them between the rays; "
      << formatNumber("%.3g", static_cast<double>(near.evaluations())) << " evaluations) in "
      << formatDuration(seconds) << ", " << near.unresolvedPoints() << " unresolved\n";
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

nlohmann::json timingJson(const PhaseClock& clock) {
  const double wall_s = clock.elapsedSeconds();
  nlohmann::json phases = nlohmann::json::array();
  double within_s = 0.0;
  for (const auto& [name, seconds] : clock.phases()) {
    phases.push_back({{"phase", name}, {"seconds", seconds}});
    within_s += seconds;
  }
  return {{"wall_seconds", wall_s},
          {"phases", phases},
          {"outside_phases_seconds", std::max(0.0, wall_s - within_s)}};
}

}  // namespace glint
