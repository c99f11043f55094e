#include "pipeline/report/batch_report.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>
#include <ostream>

#include "export/atomic_file.h"
#include "export/exr_map.h"
#include "export/geo_files.h"
#include "export/lattice_vdb.h"
#include "glint/version.h"
#include "pipeline/base/number_format.h"
#include "pipeline/base/output_names.h"
#include "pipeline/report/engagement_report.h"
#include "pipeline/report/run_report.h"

namespace glint {
namespace {

// Linear interpolation between order statistics (Hyndman and Fan's type 7, as numpy's default).
double quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const double h = q * static_cast<double>(v.size() - 1);
  const auto lo = static_cast<std::size_t>(std::floor(h));
  const std::size_t hi = std::min(lo + 1, v.size() - 1);
  if (v[lo] == v[hi]) return v[lo];  // +∞ beside +∞ (an unbounded reach) is +∞, not NaN
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

// A reach as a number for the quantiles: an unbounded one (null) is +∞, never 0.
double reachDistance(const nlohmann::json& entry) {
  const nlohmann::json& d = entry.at("distance_m");
  return d.is_null() ? std::numeric_limits<double>::infinity() : d.get<double>();
}

// The levels judged beside the MPE (hazard.levels), as the scenarios' reach records name them:
// every scenario of a study has the same.
std::vector<std::string> reachLevelNames(const std::map<std::size_t, nlohmann::json>& records) {
  std::vector<std::string> names;
  if (records.empty()) return names;
  const nlohmann::json& reach = records.begin()->second.at("hazard_reach");
  if (!reach.contains("levels")) return names;
  for (const auto& item : reach.at("levels").items()) names.push_back(item.key());
  return names;
}

// The study's hazard reach: quantiles of the scenarios' distances, how many are closed, and the
// farthest scenario; the aided reach's and each level's quantiles.
nlohmann::json studyReachJson(const std::map<std::size_t, nlohmann::json>& records, bool aided) {
  std::vector<double> distance, aided_distance;
  std::size_t closed = 0;
  const nlohmann::json* farthest = nullptr;
  std::size_t farthest_index = 0;
  for (const auto& [index, rec] : records) {
    const nlohmann::json& h = rec.at("hazard_reach");
    distance.push_back(reachDistance(h));
    closed += h.at("closed").get<bool>() ? 1 : 0;
    if (farthest == nullptr || distance.back() > reachDistance(*farthest)) {
      farthest = &h;
      farthest_index = index;
    }
    if (aided) aided_distance.push_back(reachDistance(h.at("aided")));
  }
  nlohmann::json j = {{"distance_m", quantilesJson(distance)},
                      {"scenarios_closed", closed},
                      {"scenarios", records.size()}};
  if (farthest != nullptr) {
    j["farthest"] = {{"scenario", farthest_index},
                     {"distance_m", farthest->at("distance_m")},
                     {"direction", farthest->at("direction")},
                     {"closed", farthest->at("closed")}};
  }
  if (aided) j["aided_distance_m"] = quantilesJson(aided_distance);
  for (const std::string& name : reachLevelNames(records)) {
    std::vector<double> level;
    std::size_t level_closed = 0;
    for (const auto& [index, rec] : records) {
      const nlohmann::json& l = rec.at("hazard_reach").at("levels").at(name);
      level.push_back(reachDistance(l));
      level_closed += l.at("closed").get<bool>() ? 1 : 0;
    }
    j["levels"][name] = {{"distance_m", quantilesJson(level)}, {"scenarios_closed", level_closed}};
  }
  return j;
}

// What the region's coverage map says with its confidence: each point's interval, and the
// region hazardous with the study's probability, bounded at that confidence over the whole map.
nlohmann::json coverageConfidenceJson(const Study& study, const StudyLattice& r, std::size_t n) {
  const SimultaneousCoverage s =
      simultaneousCoverage(r, n, study.coverage_confidence, study.coverage_probability);
  const char* unit = r.plane ? "_m2" : "_m3";
  nlohmann::json j = {
      {"confidence", study.coverage_confidence},
      {"probability", study.coverage_probability},
      {"pointwise",
       "coverage_lower and coverage_upper: each point's Clopper-Pearson interval, which "
       "holds with probability at least the confidence"},
      {"simultaneous",
       "Clopper-Pearson at 1 - (1 - confidence) / (2 points) a side (Bonferroni over the "
       "map's points): with probability at least the confidence, every point counted in "
       "the first extent is hazardous with at least the probability, and every such point "
       "is counted in the second"},
      {"points", s.points},
      {std::string("hazardous_with_probability_certainly") + unit,
       static_cast<double>(s.certain) * r.cell()},
      {std::string("hazardous_with_probability_possibly") + unit,
       static_cast<double>(s.possible) * r.cell()},
      {"scenarios_needed_at_a_point", s.certain_from_count}};
  if (r.combinations > 1) {
    // The scenarios of one jitter sample share its pointing error: each combination's are
    // trials apart from the others'.
    j["combinations"] = r.combinations;
    j["pointwise"] =
        "coverage_lower and coverage_upper: the mean over the combinations of the swept "
        "parameters of each one's Clopper-Pearson interval at (1 - confidence) / combinations "
        "(Bonferroni: the scenarios of one jitter sample share it and are not independent), "
        "which holds with probability at least the confidence";
    j["simultaneous"] =
        "the same at 1 - (1 - confidence) / (2 points) a side: with probability at least the "
        "confidence, every point counted in the first extent is hazardous with at least the "
        "probability, and every such point is counted in the second";
  }
  return j;
}

}  // namespace

std::string scenariosCsv(const std::vector<StudyLattice>& lattices,
                         const std::map<std::size_t, nlohmann::json>& records, bool far_field,
                         bool reach, bool aided) {
  std::string csv =
      "scenario,time_s,offset_x_m,offset_y_m,offset_z_m,pose_yaw_deg,pose_pitch_deg,"
      "pose_roll_deg,yaw_deg,pitch_deg,roll_deg,surface_state,sigma,specular_reflectance,jitter_"
      "sample,"
      "jitter_u_rad,jitter_v_rad";
  for (const StudyLattice& r : lattices) {
    for (const std::string& c : output_names::studyLatticeColumns(r.name, r.plane, aided))
      csv += "," + c;
  }
  if (far_field) csv += ",far_max_nohd_m,far_peak_intensity_w_sr";
  if (far_field && aided) csv += ",far_aided_max_nohd_m";
  if (reach) csv += ",reach_m,reach_closed";
  if (reach && aided) csv += ",aided_reach_m";
  const std::vector<std::string> levels =
      reach ? reachLevelNames(records) : std::vector<std::string>{};
  for (const std::string& name : levels) {
    csv += ',';
    csv += output_names::levelReach(name);
  }
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
    cell(p.contains("surface_state") ? p.at("surface_state").get<std::string>() : std::string());
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
    if (reach) {
      const nlohmann::json& h = rec.at("hazard_reach");
      // An unbounded reach (null) is written as inf: never an empty cell that reads as 0.
      cell(h.at("distance_m").is_null() ? "inf" : csvNumber(h.at("distance_m").get<double>()));
      cell(h.at("closed").get<bool>() ? "1" : "0");
      if (aided) {
        const nlohmann::json& a = h.at("aided").at("distance_m");
        cell(a.is_null() ? "inf" : csvNumber(a.get<double>()));
      }
      for (const std::string& name : levels) {
        const nlohmann::json& l = h.at("levels").at(name).at("distance_m");
        cell(l.is_null() ? "inf" : csvNumber(l.get<double>()));
      }
    }
    cell(std::to_string(rec.at("unconverged_points").get<std::int64_t>()));
    cell(std::to_string(rec.at("evaluations").get<std::int64_t>()));
    cell(formatNumber("%.3f", rec.at("seconds").get<double>()));
    row += '\n';
    csv += row;
  }
  return csv;
}

