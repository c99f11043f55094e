#pragma once
/// @file
/// @brief The names of the files glint writes, each spelled once here (docs/usage.md,
/// "glint run" and "Far field", and docs/batch.md describe their contents).

#include <string>

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

// glint batch: the study's folder (summary.json too) and each scenario's
inline constexpr const char* kScenariosCsv = "scenarios.csv";
inline constexpr const char* kStudyBoxVdb = "box.vdb";
inline constexpr const char* kScenariosFolder = "scenarios";
inline constexpr const char* kScenarioScene = "scene.json";
inline constexpr const char* kScenarioResult =
    "result.json";  ///< written last: the scenario is done

}  // namespace glint::output_names
