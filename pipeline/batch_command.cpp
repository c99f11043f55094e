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
#include "pipeline/cluster.h"
#include "pipeline/input_error.h"
#include "pipeline/json_reader.h"
#include "pipeline/memory_budget.h"
#include "pipeline/progress.h"
#include "pipeline/run_command.h"
#include "pipeline/study.h"
#include "pipeline/target_builder.h"

namespace glint {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

// One observer lattice of the study (the box or a plane): the same in every scenario,
// since poses move the target, never the observers.
struct StudyLattice {
  std::string name;  // "box" or the plane's name
  bool plane = false;
  std::size_t plane_index = 0;
  FieldSpec spec;
  // Over the scenarios this rank has seen (rank 0, after the reduction: all of them).
  std::vector<float> max_w_m2;
  std::vector<std::uint32_t> hazardous;  // scenarios with irradiance ≥ MPE at the point

  [[nodiscard]] std::string scenarioFile() const {
    return plane ? name + ".exr" : "irradiance.vdb";
  }
  [[nodiscard]] double cell() const {  // m² of a plane's pixel, m³ of a box's voxel
    return plane ? spec.voxel_m * spec.voxel_m : spec.voxel_m * spec.voxel_m * spec.voxel_m;
  }
};

std::vector<StudyLattice> studyLattices(const Scene& base) {
  std::vector<StudyLattice> lattices;
  auto add = [&](StudyLattice r) {
    const auto n = r.spec.nodes();
    const std::size_t points = static_cast<std::size_t>(n[0]) * static_cast<std::size_t>(n[1]) *
                               static_cast<std::size_t>(n[2]);
    r.max_w_m2.assign(points, 0.0f);
    r.hazardous.assign(points, 0u);
    lattices.push_back(std::move(r));
  };
  if (base.observers) add({"box", false, 0, fieldSpec(base), {}, {}});
  for (std::size_t p = 0; p < base.planes.size(); ++p)
    add({base.planes[p].name, true, p, planeFieldSpec(base, base.planes[p]), {}, {}});
  return lattices;
}

// Adds one scenario's irradiance to a region's maximum and hazard count, and returns how many
// of its points reach the MPE. The count compares the stored float with the MPE, so a
// scenario read back from its file counts as it did when fresh.
std::int64_t accumulate(StudyLattice& r, const std::vector<float>& e_w_m2, double mpe_w_m2) {
  if (e_w_m2.size() != r.max_w_m2.size())
    throw std::logic_error("batch: a scenario's map does not fit its region's lattice");
  std::int64_t hazardous = 0;
  for (std::size_t i = 0; i < e_w_m2.size(); ++i) {
    r.max_w_m2[i] = std::max(r.max_w_m2[i], e_w_m2[i]);
    if (static_cast<double>(e_w_m2[i]) / mpe_w_m2 >= 1.0) {
      ++r.hazardous[i];
      ++hazardous;
    }
  }
  return hazardous;
}

std::string scenarioDirName(std::size_t index) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "s%06zu", index);
  return buf;
}

