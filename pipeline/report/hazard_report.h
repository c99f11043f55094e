#pragma once
/// @file
/// @brief What the outputs make of the hazard (hazard/hazard.h): the terminal's line, the
/// entries of `summary.json` and `result.json`, the hazard arrays of the volumes and the plane
/// maps of the EXR files. The hazard layer itself knows no file format.

#include <nlohmann/json_fwd.hpp>
#include <string>
#include <vector>

#include "export/exr_map.h"      // PlaneMap
#include "export/field_files.h"  // ScaledArray
#include "facets/beam.h"
#include "hazard/hazard.h"

namespace glint {

/// @brief The laser as read, in one line for the terminal, so that a slip of units shows: its
/// mean power (a pulse's energy, duration and rate), wavelength, beam, position and direction,
/// e.g. "5 W at 532 nm; Gaussian beam, w 0.001 m, divergence 1 mrad; from (-300, 0, 0) m
/// toward (1, 0, 0)".
std::string laserLine(const Beam& laser, const HazardSpec& h);

/// @brief The laser as `summary.json` records it (`laser`): the same quantities, in SI units.
nlohmann::json laserJson(const Beam& laser, const HazardSpec& h);

/// @brief The limits in one line for the terminal, e.g. "MPE 50 W/m² for 10 s (default,
/// thermal)", with the pulse's MPE, the air and the aid where the scene has them.
std::string hazardLine(const HazardSpec& h);

/// @brief One level for the terminal: its label, its threshold at the eye and, where visually
/// corrected, the level and the correction.
std::string levelLine(const ExposureLevel& l);

/// @brief A level as the summary records it: its value, correction, threshold and source.
nlohmann::json levelJson(const ExposureLevel& l);

/// @brief The limits as `summary.json` and `result.json` record them (docs/hazard.md):
/// exposure, MPE and its rule, the pulse train's rules, the air, the aid.
nlohmann::json hazardLimitsJson(const HazardSpec& h);

/// @brief The far-field hazard's entries of `far_field` in the summaries: `max_nohd_m` and its
/// direction, the aided ones with an aid, and per level (`levels`) its own.
nlohmann::json farHazardJson(const FarHazard& hazard, const HazardSpec& h);

/// @brief The hazard arrays the volumes carry beside irradiance: `hazard_ratio` (per W/m²:
/// 1/MPE), with an optical aid `aided_hazard_ratio` (gain/MPE), and per level `<level>_ratio`.
std::vector<ScaledArray> hazardArrays(const HazardSpec& h);

/// @brief A plane's field as the map its EXR holds: lattice row j along v, column i along u;
/// `hazard_ratio`, (with an aid) `aided_hazard_ratio` and each level's ratio as @p h forms them.
PlaneMap planeMap(const ObserverField& field, const HazardSpec& h);

/// @brief A plane's irradiance as its map holds it (planeMap()'s `irradiance_w_m2`): the floats
/// a batch adds up, so that a scenario counts as it does read back from its map.
std::vector<float> planeIrradiance(const ObserverField& field);

/// @brief hazardLimitsJson() with, where there is a @p zone, its peak ratios and the nominal
/// hazard zone (`nominal_hazard_zone`, and `aided_nominal_hazard_zone` with an aid), and per
/// level (`levels`) its peak ratio and zone.
nlohmann::json hazardJson(const HazardSpec& h, const HazardZone* zone);

}  // namespace glint
