#pragma once
/// @file
/// @brief The files of `glint run`: the OpenVDB volume and the VTK XML files for ParaView.

#include <cstdint>
#include <ostream>
#include <string>
#include <vector>

#include "facets/integrator.h"
#include "observers/far_field.h"
#include "observers/field.h"

namespace glint {

/// @brief What the files record about the run that made them.
struct RunInfo {
  std::string program_version;
  std::string scene_file;
  std::string scene_fnv1a64;  ///< FNV-1a hash of the scene file's bytes
  std::string scheme;         ///< "adaptive" or "uniform"
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

/// @brief VTK ImageData (.vti) of the box: point data `irradiance_w_m2` (Float32, 0 where
/// not computed), `hazard_ratio` (as for the VDB), `refinement_level` and `status`, sampled
/// every @p stride lattice points.
void writeVti(std::ostream& out, const ObserverField& field, int stride, double mpe_w_m2);

/// @brief VTK UnstructuredGrid (.vtu) of the octree's final blocks as hexahedra: cell data
/// `refinement_level` and `status` (1 computed, 2 interpolated, 3 proven below the floor),
/// point data `irradiance_w_m2` (and `hazard_ratio` where @p mpe_w_m2 > 0) at the corners.
void writeBlocksVtu(std::ostream& out, const ObserverField& field, double mpe_w_m2);

/// @brief VTK PolyData (.vtp) of the lit target: its coarse facets split @p level times on the
/// true surface, cell data `incident_power_w` (beam power received) and `coarse_facet`.
void writeTargetVtp(std::ostream& out, const FacetIntegrator& integrator, int level);

/// @brief VTK PolyData (.vtp) of the far field's hazard boundary (hazardSurface()): quads,
/// point data `nohd_m` (0 where the hazard ends inside the far radius), `intensity_w_sr` and
/// `beyond_far_radius` (1 where the point lies at its hazard distance, 0 on the far radius).
void writeHazardSurfaceVtp(std::ostream& out, const HazardSurface& surface);

}  // namespace glint