nlohmann::json parametersJson(const Scenario& s) {
  nlohmann::json p = {{"time_s", s.pose.time_s},
                      {"offset_m", {s.pose.offset_m.x, s.pose.offset_m.y, s.pose.offset_m.z}},
                      {"pose_yaw_deg", s.pose.yaw_deg},
                      {"pose_pitch_deg", s.pose.pitch_deg},
                      {"pose_roll_deg", s.pose.roll_deg},
                      {"yaw_deg", s.yaw_deg},
                      {"pitch_deg", s.pitch_deg},
                      {"roll_deg", s.roll_deg},
                      {"jitter_sample", s.jitter_sample},
                      {"jitter_u_rad", s.jitter_u_rad},
                      {"jitter_v_rad", s.jitter_v_rad}};
  if (s.sigma) p["sigma"] = *s.sigma;
  if (s.specular_reflectance) p["specular_reflectance"] = *s.specular_reflectance;
  return p;
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
  const fs::path dir = out_dir / "scenarios" / scenarioDirName(s.index);
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw OutputError(dir.string() + ": cannot create the scenario folder: " + ec.message());

  AtomicFile scene_file(dir / "scene.json");
  scene_file.stream() << scene_json;
  scene_file.commit();

  const RunInfo info = runInfo(scene, (dir / "scene.json").string(), scene_json, "adaptive");

  nlohmann::json record = {
      {"study_fnv1a64", study.fnv1a64}, {"scenario", s.index}, {"parameters", parametersJson(s)}};
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
    const HazardSpec& h = scene.hazard;
    const std::int64_t hazardous = accumulate(r, e, mpe);
    const char* extent = r.plane ? "hazardous_area_m2" : "hazard_volume_m3";
    nlohmann::json region = {{"name", r.name},
                             {"peak_hazard_ratio", h.ratio(st.peak_w_m2)},
                             {"hazardous_points", hazardous},
                             {extent, static_cast<double>(hazardous) * r.cell()},
                             {"evaluations", st.evaluations},
                             {"unconverged_points", st.unconverged_points},
                             // Below 1, no unconverged point of the scenario can be hazardous
                             // (aided, where there is an aid).
                             {"unconverged_max_hazard_ratio_plus_error",
                              std::max(h.ratio(st.unconverged_max_upper_w_m2),
                                       h.aidedRatio(st.unconverged_max_upper_w_m2))}};
    if (h.pulse) {
      region["peak_radiant_exposure_j_m2_per_pulse"] = h.pulseRadiantExposureJ_m2(st.peak_w_m2);
    }
    if (h.aid) {
      // As accumulate() counts: the stored float against the limit.
      const auto aided = static_cast<std::int64_t>(std::count_if(e.begin(), e.end(), [&](float x) {
        return h.aidedRatio(static_cast<double>(x)) >= 1.0;
      }));
      region["aided_peak_hazard_ratio"] = h.aidedRatio(st.peak_w_m2);
      region["aided_hazardous_points"] = aided;
      region[std::string("aided_") + extent] = static_cast<double>(aided) * r.cell();
    }
    results.push_back(std::move(region));
    evaluations += st.evaluations;
    unconverged += st.unconverged_points;
  }
  record["regions"] = results;
  if (scene.far_field.enabled) {
    const FarField far =
        sceneFarField(target, scene, watch, "scenario " + std::to_string(s.index) + ", far field",
                      nullptr, false);
    const Vec3& peak = far.peak().direction;
    record["far_field"] = {{"far_radius_m", far.spec().far_radius_m},
                           {"peak_intensity_w_sr", far.peak().intensity_w_sr},
                           {"peak_direction", {peak.x, peak.y, peak.z}},
                           {"evaluations", far.stats().evaluations},
                           {"unconverged_directions", far.stats().unconverged_points}};
    record["far_field"].update(farHazardJson(farHazard(far, scene.hazard)));
    if (far.stats().unconverged_points > 0) {
      record["far_field"]["unconverged_max_intensity_plus_error_w_sr"] =
          far.stats().unconverged_max_upper_w_m2;
    }
    evaluations += far.stats().evaluations;
  }
  record["evaluations"] = evaluations;
  record["unconverged_points"] = unconverged;
  record["seconds"] = std::chrono::duration<double>(Clock::now() - start).count();
  const std::string text = record.dump(2) + "\n";
  AtomicFile result(dir / "result.json");
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
  const fs::path dir = out_dir / "scenarios" / scenarioDirName(s.index);
  std::error_code ec;
  if (!fs::is_regular_file(dir / "result.json", ec)) return std::nullopt;
  nlohmann::json record;
  std::string fnv;
  bool matches = false;
  try {
    record = nlohmann::json::parse(readUserFile(dir / "result.json", "scenario result"));
    fnv = record.at("study_fnv1a64").get<std::string>();
    matches =
        record.at("scenario").get<std::size_t>() == s.index &&
        record.at("regions").size() == lattices.size() &&
        record.contains("far_field") == study.base.far_field.enabled &&
        // A result from before the scene had an optical aid lacks the aided figures.
        (!study.base.hazard.aid || record.at("regions").at(0).contains("aided_peak_hazard_ratio"));
  } catch (const std::exception&) {
    if (!quiet) err << "glint batch: " << (dir / "result.json").string() << " unreadable: redone\n";
    return std::nullopt;
  }
  if (fnv != study.fnv1a64) {
    if (fresh) return std::nullopt;
    throw InputError(out_dir.string() + ": holds results of another study (or of this study " +
                     "before it changed): " + (dir / "result.json").string() + " has study " + fnv +
                     ", this study is " + study.fnv1a64 +
                     ". Use --fresh to discard them, or another --out folder");
  }
  if (!matches) {
    if (!quiet)
      err << "glint batch: " << (dir / "result.json").string() << " does not match: redone\n";
    return std::nullopt;
  }
  // Maps read in full before any is added, so a damaged file leaves the aggregates untouched.
  const double mpe = study.base.hazard.mpe_w_m2;
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
  for (std::size_t i = 0; i < lattices.size(); ++i) accumulate(lattices[i], maps[i], mpe);
  return record;
}

