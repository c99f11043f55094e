#include "pipeline/input/output_registry.h"

#include <algorithm>
#include <cctype>
#include <map>

#include "hazard/levels.h"
#include "pipeline/base/input_error.h"
#include "pipeline/base/number_format.h"
#include "pipeline/base/output_names.h"

namespace glint {
namespace {

constexpr const char* kPointsTable = "the points table's columns";
constexpr const char* kEngagementTable = "the engagement table's columns";
constexpr const char* kPlaneMaps = "a plane map's channels";
constexpr const char* kVolumes = "the volumes' grids and arrays";
constexpr const char* kReachMap = "reach.exr's channels";
constexpr const char* kFootprint = "the reach footprint's layers";
constexpr const char* kFiles = "the run's files";
constexpr const char* kStudyColumns = "a study's scenarios.csv columns";
constexpr const char* kStudyMaps = "a study's coverage map's channels";

// OpenEXR's Imf::Name holds at most this many bytes: a longer channel name is cut short.
constexpr std::size_t kExrNameBytes = 255;

// The key that chose level @p k of @p h.levels: the flight zones come first, then the
// analyst's levels in the order of `hazard.levels`.
std::string levelKey(const HazardSpec& h, std::size_t k) {
  const std::vector<ExposureLevel> zones = flightZoneLevels(false);
  std::size_t flight = 0;
  while (flight < h.levels.size() && flight < zones.size() &&
         h.levels[flight].name == zones[flight].name) {
    ++flight;
  }
  if (k < flight) return "/hazard/flight_zones";
  return "/hazard/levels/" + std::to_string(k - flight) + "/name";
}

}  // namespace

std::vector<OutputName> outputNames(const Scene& scene) {
  const HazardSpec& h = scene.hazard;
  std::vector<OutputName> names;
  const auto own = [&](const char* place, std::string name, std::string owner) {
    names.push_back({place, std::move(name), std::move(owner), ""});
  };
  const auto chosen = [&](const char* place, std::string name, std::string owner, std::string key) {
    names.push_back({place, std::move(name), std::move(owner), std::move(key)});
  };
  const auto levels = [&](const char* place, auto&& nameOf, const char* what) {
    for (std::size_t k = 0; k < h.levels.size(); ++k) {
      chosen(place, nameOf(h.levels[k].name), "the " + h.levels[k].name + " level's " + what,
             levelKey(h, k));
    }
  };

  // glint points' table (export/points_csv.cpp, commands/points_command.cpp).
  for (const char* c :
       {"x", "y", "z", "irradiance_w_m2", "error_estimate_w_m2", "evaluations", "converged"}) {
    own(kPointsTable, c, std::string("glint's own column ") + c);
  }
  own(kPointsTable, "hazard_ratio", "the hazard ratio");
  if (h.aid) own(kPointsTable, "aided_hazard_ratio", "the aided hazard ratio");
  if (h.pulse) own(kPointsTable, "radiant_exposure_j_m2_per_pulse", "one pulse's exposure");
  levels(kPointsTable, output_names::levelRatio, "ratio");

  // An engagement's table (report/engagement_report.cpp).
  if (scene.engagement) {
    for (const char* c : {"x",
                          "y",
                          "z",
                          "exposure_j_m2",
                          "exposure_error_j_m2",
                          "peak_irradiance_w_m2",
                          "peak_time_s",
                          "time_above_mpe_s",
                          "hazard_ratio",
                          "hazard_rule",
                          "worst_window_ratio",
                          "worst_window_s",
                          "worst_window_start_s",
                          "worst_window_exposure_j_m2",
                          "worst_window_mpe_j_m2",
                          "pulses",
                          "pulse_train_ratio",
                          "effective_pulses",
                          "pulse_reduction",
                          "pulse_ratio",
                          "pulse_by_half_peak",
                          "pulse_window_s",
                          "pulse_window_exposure_j_m2",
                          "pulse_duration_s",
                          "pulse_exposure_j_m2",
                          "aided_hazard_ratio",
                          "stare_hazard_ratio",
                          "time_samples",
                          "evaluations",
                          "converged"}) {
      own(kEngagementTable, c, std::string("glint's own column ") + c);
    }
    levels(kEngagementTable, output_names::levelPeakRatio, "peak ratio");
    levels(kEngagementTable, output_names::levelTimeAbove, "time above it");
  }

  // A plane's map (export/exr_map.cpp, report/hazard_report.cpp) and the volumes (the grids
  // of observers/field_common.cpp, the arrays of report/hazard_report.cpp).
  for (const char* c : {"irradiance_w_m2", "hazard_ratio", "aided_hazard_ratio",
                        "irradiance_upper_w_m2", "level", "status"}) {
    own(kPlaneMaps, c, std::string("glint's own channel ") + c);
  }
  levels(kPlaneMaps, output_names::levelRatio, "ratio");
  for (const char* c : {"irradiance_w_m2", "refinement_level", "status", "irradiance_upper_w_m2",
                        "hazard_ratio", "aided_hazard_ratio"}) {
    own(kVolumes, c, std::string("glint's own grid ") + c);
  }
  levels(kVolumes, output_names::levelRatio, "ratio");

  // The reach's map and footprint (report/run_outputs.cpp).
  own(kReachMap, "reach_m", "the hazard reach");
  if (h.aid) own(kReachMap, "aided_reach_m", "the aided hazard reach");
  levels(kReachMap, output_names::levelReach, "reach");
  if (scene.reach.footprint) {
    std::vector<std::pair<std::string, std::string>> layers = {{"reach", ""}};
    if (h.aid) layers.emplace_back("aided_reach", "");
    for (std::size_t k = 0; k < h.levels.size(); ++k) {
      layers.emplace_back(output_names::levelFootprint(h.levels[k].name), levelKey(h, k));
    }
    for (const auto& [layer, key] : layers) {
      names.push_back({kFootprint, layer, "the " + layer + " layer", key});
    }
    const std::vector<double>& altitudes = scene.reach.footprint->flight_altitudes_m;
    for (std::size_t a = 0; a < altitudes.size(); ++a) {
      const std::string at = formatNumber("%g", altitudes[a]);
      for (const auto& [layer, key] : layers) {
        chosen(kFootprint, output_names::footprintAtAltitude(layer, at),
               "the " + layer + " layer at " + at + " m",
               "/reach/footprint/flight_altitudes_m/" + std::to_string(a));
      }
    }
  }

  // A study's scenarios.csv (report/batch_report.cpp), whose columns of each lattice carry the
  // lattice's name: a plane named "box" beside the box, or "x_aided" beside a plane "x" with an
  // aid, would repeat a column. Listed for every scene: any scene may be a study's.
  if (scene.observers) {
    for (const std::string& c :
         output_names::studyLatticeColumns(output_names::kStudyBoxName, false, h.aid.has_value()))
      own(kStudyColumns, c, "the study box's column " + c);
  }
  for (std::size_t i = 0; i < scene.planes.size(); ++i) {
    const std::string& p = scene.planes[i].name;
    for (const std::string& c : output_names::studyLatticeColumns(p, true, h.aid.has_value())) {
      chosen(kStudyColumns, c, "plane \"" + p + "\"'s study column " + c,
             "/planes/" + std::to_string(i) + "/name");
    }
  }

  // A study's coverage maps, of its box and of each plane (report/batch_report.cpp): EXR
  // channels, GeoTIFF bands and VDB grids of one set of names. Listed for every scene.
  for (const char* c : {"max_irradiance_w_m2", "max_hazard_ratio", "coverage_probability",
                        "coverage_lower", "coverage_upper"}) {
    own(kStudyMaps, c, std::string("glint's own coverage channel ") + c);
  }
  if (h.aid) {
    for (const char* c : {"aided_max_hazard_ratio", "aided_coverage_probability",
                          "aided_coverage_lower", "aided_coverage_upper"}) {
      own(kStudyMaps, c, std::string("glint's own coverage channel ") + c);
    }
  }
  for (const char* what : {"probability", "lower", "upper"}) {
    levels(
        kStudyMaps, [&](const std::string& l) { return output_names::levelCoverage(l, what); },
        (std::string("coverage ") + what).c_str());
  }

  // The run's folder (base/output_names.h).
  for (const char* f :
       {output_names::kSummary, output_names::kIrradianceVdb, output_names::kIrradianceVti,
        output_names::kIrradianceAmr, "irradiance", output_names::kBlocksVtu,
        output_names::kTargetVtp, output_names::kFarFieldExr, output_names::kFarFieldVtp,
        output_names::kFarFieldAidedVtp, output_names::kReachExr, output_names::kReachVtp,
        output_names::kReachFootprintTif, output_names::kReachFootprintGeoJson,
        output_names::kReachFootprintKml, output_names::kEngagementVdb}) {
    own(kFiles, f, std::string("glint's own ") + f);
  }
  for (std::size_t i = 0; i < scene.planes.size(); ++i) {
    const std::string& p = scene.planes[i].name;
    const std::string key = "/planes/" + std::to_string(i) + "/name";
    const std::string owner = "plane \"" + p + "\"'s ";
    chosen(kFiles, output_names::planeExr(p), owner + "map", key);
    if (scene.site) {
      chosen(kFiles, output_names::planeGeoTiff(p), owner + "GeoTIFF", key);
      chosen(kFiles, output_names::planeZonesGeoJson(p), owner + "zones", key);
      chosen(kFiles, output_names::planeZonesKml(p), owner + "zones", key);
    }
  }
  return names;
}

void requireDistinctOutputNames(const Scene& scene) {
  const std::vector<OutputName> names = outputNames(scene);
  const auto refuse = [&](const OutputName& n, const std::string& why) {
    throw InputError(scene.source + ": " + (n.key.empty() ? std::string("/") : n.key) + ": " + why);
  };
  std::map<std::pair<std::string, std::string>, const OutputName*> seen;
  for (const OutputName& n : names) {
    if (n.place != kFiles && n.name.size() > kExrNameBytes) {
      refuse(n, "\"" + n.name + "\" (" + n.owner + ") is longer than the " +
                    std::to_string(kExrNameBytes) + " bytes a map's channel may have");
    }
    std::string folded = n.name;
    if (n.place == kFiles) {
      std::transform(folded.begin(), folded.end(), folded.begin(),
                     [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    }
    const auto [at, fresh] = seen.emplace(std::make_pair(n.place, folded), &n);
    if (fresh) continue;
    const OutputName& first = *at->second;
    // Name the key of whichever the scene chose (glint's own names came first).
    const OutputName& blamed = n.key.empty() ? first : n;
    const OutputName& other = n.key.empty() ? n : first;
    refuse(blamed, "its outputs would take a name another output has: " + blamed.owner + " and " +
                       other.owner + " would both be " + n.name + " in " + n.place +
                       (n.place == kFiles && blamed.name != other.name
                            ? " (" + blamed.name + " and " + other.name +
                                  " are one file where case is not told apart)"
                            : "") +
                       "; choose another name");
  }
}

}  // namespace glint