namespace {

// A study's plane map on the site's map: its channels as a GeoTIFF, and where some scenario, and
// where at least half of them, are hazardous as polygons (naked eye and aided).
void writeStudyGeoMaps(OutputSet& outputs, const std::filesystem::path& dir, const PlaneGrid& g,
                       const std::vector<ExrChannel>& channels, const StudyLattice& r,
                       const Study& study, const std::vector<float>& cover,
                       const std::vector<float>& aided_cover, const std::string& program,
                       std::size_t scenarios) {
  const HazardSpec& h = study.base.hazard;
  const SiteFrame site(*study.base.site);
  const GeoInfo info{program, r.name, hazardCitation(h), h.wavelength_nm, h.mpe_w_m2};
  std::vector<std::string> units;
  for (const ExrChannel& c : channels) {
    units.emplace_back(c.name == "max_irradiance_w_m2" ? "W/m^2" : "1");
  }
  outputs.open(dir / output_names::planeGeoTiff(r.name)).write([&](std::ostream& out) {
    writeGeoTiff(out, g, channels, units, site, info);
  });
  const auto zone = [&](const char* kind, const char* description, const std::vector<float>& p,
                        float at_least) {
    ZoneMask z{kind, description, std::vector<unsigned char>(p.size())};
    for (std::size_t i = 0; i < p.size(); ++i) z.inside[i] = p[i] >= at_least ? 1 : 0;
    return z;
  };
  // The smallest positive coverage is 1 / scenarios: anything above half of that is some.
  const auto some =
      static_cast<float>(0.5 / static_cast<double>(std::max<std::size_t>(1, scenarios)));
  std::vector<ZoneMask> zones = {
      zone("hazardous_in_some_scenario", "the MPE is reached in at least one scenario", cover,
           some),
      zone("hazardous_in_half_the_scenarios", "the MPE is reached in at least half the scenarios",
           cover, 0.5f)};
  if (h.aid) {
    zones.push_back(zone("aided_hazardous_in_some_scenario",
                         "through the optical aid, in at least one scenario", aided_cover, some));
  }
  for (const auto& [name, format] :
       {std::pair{output_names::planeZonesGeoJson(r.name), VectorFormat::GeoJson},
        std::pair{output_names::planeZonesKml(r.name), VectorFormat::Kml}}) {
    // A named copy: Clang 14 does not let a lambda capture a structured binding.
    const VectorFormat as = format;
    outputs.open(dir / name).write([&](std::ostream& out) {
      writeZones(out, as, g, zones, site, info);
    });
  }
}

}  // namespace

