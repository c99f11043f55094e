#pragma once
/// @file
/// @brief Maps over a plane of observers as OpenEXR images (FLOAT channels: irradiance
/// overflows HALF's 65504 in any hazardous glint).

#include <ostream>
#include <string>
#include <utility>
#include <vector>

#include "facets/vec3.h"

namespace glint {

/// @brief A width × height lattice on a plane: point (i, j) lies at
/// origin_m + pixel_m (i u_axis + j v_axis).
struct PlaneGrid {
  int width = 0;   ///< lattice points along u_axis
  int height = 0;  ///< lattice points along v_axis
  Vec3 origin_m{0.0};
  Vec3 u_axis{1.0, 0.0, 0.0};  ///< unit
  Vec3 v_axis{0.0, 1.0, 0.0};  ///< unit, orthogonal to u_axis
  double pixel_m = 0.0;        ///< lattice spacing
};

/// @brief The map `glint run` writes for a plane. Arrays are indexed [j × width + i].
struct PlaneMap : PlaneGrid {
  std::vector<float> irradiance_w_m2;
  std::vector<float> hazard_ratio;        ///< irradiance / MPE
  std::vector<float> aided_hazard_ratio;  ///< irradiance × aid gain / MPE; empty without an aid
  /// Per level judged beside the MPE: its channel's name (`<level>_ratio`) and irradiance /
  /// the level's threshold.
  std::vector<std::pair<std::string, std::vector<float>>> level_ratios;
  /// The most each point may receive (ObserverField::upperLattice()): above the irradiance
  /// only where the integration stopped short or a narrower glint may pass unseen.
  std::vector<float> irradiance_upper_w_m2;
  std::vector<float> level;   ///< refinement level (0 = coarsest block)
  std::vector<float> status;  ///< VoxelStatus: why a 0 is 0 (proven below floor, ...)
  /// A plane laid over the terrain: each observer's height, local z (m); empty for a flat one.
  std::vector<float> observer_z_m;
};

/// @brief One FLOAT channel: width × height values indexed [j × width + i].
struct ExrChannel {
  std::string name;
  const std::vector<float>* values = nullptr;
};

/// @brief What the header records besides the plane's geometry.
struct ExrInfo {
  std::string program_version;
  double wavelength_nm = 0.0;
  double mpe_w_m2 = 0.0;
  std::string mpe_rule;  ///< the standard, table and row the MPE came from (empty: none)
};

/// @brief Writes @p channels over @p grid as a scanline OpenEXR image with FLOAT channels (ZIP
/// compressed). The image's top row is the plane's highest v, so viewers show v upwards. Header
/// attributes: `glint_origin_m`, `glint_u_axis`, `glint_v_axis` (V3d), `glint_pixel_m`,
/// `glint_wavelength_nm`, `glint_mpe_w_m2` (double), `glint_program` (string).
/// @throw std::invalid_argument when a channel does not hold width × height values;
/// OutputError when the stream fails.
void writeExr(std::ostream& out, const PlaneGrid& grid, const std::vector<ExrChannel>& channels,
              const ExrInfo& info);

/// @brief A map over all directions from a centre, in longitude and latitude (width = 2 ×
/// height; see latLongMap() in observers/far_field.h).
struct LatLongGrid {
  int width = 0;
  int height = 0;
  Vec3 centre_m{0.0};         ///< where the directions start
  double far_radius_m = 0.0;  ///< beyond it the map's intensity gives the irradiance
};

/// @brief Writes @p channels over @p grid as writeExr() does, with the attributes
/// `glint_projection` (string: the mapping of pixels to directions), `glint_centre_m` (V3d),
/// `glint_far_radius_m`, `glint_wavelength_nm`, `glint_mpe_w_m2` (double), `glint_program`.
void writeLatLongExr(std::ostream& out, const LatLongGrid& grid,
                     const std::vector<ExrChannel>& channels, const ExrInfo& info);

/// @brief Writes @p map with its channels `irradiance_w_m2`, `hazard_ratio`,
/// `aided_hazard_ratio` (where the map has one), each level's ratio, `irradiance_upper_w_m2`
/// (where the map has one), `level`, `status` and `observer_z_m` (over a surface); see the
/// overload above.
void writeExr(std::ostream& out, const PlaneMap& map, const ExrInfo& info);

/// @brief Reads FLOAT channel @p name of an EXR glint wrote, indexed [j × width + i] like the
/// maps it came from, and the lattice's size.
/// @throw std::runtime_error when the file cannot be read or has no such channel.
std::vector<float> readExrChannel(const std::string& path, const std::string& name, int& width,
                                  int& height);

}  // namespace glint