// Linear interpolation between order statistics (Hyndman and Fan's type 7, as numpy's default).
double quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const double h = q * static_cast<double>(v.size() - 1);
  const auto lo = static_cast<std::size_t>(std::floor(h));
  const std::size_t hi = std::min(lo + 1, v.size() - 1);
  return v[lo] + (h - static_cast<double>(lo)) * (v[hi] - v[lo]);
}

nlohmann::json quantilesJson(const std::vector<double>& v) {
  double sum = 0.0;
  for (double x : v) sum += x;
  return {
      {"min", quantile(v, 0.0)},  {"p05", quantile(v, 0.05)},
      {"p25", quantile(v, 0.25)}, {"median", quantile(v, 0.5)},
      {"p75", quantile(v, 0.75)}, {"p95", quantile(v, 0.95)},
      {"max", quantile(v, 1.0)},  {"mean", v.empty() ? 0.0 : sum / static_cast<double>(v.size())}};
}

// %.10g: enough for every parameter a study file can hold, and the same text on every rank.
std::string csvNumber(double x) { return formatNumber("%.10g", x); }

std::string scenariosCsv(const std::vector<StudyLattice>& lattices,
                         const std::map<std::size_t, nlohmann::json>& records, bool far_field,
                         bool aided) {
  std::string csv =
      "scenario,time_s,offset_x_m,offset_y_m,offset_z_m,pose_yaw_deg,pose_pitch_deg,"
      "pose_roll_deg,yaw_deg,pitch_deg,roll_deg,sigma,specular_reflectance,jitter_sample,"
      "jitter_u_rad,jitter_v_rad";
  for (const StudyLattice& r : lattices) {
    const std::string extent = r.plane ? "_hazardous_area_m2" : "_hazard_volume_m3";
    csv += "," + r.name + "_peak_hazard_ratio," + r.name + extent;
    if (aided) csv += "," + r.name + "_aided_peak_hazard_ratio," + r.name + "_aided" + extent;
  }
  if (far_field) csv += ",far_max_nohd_m,far_peak_intensity_w_sr";
  if (far_field && aided) csv += ",far_aided_max_nohd_m";
  csv += ",unconverged_points,evaluations,seconds\n";
  for (const auto& [index, rec] : records) {
    const nlohmann::json& p = rec.at("parameters");
    std::string row = std::to_string(index);
    auto cell = [&row](const std::string& value) {
      row += ',';
      row += value;
    };
    auto number = [&](const nlohmann::json& x) { cell(csvNumber(x.get<double>())); };
    number(p.at("time_s"));
    for (const nlohmann::json& x : p.at("offset_m")) number(x);
    for (const char* key :
         {"pose_yaw_deg", "pose_pitch_deg", "pose_roll_deg", "yaw_deg", "pitch_deg", "roll_deg"})
      number(p.at(key));
    // Empty: as in the scene.
    for (const char* key : {"sigma", "specular_reflectance"})
      p.contains(key) ? number(p.at(key)) : cell("");
    const int sample = p.at("jitter_sample").get<int>();
    cell(sample >= 0 ? std::to_string(sample) : std::string());
    number(p.at("jitter_u_rad"));
    number(p.at("jitter_v_rad"));
    for (const nlohmann::json& r : rec.at("regions")) {
      const bool plane = r.contains("hazardous_area_m2");
      number(r.at("peak_hazard_ratio"));
      number(plane ? r.at("hazardous_area_m2") : r.at("hazard_volume_m3"));
      if (aided) {
        number(r.at("aided_peak_hazard_ratio"));
        number(plane ? r.at("aided_hazardous_area_m2") : r.at("aided_hazard_volume_m3"));
      }
    }
    if (far_field) {
      number(rec.at("far_field").at("max_nohd_m"));
      number(rec.at("far_field").at("peak_intensity_w_sr"));
      if (aided) number(rec.at("far_field").at("aided_max_nohd_m"));
    }
    cell(std::to_string(rec.at("unconverged_points").get<std::int64_t>()));
    cell(std::to_string(rec.at("evaluations").get<std::int64_t>()));
    cell(formatNumber("%.3f", rec.at("seconds").get<double>()));
    row += '\n';
    csv += row;
  }
  return csv;
}