bool studyMapOnTheEarth(const Study& study, const StudyLattice& r) {
  if (!study.base.site || !r.plane) return false;
  const PlaneSpec& p = study.base.planes[r.plane_index];
  return mappable(p.u_axis, p.v_axis);
}

namespace {

// The arrays of a study's map beside the maximum irradiance: the largest hazard ratio, the
// coverage and its interval, the same through the aid, and each level's coverage.
struct StudyMapArrays {
  std::vector<float> max_ratio, cover, aided_max_ratio, aided_cover;
  CoverageBounds bounds, aided_bounds;
  std::vector<std::vector<float>> level_cover;
  std::vector<CoverageBounds> level_bounds;
};

StudyMapArrays studyMapArrays(const StudyLattice& r, const Study& study, std::size_t scenarios) {
  const HazardSpec& h = study.base.hazard;
  StudyMapArrays a;
  // A pose's ratio is its irradiance's, so the largest follows from the largest irradiance;
  // an engagement's worst windows were kept apart (StudyLattice::max_ratio).
  const auto largestRatio = [&](const std::vector<float>& kept, auto ratio) {
    if (r.engagement) return kept;
    std::vector<float> out(r.max_w_m2.size());
    for (std::size_t i = 0; i < out.size(); ++i)
      out[i] = static_cast<float>(ratio(static_cast<double>(r.max_w_m2[i])));
    return out;
  };
  a.max_ratio = largestRatio(r.max_ratio, [&](double e) { return h.ratio(e); });
  a.cover = coverage(r.hazardous, scenarios);
  // Each point's exact interval at the study's confidence.
  const double alpha_each_side = 0.5 * (1.0 - study.coverage_confidence);
  a.bounds = r.coverageBounds(false, scenarios, alpha_each_side);
  if (h.aid) {
    a.aided_max_ratio = largestRatio(r.aided_max_ratio, [&](double e) { return h.aidedRatio(e); });
    a.aided_cover = coverage(r.aided_hazardous, scenarios);
    a.aided_bounds = r.coverageBounds(true, scenarios, alpha_each_side);
  }
  for (std::size_t k = 0; k < h.levels.size(); ++k) {
    a.level_cover.push_back(coverage(r.level_reached.at(k), scenarios));
    a.level_bounds.push_back(r.levelCoverageBounds(k, scenarios, alpha_each_side));
  }
  return a;
}

// The map's channels with their units, in the order both files hold them.
std::vector<LatticeChannel> studyMapChannels(const StudyLattice& r, const HazardSpec& h,
                                             const StudyMapArrays& a) {
  std::vector<LatticeChannel> c = {
      {"max_irradiance_w_m2", "W/m^2", &r.max_w_m2},
      {"max_hazard_ratio",
       r.engagement ? "1 (worst window's exposure / its MPE)" : "1 (irradiance / MPE)",
       &a.max_ratio},
      {"coverage_probability", "1 (fraction of scenarios at or above the MPE)", &a.cover},
      {"coverage_lower", "1 (Clopper-Pearson lower bound at coverage_confidence)", &a.bounds.lower},
      {"coverage_upper", "1 (Clopper-Pearson upper bound at coverage_confidence)",
       &a.bounds.upper}};
  if (h.aid) {
    c.push_back(
        {"aided_max_hazard_ratio", "1 (irradiance x optical aid gain / MPE)", &a.aided_max_ratio});
    c.push_back({"aided_coverage_probability",
                 "1 (fraction of scenarios at or above the MPE through the aid)", &a.aided_cover});
    c.push_back(
        {"aided_coverage_lower", "1 (Clopper-Pearson lower bound, aided)", &a.aided_bounds.lower});
    c.push_back(
        {"aided_coverage_upper", "1 (Clopper-Pearson upper bound, aided)", &a.aided_bounds.upper});
  }
  for (std::size_t k = 0; k < h.levels.size(); ++k) {
    const std::string& name = h.levels[k].name;
    c.push_back(
        {output_names::levelCoverage(name, "probability"),
         "1 (fraction of scenarios whose irradiance reaches the " + name + " level's threshold)",
         &a.level_cover[k]});
    c.push_back({output_names::levelCoverage(name, "lower"), "1 (Clopper-Pearson lower bound)",
                 &a.level_bounds[k].lower});
    c.push_back({output_names::levelCoverage(name, "upper"), "1 (Clopper-Pearson upper bound)",
                 &a.level_bounds[k].upper});
  }
  return c;
}

}  // namespace

