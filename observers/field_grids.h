#pragma once
/// @file
/// @brief The OpenVDB grids of an ObserverField. Include only from .cpp files: it brings in
/// OpenVDB.

#include <openvdb/openvdb.h>

#include <array>
#include <vector>

#include "observers/field.h"

namespace glint {

/// @brief Index (i, j, k) to world: lattice point (i, j, k) of @p spec, axes and all.
openvdb::math::Transform::Ptr fieldTransform(const FieldSpec& spec);

/// @brief The active values of @p grid on the dense lattice of @p nodes points per axis,
/// indexed [(k · nodes[1] + j) · nodes[0] + i], 0 elsewhere; @p outside counts the active
/// voxels beyond the lattice, which are left out.
std::vector<float> activeOnLattice(const openvdb::FloatGrid& grid, const std::array<int, 3>& nodes,
                                   std::size_t& outside);

/// @brief All at the finest voxel size, index (i, j, k) = lattice point (i, j, k).
struct FieldGrids {
  openvdb::FloatGrid::Ptr
      irradiance;  ///< `irradiance_w_m2`: active where evaluated or interpolated
  // Float grids, though the values are small integers: Debian's python3-openvdb (and many
  // other readers) handle only float, vector and bool grids.
  openvdb::FloatGrid::Ptr level;   ///< `refinement_level`: 0 = coarsest block
  openvdb::FloatGrid::Ptr status;  ///< `status`: a VoxelStatus, background Outside
  /// `irradiance_upper_w_m2`: at Unconverged points only, their irradiance plus its error
  /// estimate (+∞ where that is not a number), what the hazard zones count them by.
  openvdb::FloatGrid::Ptr upper;
};

}  // namespace glint