// The coverage probability: the fraction of scenarios whose irradiance reaches the MPE here.
std::vector<float> coverage(const StudyLattice& r, std::size_t scenarios) {
  std::vector<float> c(r.hazardous.size());
  for (std::size_t i = 0; i < c.size(); ++i)
    c[i] = static_cast<float>(static_cast<double>(r.hazardous[i]) / static_cast<double>(scenarios));
  return c;
}

void writeLatticeMap(const fs::path& path, const StudyLattice& r, const Study& study,
                     std::size_t scenarios) {
  const HazardSpec& h = study.base.hazard;
  std::vector<float> max_ratio(r.max_w_m2.size());
  for (std::size_t i = 0; i < max_ratio.size(); ++i)
    max_ratio[i] = static_cast<float>(h.ratio(static_cast<double>(r.max_w_m2[i])));
  const std::vector<float> cover = coverage(r, scenarios);
  const std::string program = std::string("glint ") + GLINT_VERSION;
  AtomicFile file(path);
  if (r.plane) {
    const PlaneSpec& p = study.base.planes[r.plane_index];
    PlaneGrid g;
    const auto n = r.spec.nodes();
    g.width = n[0];
    g.height = n[1];
    g.origin_m = r.spec.min_m;
    g.u_axis = p.u_axis;
    g.v_axis = p.v_axis;
    g.pixel_m = r.spec.voxel_m;
    writeExr(file.stream(), g,
             {{"max_irradiance_w_m2", &r.max_w_m2},
              {"max_hazard_ratio", &max_ratio},
              {"coverage_probability", &cover}},
             {program, study.base.laser.wavelength_nm, h.mpe_w_m2});
  } else {
    LatticeMeta meta;
    meta.strings = {{"program", program},
                    {"study_file", study.source},
                    {"study_fnv1a64", study.fnv1a64},
                    {"length_unit", "m"},
                    {"mpe_rule", hazardCitation(h)}};
    meta.numbers = {{"scenarios", static_cast<double>(scenarios)},
                    {"wavelength_nm", study.base.laser.wavelength_nm},
                    {"exposure_s", h.exposure_s},
                    {"mpe_w_m2", h.mpe_w_m2},
                    {"voxel_m", r.spec.voxel_m}};
    writeLatticeVdb(
        file.stream(), r.spec,
        {{"max_irradiance_w_m2", "W/m^2", &r.max_w_m2},
         {"max_hazard_ratio", "1 (irradiance / MPE)", &max_ratio},
         {"coverage_probability", "1 (fraction of scenarios at or above the MPE)", &cover}},
        meta);
  }
  file.commit();
}