void writeStudyMap(OutputSet& outputs, const std::filesystem::path& path, const StudyLattice& r,
                   const Study& study, std::size_t scenarios) {
  const HazardSpec& h = study.base.hazard;
  const StudyMapArrays arrays = studyMapArrays(r, study, scenarios);
  const std::vector<LatticeChannel> channels = studyMapChannels(r, h, arrays);
  const std::string program = std::string("glint ") + GLINT_VERSION;
  AtomicFile& file = outputs.open(path);
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
    std::vector<ExrChannel> maps;
    for (const LatticeChannel& c : channels) maps.push_back({c.name, c.values});
    file.write([&](std::ostream& out) {
      writeExr(out, g, maps,
               {program, study.base.hazard.wavelength_nm, h.mpe_w_m2, hazardCitation(h)});
    });
    if (studyMapOnTheEarth(study, r)) {
      writeStudyGeoMaps(outputs, path.parent_path(), g, maps, r, study, arrays.cover,
                        arrays.aided_cover, program, scenarios);
    }
    return;
  }
  LatticeMeta meta;
  meta.strings = {{"program", program},
                  {"study_file", study.source},
                  {"study_fnv1a64", study.fnv1a64},
                  {"length_unit", "m"},
                  {"mpe_rule", hazardCitation(h)}};
  meta.numbers = {{"scenarios", static_cast<double>(scenarios)},
                  {"coverage_confidence", study.coverage_confidence},
                  {"wavelength_nm", study.base.hazard.wavelength_nm},
                  {"exposure_s", h.exposure_s},
                  {"mpe_w_m2", h.mpe_w_m2},
                  {"voxel_m", r.spec.voxel_m}};
  if (h.aid) meta.numbers["optical_aid_gain"] = h.aid->gain;
  file.write([&](std::ostream& out) { writeLatticeVdb(out, r.spec, channels, meta); });
}

