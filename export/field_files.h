#pragma once
/// @file
/// @brief The files of `glint run`: the OpenVDB volume (the VTK XML files: export/vtk_files.h).

#include <cstdint>
#include <ostream>
#include <string>
#include <vector>

#include "observers/field.h"

namespace glint {

/// @brief An array written beside irradiance at every point of a volume: irradiance ×
/// per_w_m2, formed in double and stored as float. Export knows no limits: pipeline/hazard
/// says which arrays a scene's hazard has (hazardArrays(): `hazard_ratio`, per_w_m2 = 1/MPE,
/// and through an optical aid `aided_hazard_ratio`, gain/MPE).
struct ScaledArray {
  std::string name;
  std::string units;  ///< recorded where the format has a place for it (VDB grid metadata)
  double per_w_m2 = 0.0;
};

/// @brief What the files record about the run that made them.
struct RunInfo {
  std::string program_version;
  std::string scene_file;
  std::string scene_fnv1a64;       ///< FNV-1a hash of the scene file's bytes
  std::string scheme;              ///< "adaptive" or "uniform"
  std::string integration_scheme;  ///< per observer: "paper", "cubature" or "lobe"
  double wavelength_nm = 0.0;
  double power_w = 0.0;
  double exposure_s = 0.0;
  double mpe_w_m2 = 0.0;            ///< recorded with exposure_s and mpe_rule where > 0
  std::string mpe_rule;             ///< the MPE table row that applied
  double optical_aid_gain = 0.0;    ///< recorded where > 0
  std::vector<ScaledArray> scaled;  ///< written beside irradiance in the volumes
};

/// @brief The grids `irradiance_w_m2`, each of info.scaled (the hazard ratios),
/// `refinement_level`, `status` (see VoxelStatus) and `irradiance_upper_w_m2` (value plus error,
/// at Unconverged points only) with the field's transform, and as file
/// metadata the units, laser, exposure and MPE, tolerance, floor, counts, program version and
/// scene hash.
///
/// Consumes @p field (move it in as the last use of it): the grids are written one at a time
/// and each freed once written, and each scaled grid is the irradiance grid rescaled in place
/// after the one before it is written (so its floats agree with irradiance × per_w_m2 to two
/// float roundings), so the file costs no memory beyond the field's own (a copy of the
/// irradiance grid was 1.4 GB of the 2 km example's peak).
void writeVdb(std::ostream& out, ObserverField field, const RunInfo& info);

// The VTK XML files (.vti, .vtu, .vtp, .vthb): export/vtk_files.h.

}  // namespace glint
