#pragma once
/// @file
/// @brief The files of `glint run`: the OpenVDB volume (the VTK XML files: export/vtk_files.h).

#include <cstdint>
#include <ostream>
#include <string>
#include <vector>

#include "observers/field.h"

namespace glint {

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
  double mpe_w_m2 = 0.0;  ///< > 0: `hazard_ratio` (irradiance / MPE) is written beside irradiance
  std::string mpe_rule;   ///< the MPE table row that applied
  /// > 0: `aided_hazard_ratio` (irradiance × gain / MPE, an optical aid's) is written too
  double aid_gain = 0.0;
};

/// @brief irradiance / MPE for each value, computed in double and stored as float.
std::vector<float> hazardRatio(const std::vector<float>& irradiance_w_m2, double mpe_w_m2);

/// @brief The grids `irradiance_w_m2`, `hazard_ratio` (irradiance / MPE, where
/// info.mpe_w_m2 > 0), `aided_hazard_ratio` (where info.aid_gain > 0 too), `refinement_level` and
/// `status` (see VoxelStatus) with the field's transform, and as file metadata the units, laser,
/// exposure and MPE, tolerance, floor, counts, program version and scene hash.
///
/// Consumes @p field (move it in as the last use of it): the grids are written one at a time
/// and each freed once written, and `hazard_ratio` is the irradiance grid divided in place
/// after that is written, so the file costs no memory beyond the field's own (a copy of the
/// irradiance grid was 1.4 GB of the 2 km example's peak).
void writeVdb(std::ostream& out, ObserverField field, const RunInfo& info);

// The VTK XML files (.vti, .vtu, .vtp, .vthb): export/vtk_files.h.

}  // namespace glint