namespace {

nlohmann::json precisionJson(const Study& study, const std::vector<StudyLattice>& lattices,
                             std::size_t n) {
  const double widest = widestCoverageHalfWidth(lattices, n, study.coverage_confidence);
  return {
      {"half_width", *study.precision_half_width},        {"widest_half_width", widest},
      {"reached", widest <= *study.precision_half_width}, {"confidence", study.coverage_confidence},
      {"jitter_samples", n / study.scenarios_per_sample}, {"max_samples", study.max_samples}};
}

// Scenarios whose target the beam does not light (their result.json's warnings say why).
std::vector<std::size_t> unlitScenarios(const std::map<std::size_t, nlohmann::json>& records) {
  std::vector<std::size_t> unlit;
  for (const auto& [index, rec] : records) {
    if (rec.contains("warnings") && !rec.at("warnings").empty()) unlit.push_back(index);
  }
  return unlit;
}

// Their empty maps are no evidence of safety, and the study's quantiles count them as 0.
std::string unlitWarning(const std::vector<std::size_t>& unlit, std::size_t n) {
  std::string list;
  for (std::size_t k = 0; k < unlit.size() && k < 10; ++k)
    list += (k == 0 ? "" : ", ") + std::to_string(unlit[k]);
  if (unlit.size() > 10) list += ", …";
  return "no facet of the target is lit in " + std::to_string(unlit.size()) + " of " +
         std::to_string(n) + " scenarios (" + list +
         "): nothing reflects there, so their empty maps say nothing of the hazard and are not "
         "safe ones; each one's result.json says why";
}

// One region's values over the scenarios, from their records: peak ratio and hazardous extent,
// and through the optical aid.
struct RegionSamples {
  std::vector<double> peak, extent, aided_peak, aided_extent;
  std::size_t with_hazard = 0, with_aided_hazard = 0;
};

RegionSamples regionSamples(const std::map<std::size_t, nlohmann::json>& records, std::size_t k,
                            double cell, bool aided) {
  RegionSamples s;
  for (const auto& [index, rec] : records) {
    const nlohmann::json& x = rec.at("regions")[k];
    s.peak.push_back(x.at("peak_hazard_ratio").get<double>());
    const std::int64_t points = x.at("hazardous_points").get<std::int64_t>();
    s.extent.push_back(static_cast<double>(points) * cell);
    s.with_hazard += points > 0 ? 1 : 0;
    if (aided) {
      s.aided_peak.push_back(x.at("aided_peak_hazard_ratio").get<double>());
      const std::int64_t aided_points = x.at("aided_hazardous_points").get<std::int64_t>();
      s.aided_extent.push_back(static_cast<double>(aided_points) * cell);
      s.with_aided_hazard += aided_points > 0 ? 1 : 0;
    }
  }
  return s;
}

// The lattice's points hazardous in any scenario and in half or more, and its largest
// irradiance.
struct LatticeTotals {
  std::int64_t ever = 0, half = 0;
  float max_e = 0.0f;
};

LatticeTotals latticeTotals(const StudyLattice& r, std::size_t n) {
  LatticeTotals t;
  for (std::size_t i = 0; i < r.hazardous.size(); ++i) {
    t.ever += r.hazardous[i] > 0 ? 1 : 0;
    t.half += r.hazardous[i] > 0 && 2 * static_cast<std::size_t>(r.hazardous[i]) >= n ? 1 : 0;
    t.max_e = std::max(t.max_e, r.max_w_m2[i]);
  }
  return t;
}

// Region @p k of the study (its lattice @p r) over the scenarios' @p records.
nlohmann::json regionSummaryJson(const Study& study, const StudyLattice& r, std::size_t k,
                                 const std::map<std::size_t, nlohmann::json>& records,
                                 std::size_t n) {
  const bool aided = study.base.hazard.aid.has_value();
  const RegionSamples s = regionSamples(records, k, r.cell(), aided);
  const LatticeTotals t = latticeTotals(r, n);
  const char* unit = r.plane ? "_m2" : "_m3";
  nlohmann::json a = {
      {"name", r.name},
      {"kind", r.plane ? "plane" : "box"},
      {"file", r.studyFile()},
      {"geo_files", studyMapOnTheEarth(study, r)
                        ? nlohmann::json{output_names::planeGeoTiff(r.name),
                                         output_names::planeZonesGeoJson(r.name),
                                         output_names::planeZonesKml(r.name)}
                        : nlohmann::json::array()},
      {"peak_hazard_ratio", quantilesJson(s.peak)},
      {std::string(r.plane ? "hazardous_area" : "hazard_volume") + unit, quantilesJson(s.extent)},
      {"scenarios_with_hazard", s.with_hazard},
      {"fraction_of_scenarios_with_hazard",
       n > 0 ? static_cast<double>(s.with_hazard) / static_cast<double>(n) : 0.0},
      {"max_irradiance_w_m2", t.max_e},
      {std::string("hazardous_in_any_scenario") + unit, static_cast<double>(t.ever) * r.cell()},
      {std::string("hazardous_in_half_or_more") + unit, static_cast<double>(t.half) * r.cell()},
      {"coverage_confidence", coverageConfidenceJson(study, r, n)}};
  if (aided) {
    std::int64_t aided_ever = 0;
    for (std::uint32_t c : r.aided_hazardous) aided_ever += c > 0 ? 1 : 0;
    a[std::string("aided_hazardous_in_any_scenario") + unit] =
        static_cast<double>(aided_ever) * r.cell();
    a["aided_peak_hazard_ratio"] = quantilesJson(s.aided_peak);
    a[std::string(r.plane ? "aided_hazardous_area" : "aided_hazard_volume") + unit] =
        quantilesJson(s.aided_extent);
    a["scenarios_with_aided_hazard"] = s.with_aided_hazard;
  }
  const std::vector<ExposureLevel>& levels = study.base.hazard.levels;
  for (std::size_t l = 0; l < levels.size(); ++l) {
    std::int64_t ever = 0, half = 0;
    for (const std::uint32_t c : r.level_reached.at(l)) {
      ever += c > 0 ? 1 : 0;
      half += c > 0 && 2 * static_cast<std::size_t>(c) >= n ? 1 : 0;
    }
    std::vector<double> extent;
    std::size_t with = 0;
    for (const auto& [index, rec] : records) {
      const nlohmann::json& x = rec.at("regions").at(k).at("levels").at(levels[l].name);
      extent.push_back(x.at(r.plane ? "area_m2" : "volume_m3").get<double>());
      with += x.at("points").get<std::int64_t>() > 0 ? 1 : 0;
    }
    a["levels"][levels[l].name] = {
        {std::string(r.plane ? "area" : "volume") + unit, quantilesJson(extent)},
        {"scenarios_reaching", with},
        {std::string("reached_in_any_scenario") + unit, static_cast<double>(ever) * r.cell()},
        {std::string("reached_in_half_or_more") + unit, static_cast<double>(half) * r.cell()}};
  }
  return a;
}

nlohmann::json farFieldSummaryJson(const std::map<std::size_t, nlohmann::json>& records,
                                   bool aided) {
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
  if (aided) {
    std::vector<double> aided_nohd;
    for (const auto& [index, rec] : records) {
      aided_nohd.push_back(rec.at("far_field").at("aided_max_nohd_m").get<double>());
    }
    far["aided_max_nohd_m"] = quantilesJson(aided_nohd);
  }
  return far;
}

}  // namespace

