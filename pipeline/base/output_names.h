#pragma once
/// @file
/// @brief The names of the files glint writes, each spelled once here (docs/usage.md,
/// "glint run" and "Far field", and docs/batch.md describe their contents).

#include <string>
#include <vector>

namespace glint::output_names {

// glint run
inline constexpr const char* kSummary = "summary.json";
inline constexpr const char* kIrradianceVdb = "irradiance.vdb";
inline constexpr const char* kIrradianceVti = "irradiance.vti";
inline constexpr const char* kIrradianceAmr = "irradiance.vthb";  ///< and its folder irradiance/
inline constexpr const char* kBlocksVtu = "blocks.vtu";
inline constexpr const char* kTargetVtp = "target.vtp";
inline constexpr const char* kFarFieldExr = "far_field.exr";
inline constexpr const char* kFarFieldVtp = "far_field.vtp";
inline constexpr const char* kFarFieldAidedVtp = "far_field_aided.vtp";  ///< with an optical aid
inline constexpr const char* kReachExr = "reach.exr";
inline constexpr const char* kReachVtp = "reach.vtp";
/// The reach's footprint on the ground (a scene with a site and reach.footprint).
inline constexpr const char* kReachFootprintTif = "reach_footprint.tif";
inline constexpr const char* kReachFootprintGeoJson = "reach_footprint.geojson";
inline constexpr const char* kReachFootprintKml = "reach_footprint.kml";
inline constexpr const char* kEngagementVdb = "engagement.vdb";  ///< an engagement over the box
/// @brief A plane's map (glint run), and its aggregate over a study's scenarios (glint batch).
inline std::string planeExr(const std::string& plane_name) { return plane_name + ".exr"; }
/// @brief A plane's map on the site's projected map (a scene with a `site`).
inline std::string planeGeoTiff(const std::string& plane_name) { return plane_name + ".tif"; }
/// @brief A plane's hazard zones as polygons on the Earth (a scene with a `site`).
inline std::string planeZonesGeoJson(const std::string& plane_name) {
  return plane_name + "_zones.geojson";
}
inline std::string planeZonesKml(const std::string& plane_name) {
  return plane_name + "_zones.kml";
}

// Names built from a level's name (hazard.levels, the flight zones): every writer takes them
// from here, and pipeline/input/output_registry.h checks at read time that none clashes.
/// @brief A level's ratio: a column of the points table, a channel of a plane's map, an array of
/// the volumes.
inline std::string levelRatio(const std::string& level) { return level + "_ratio"; }
/// @brief A level's reach: a channel of reach.exr, a column of a study's scenarios.csv.
inline std::string levelReach(const std::string& level) { return level + "_reach_m"; }
/// @brief A level's layer of the reach's footprint (a GeoTIFF band, a polygon's name).
inline std::string levelFootprint(const std::string& level) { return level + "_reach"; }
/// @brief A footprint layer @p layer drawn at a flight altitude written @p altitude.
inline std::string footprintAtAltitude(const std::string& layer, const std::string& altitude) {
  return layer + "_at_" + altitude + "m";
}
/// @brief A level's channel of a study's coverage map: @p what is "probability", "lower" or
/// "upper" (the fraction of scenarios reaching it and its Clopper-Pearson bounds).
inline std::string levelCoverage(const std::string& level, const char* what) {
  return level + "_coverage_" + what;
}
/// @brief An engagement's columns of a level: its peak ratio and the time above it.
inline std::string levelPeakRatio(const std::string& level) { return level + "_peak_ratio"; }
inline std::string levelTimeAbove(const std::string& level) { return "time_above_" + level + "_s"; }

// glint batch: the study's folder (summary.json too) and each scenario's
inline constexpr const char* kScenariosCsv = "scenarios.csv";
inline constexpr const char* kStudyBoxVdb = "box.vdb";
inline constexpr const char* kScenariosFolder = "scenarios";
inline constexpr const char* kScenarioScene = "scene.json";
inline constexpr const char* kScenarioResult =
    "result.json";  ///< written last: the scenario is done
/// The study box's name among its lattices (the planes keep their own).
inline constexpr const char* kStudyBoxName = "box";
/// scenarios.csv's columns of one lattice (the box, or a plane): its peak and its extent, and
/// with an optical aid the same through it.
inline std::vector<std::string> studyLatticeColumns(const std::string& lattice, bool plane,
                                                    bool aided) {
  const std::string extent = plane ? "_hazardous_area_m2" : "_hazard_volume_m3";
  std::vector<std::string> columns = {lattice + "_peak_hazard_ratio", lattice + extent};
  if (aided) {
    columns.push_back(lattice + "_aided_peak_hazard_ratio");
    columns.push_back(lattice + "_aided" + extent);
  }
  return columns;
}

}  // namespace glint::output_names