nlohmann::json summaryJson(const Study& study, const std::vector<StudyLattice>& lattices,
                           const std::map<std::size_t, nlohmann::json>& records,
                           std::size_t resumed, int ranks, double wall_s) {
  const HazardSpec& h = study.base.hazard;
  const std::size_t n = records.size();
  nlohmann::json j = {
      {"program", std::string("glint ") + GLINT_VERSION},
      {"study_file", study.source},
      {"study_fnv1a64", study.fnv1a64},
      {"scene_file", study.scene_path.string()},
      {"description", study.description},
      {"scenarios", {{"count", n}, {"computed", n - resumed}, {"resumed", resumed}}},
      {"ranks", ranks},
      {"wall_seconds", wall_s},
      {"hazard", hazardLimitsJson(h)}};
  std::vector<double> evaluations, seconds;
  for (const auto& [index, rec] : records) {
    evaluations.push_back(static_cast<double>(rec.at("evaluations").get<std::int64_t>()));
    seconds.push_back(rec.at("seconds").get<double>());
  }
  j["evaluations"] = quantilesJson(evaluations);
  j["scenario_seconds"] = quantilesJson(seconds);
  nlohmann::json rs = nlohmann::json::array();
  for (std::size_t k = 0; k < lattices.size(); ++k) {
    const StudyLattice& r = lattices[k];
    std::vector<double> peak, extent, aided_peak, aided_extent;
    std::size_t with_hazard = 0, with_aided_hazard = 0;
    for (const auto& [index, rec] : records) {
      const nlohmann::json& x = rec.at("regions")[k];
      peak.push_back(x.at("peak_hazard_ratio").get<double>());
      const std::int64_t points = x.at("hazardous_points").get<std::int64_t>();
      extent.push_back(static_cast<double>(points) * r.cell());
      with_hazard += points > 0 ? 1 : 0;
      if (h.aid) {
        aided_peak.push_back(x.at("aided_peak_hazard_ratio").get<double>());
        const std::int64_t aided = x.at("aided_hazardous_points").get<std::int64_t>();
        aided_extent.push_back(static_cast<double>(aided) * r.cell());
        with_aided_hazard += aided > 0 ? 1 : 0;
      }
    }
    std::int64_t ever = 0, half = 0;
    float max_e = 0.0f;
    for (std::size_t i = 0; i < r.hazardous.size(); ++i) {
      ever += r.hazardous[i] > 0 ? 1 : 0;
      half += r.hazardous[i] > 0 && 2 * static_cast<std::size_t>(r.hazardous[i]) >= n ? 1 : 0;
      max_e = std::max(max_e, r.max_w_m2[i]);
    }
    const char* unit = r.plane ? "_m2" : "_m3";
    rs.push_back(
        {{"name", r.name},
         {"kind", r.plane ? "plane" : "box"},
         {"file", r.plane ? r.name + ".exr" : "box.vdb"},
         {"peak_hazard_ratio", quantilesJson(peak)},
         {std::string(r.plane ? "hazardous_area" : "hazard_volume") + unit, quantilesJson(extent)},
         {"scenarios_with_hazard", with_hazard},
         {"fraction_of_scenarios_with_hazard",
          n > 0 ? static_cast<double>(with_hazard) / static_cast<double>(n) : 0.0},
         {"max_irradiance_w_m2", max_e},
         {std::string("hazardous_in_any_scenario") + unit, static_cast<double>(ever) * r.cell()},
         {std::string("hazardous_in_half_or_more") + unit, static_cast<double>(half) * r.cell()}});
    if (h.aid) {
      nlohmann::json& a = rs.back();
      a["aided_peak_hazard_ratio"] = quantilesJson(aided_peak);
      a[std::string(r.plane ? "aided_hazardous_area" : "aided_hazard_volume") + unit] =
          quantilesJson(aided_extent);
      a["scenarios_with_aided_hazard"] = with_aided_hazard;
    }
  }
  j["regions"] = rs;
  if (study.base.far_field.enabled) {
    std::vector<double> nohd;
    std::size_t beyond = 0;
    const nlohmann::json* farthest = nullptr;
    std::size_t farthest_index = 0;
    for (const auto& [index, rec] : records) {
      const nlohmann::json& f = rec.at("far_field");
      const double d = f.at("max_nohd_m").get<double>();
      nohd.push_back(d);
      beyond += d > 0.0 ? 1 : 0;
      if (farthest == nullptr || d > farthest->at("max_nohd_m").get<double>()) {
        farthest = &f;
        farthest_index = index;
      }
    }
    nlohmann::json far = {{"max_nohd_m", quantilesJson(nohd)},
                          {"scenarios_hazardous_beyond_far_radius", beyond}};
    if (farthest != nullptr) {
      far["farthest"] = {{"scenario", farthest_index},
                         {"max_nohd_m", farthest->at("max_nohd_m")},
                         {"direction", farthest->at("max_nohd_direction")},
                         {"far_radius_m", farthest->at("far_radius_m")}};
    }
    if (h.aid) {
      std::vector<double> aided;
      for (const auto& [index, rec] : records) {
        aided.push_back(rec.at("far_field").at("aided_max_nohd_m").get<double>());
      }
      far["aided_max_nohd_m"] = quantilesJson(aided);
    }
    j["far_field"] = far;
  }
  return j;
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
  // Each region keeps two dense maps over the scenarios (float maximum, uint32 count) besides
  // one scenario's field at a time.
  const std::uint64_t budget =
      args.memory_bytes > 0 ? args.memory_bytes : defaultMemoryBudgetBytes();
  std::uint64_t floor_bytes = 0;
  for (const StudyLattice& r : lattices) {
    const std::array<int, 3> n = r.spec.nodes();
    floor_bytes += 8 * static_cast<std::uint64_t>(n[0]) * static_cast<std::uint64_t>(n[1]) *
                       static_cast<std::uint64_t>(n[2]) +
                   fieldMemoryFloorBytes(r.spec, false);
  }
  requireWithinBudget("the study's regions (" + std::to_string(lattices.size()) + ")", floor_bytes,
                      budget,
                      "coarsen the base scene's voxel_m or pixel_m, shrink its regions, or "
                      "raise --memory");
  const MemoryWatch watch(budget);
  std::map<std::size_t, nlohmann::json> records;  // rank 0: every scenario's result
  std::vector<std::size_t> todo;
  std::size_t resumed = 0;
  if (root) {
    std::error_code ec;
    if (args.fresh) fs::remove_all(out_dir / "scenarios", ec);
    fs::create_directories(out_dir / "scenarios", ec);
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
          << "; scenario folders in " << (out_dir / "scenarios").string() << "\n";
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
  }
  if (!root) return;

  const std::size_t n = study.scenarios.size();
  AtomicFile csv(out_dir / "scenarios.csv");
  csv.stream() << scenariosCsv(lattices, records, study.base.far_field.enabled,
                               study.base.hazard.aid.has_value());
  csv.commit();
  for (const StudyLattice& r : lattices)
    writeLatticeMap(out_dir / (r.plane ? r.name + ".exr" : "box.vdb"), r, study, n);
  const double wall_s = std::chrono::duration<double>(Clock::now() - wall_start).count();
  const nlohmann::json summary =
      summaryJson(study, lattices, records, resumed, cluster.size(), wall_s);
  AtomicFile summary_file(out_dir / "summary.json");
  summary_file.stream() << summary.dump(2) << "\n";
  summary_file.commit();
  if (!talk) return;
  for (const nlohmann::json& r : summary.at("regions")) {
    const bool plane = r.at("kind") == "plane";
    const char* unit = plane ? "m²" : "m³";
    const nlohmann::json& q = r.at("peak_hazard_ratio");
    err << "  " << r.at("name").get<std::string>() << ": peak hazard ratio median "
        << formatNumber("%.3g", q.at("median").get<double>()) << ", p95 "
        << formatNumber("%.3g", q.at("p95").get<double>()) << ", max "
        << formatNumber("%.3g", q.at("max").get<double>()) << "; hazard in "
        << r.at("scenarios_with_hazard").get<std::size_t>() << " of " << n
        << " scenarios; hazardous in any scenario "
        << formatNumber(
               "%.4g", r.at(plane ? "hazardous_in_any_scenario_m2" : "hazardous_in_any_scenario_m3")
                           .get<double>())
        << " " << unit << "\n";
  }
  err << "  wrote " << out_dir.string() << "/{scenarios.csv, summary.json";
  for (const StudyLattice& r : lattices) err << ", " << (r.plane ? r.name + ".exr" : "box.vdb");
  err << "} in " << formatDuration(wall_s) << "\n";
}

}  // namespace glint