nlohmann::json batchSummaryJson(const Study& study, const std::vector<StudyLattice>& lattices,
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
      // The base scene's laser: a scenario may turn or move it (its result.json says where).
      {"laser", laserJson(study.base.laser, h)},
      {"hazard", hazardLimitsJson(h)},
      // As the scene gives them; a sweep of sigma or specular_reflectance changes the first lobe,
      // and a surface_state sweep puts one of them in the swept material's place.
      {"materials", materialsJson(study.base)}};
  if (study.precision_half_width) j["precision"] = precisionJson(study, lattices, n);
  // Each scenario integrated over the engagement: its regions' ratios are their worst windows'.
  if (study.base.engagement) j["engagement"] = engagementJson(*study.base.engagement);
  std::vector<double> evaluations, seconds;
  for (const auto& [index, rec] : records) {
    evaluations.push_back(static_cast<double>(rec.at("evaluations").get<std::int64_t>()));
    seconds.push_back(rec.at("seconds").get<double>());
  }
  j["evaluations"] = quantilesJson(evaluations);
  j["scenario_seconds"] = quantilesJson(seconds);
  const std::vector<std::size_t> unlit = unlitScenarios(records);
  j["scenarios"]["unlit"] = unlit.size();
  j["warnings"] = nlohmann::json::array();
  if (!unlit.empty()) j["warnings"].push_back(unlitWarning(unlit, n));
  nlohmann::json rs = nlohmann::json::array();
  for (std::size_t k = 0; k < lattices.size(); ++k)
    rs.push_back(regionSummaryJson(study, lattices[k], k, records, n));
  j["regions"] = rs;
  if (study.base.far_field.enabled)
    j["far_field"] = farFieldSummaryJson(records, h.aid.has_value());
  if (study.base.wantsReach()) j["hazard_reach"] = studyReachJson(records, h.aid.has_value());
  return j;
}

nlohmann::json scenarioParametersJson(const Study& study, const Scenario& s) {
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
  if (s.surface_state) p["surface_state"] = study.base.material_names.at(*s.surface_state);
  return p;
}

namespace {

// A scenario's region against each level: its peak ratio, the points that reach it and their
// area or volume (`levels`, nothing without levels).
nlohmann::json scenarioLevelsJson(const StudyLattice& r, double peak_w_m2, const HazardSpec& h,
                                  const HazardousPoints& hazardous) {
  nlohmann::json j = nlohmann::json::object();
  for (std::size_t k = 0; k < h.levels.size(); ++k) {
    const std::int64_t points = hazardous.levels.at(k);
    j["levels"][h.levels[k].name] = {
        {"peak_ratio", h.levels[k].ratio(peak_w_m2)},
        {"points", points},
        {r.plane ? "area_m2" : "volume_m3", static_cast<double>(points) * r.cell()}};
  }
  return j;
}

}  // namespace

nlohmann::json scenarioRegionJson(const StudyLattice& r, const FieldStats& st, const HazardSpec& h,
                                  const HazardousPoints& hazardous) {
  const char* extent = r.plane ? "hazardous_area_m2" : "hazard_volume_m3";
  nlohmann::json region = {{"name", r.name},
                           {"peak_hazard_ratio", h.ratio(st.peak_w_m2)},
                           {"hazardous_points", hazardous.unaided},
                           {extent, static_cast<double>(hazardous.unaided) * r.cell()},
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
    region["aided_peak_hazard_ratio"] = h.aidedRatio(st.peak_w_m2);
    region["aided_hazardous_points"] = hazardous.aided;
    region[std::string("aided_") + extent] = static_cast<double>(hazardous.aided) * r.cell();
  }
  region.update(scenarioLevelsJson(r, st.peak_w_m2, h, hazardous));
  return region;
}

nlohmann::json scenarioEngagementRegionJson(const StudyLattice& r, const EngagementRegion& region,
                                            const HazardSpec& h, const HazardousPoints& hazardous) {
  nlohmann::json j = engagementRegionJson(r.name, r.scenarioFile(), r.spec, region, h);
  // The scenario's record has its own time and names its files apart.
  j.erase("seconds");
  j.erase("file");
  double peak = 0.0, aided_peak = 0.0;
  for (const ExposureVerdict& v : region.results.verdicts) {
    peak = std::max(peak, v.ratio);
    aided_peak = std::max(aided_peak, v.aided_ratio);
  }
  const std::string extent = r.plane ? "hazardous_area_m2" : "hazard_volume_m3";
  j["peak_hazard_ratio"] = peak;
  j["hazardous_points"] = hazardous.unaided;
  j[extent] = static_cast<double>(hazardous.unaided) * r.cell();
  if (h.aid) {
    j["aided_peak_hazard_ratio"] = aided_peak;
    j["aided_hazardous_points"] = hazardous.aided;
    j["aided_" + extent] = static_cast<double>(hazardous.aided) * r.cell();
  }
  float peak_w_m2 = 0.0f;
  for (const float e : region.maps.peak_irradiance_w_m2) peak_w_m2 = std::max(peak_w_m2, e);
  j.update(scenarioLevelsJson(r, static_cast<double>(peak_w_m2), h, hazardous));
  return j;
}

RegionValues engagementValues(const EngagementRegion& region, const HazardSpec& h) {
  return {region.maps.peak_irradiance_w_m2, region.maps.hazard_ratio,
          h.aid ? region.maps.aided_hazard_ratio : std::vector<float>{}};
}

nlohmann::json scenarioFarFieldJson(const FarField& far, const FarHazard& hazard,
                                    const HazardSpec& h) {
  const Vec3& peak = far.peak().direction;
  nlohmann::json j = {{"far_radius_m", far.spec().far_radius_m},
                      {"peak_intensity_w_sr", far.peak().intensity_w_sr},
                      {"peak_intensity_basis", FarField::basisName(far.peak().basis)},
                      {"peak_direction", {peak.x, peak.y, peak.z}},
                      {"evaluations", far.stats().evaluations},
                      {"unconverged_directions", far.stats().unconverged_points}};
  j.update(farHazardJson(hazard, h));
  if (far.stats().unconverged_points > 0) {
    j["unconverged_max_intensity_plus_error_w_sr"] = far.stats().unconverged_max_upper_w_m2;
  }
  return j;
}

void printBatchSummary(std::ostream& err, const nlohmann::json& summary,
                       const std::vector<StudyLattice>& lattices,
                       const std::filesystem::path& out_dir, double wall_s) {
  const std::size_t n = summary.at("scenarios").at("count").get<std::size_t>();
  for (const nlohmann::json& w : summary.at("warnings"))
    err << "  warning: " << w.get<std::string>() << "\n";
  if (summary.contains("precision")) {
    const nlohmann::json& p = summary.at("precision");
    const bool reached = p.at("reached").get<bool>();
    err << "  " << (reached ? "precision" : "warning: precision not reached") << ": after "
        << p.at("jitter_samples").get<std::size_t>()
        << " jitter samples every point's interval is within ±"
        << formatNumber("%.3g", p.at("widest_half_width").get<double>()) << " (asked ±"
        << formatNumber("%g", p.at("half_width").get<double>()) << ")"
        << (reached ? "" : "; max_samples stopped the study: raise it for the precision asked")
        << "\n";
  }
  for (const nlohmann::json& r : summary.at("regions")) {
    const bool plane = r.at("kind") == "plane";
    const std::string unit = plane ? "_m2" : "_m3";
    const char* symbol = plane ? "m²" : "m³";
    const nlohmann::json& q = r.at("peak_hazard_ratio");
    err << "  " << r.at("name").get<std::string>() << ": peak hazard ratio median "
        << formatNumber("%.3g", q.at("median").get<double>()) << ", p95 "
        << formatNumber("%.3g", q.at("p95").get<double>()) << ", max "
        << formatNumber("%.3g", q.at("max").get<double>()) << "; hazard in "
        << r.at("scenarios_with_hazard").get<std::size_t>() << " of " << n
        << " scenarios; hazardous in any scenario "
        << formatNumber("%.4g", r.at("hazardous_in_any_scenario" + unit).get<double>()) << " "
        << symbol << "\n";
    const nlohmann::json& c = r.at("coverage_confidence");
    err << "    hazardous with probability ≥ "
        << formatNumber("%g", c.at("probability").get<double>()) << " at "
        << formatNumber("%g", 100.0 * c.at("confidence").get<double>())
        << " % confidence over the whole map: at least "
        << formatNumber("%.4g", c.at("hazardous_with_probability_certainly" + unit).get<double>())
        << ", at most "
        << formatNumber("%.4g", c.at("hazardous_with_probability_possibly" + unit).get<double>())
        << " " << symbol;
    if (c.at("scenarios_needed_at_a_point").get<std::size_t>() > n)
      err << " (" << n << " scenarios cannot prove it anywhere: more are needed)";
    err << "\n";
    if (r.contains("scenarios_with_aided_hazard")) {
      err << "    through the optical aid: peak ratio max "
          << formatNumber("%.3g", r.at("aided_peak_hazard_ratio").at("max").get<double>())
          << "; hazard in " << r.at("scenarios_with_aided_hazard").get<std::size_t>() << " of " << n
          << " scenarios; hazardous in any scenario "
          << formatNumber("%.4g", r.at("aided_hazardous_in_any_scenario" + unit).get<double>())
          << " " << symbol << "\n";
    }
  }
  if (summary.contains("hazard_reach")) {
    const nlohmann::json& h = summary.at("hazard_reach");
    const nlohmann::json& q = h.at("distance_m");
    const auto metres = [](const nlohmann::json& x) {
      return x.is_null() ? std::string("unbounded") : formatNumber("%.4g", x.get<double>()) + " m";
    };
    err << "  hazard reach: median " << metres(q.at("median")) << ", p95 " << metres(q.at("p95"))
        << ", max " << metres(q.at("max")) << "; closed in "
        << h.at("scenarios_closed").get<std::size_t>() << " of " << n << " scenarios\n";
  }
  err << "  wrote " << out_dir.string() << "/{" << output_names::kScenariosCsv << ", "
      << output_names::kSummary;
  for (const StudyLattice& r : lattices) err << ", " << r.studyFile();
  err << "} in " << formatDuration(wall_s) << "\n";
}

}  // namespace glint
