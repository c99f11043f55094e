#pragma once
/// @file
/// @brief The VTK XML files of `glint run` for ParaView, written by VTK's own writers (the VTK
/// 9.2 that Debian's paraview-dev ships with ParaView 5.11). VTK's headers stay in
/// export/vtk_files.cpp.
///
/// Every array is ZLib-compressed and inline (format "binary", base64), never in an
/// <AppendedData> section: since expat 2.6 (Debian 12's libexpat1 2.5.0-1+deb12u5) VTK's XML
/// reader fails on any appended section (VTK issue 19258), so ParaView 5.11 on an up-to-date
/// Debian 12 could not open such files.

#include <filesystem>
#include <ostream>
#include <vector>

#include "export/field_files.h"  // ScaledArray
#include "facets/integrator.h"
#include "observers/far_field.h"
#include "observers/field.h"
#include "observers/reach.h"

namespace glint {

/// @brief VTK ImageData (.vti) of the box: point data `irradiance_w_m2` (Float32, 0 where
/// not computed), each of @p scaled (Float32: the hazard ratios), `irradiance_upper_w_m2`
/// (Float32, ObserverField::upperLattice()), `refinement_level` and `status` (Int32), sampled
/// every @p stride lattice points.
/// @throw OutputError when VTK's writer fails.
void writeVti(std::ostream& out, const ObserverField& field, int stride,
              const std::vector<ScaledArray>& scaled);

/// @brief VTK UnstructuredGrid (.vtu) of the octree's final blocks as hexahedra: cell data
/// `refinement_level` and `status` (VoxelStatus: 1 evaluated, 2 interpolated, 3 proven below the
/// floor), point data `irradiance_w_m2` and each of @p scaled at the corners, Float32. A finest
/// block (every lattice point evaluated) is written as its 8 voxels.
/// @throw OutputError when VTK's writer fails.
void writeBlocksVtu(std::ostream& out, const ObserverField& field,
                    const std::vector<ScaledArray>& scaled);

/// @brief VTK PolyData (.vtp) of the lit target: its coarse facets split @p level times on the
/// true surface, cell data `incident_power_w` (Float64, beam power received) and
/// `coarse_facet` (Int32).
/// @throw OutputError when VTK's writer fails.
void writeTargetVtp(std::ostream& out, const FacetIntegrator& integrator, int level);

/// @brief VTK PolyData (.vtp) of the far field's hazard boundary (hazardSurface()): quads,
/// point data `nohd_m` (0 where the hazard ends inside the far radius), `intensity_w_sr`
/// (Float32) and `beyond_far_radius` (UInt8: 1 where the point lies at its hazard distance, 0
/// on the far radius).
/// @throw OutputError when VTK's writer fails.
void writeHazardSurfaceVtp(std::ostream& out, const HazardSurface& surface);

/// @brief VTK PolyData (.vtp) of the hazard reach's boundary (reachSurface()): quads, point data
/// `distance_m` (from the lit centre; 0 where nothing along the ray is hazardous) and
/// `hazard_ratio` (Float32: the ray's largest irradiance over the MPE).
/// @throw OutputError when VTK's writer fails.
void writeReachVtp(std::ostream& out, const ReachSurface& surface);

class OutputSet;

/// @brief An AMR data set written whole into a staging folder beside its target (a hidden
/// `.<name>.glint-<pid>-<random>` folder, which removeStaleTemporaries() knows): addTo() has an
/// OutputSet move it into place with the command's other outputs. The staging folder goes with
/// this object, and with an interrupted run.
class StagedAmr {
 public:
  StagedAmr(std::filesystem::path staging, std::filesystem::path vthb_path);
  StagedAmr(StagedAmr&& other) noexcept;
  StagedAmr& operator=(StagedAmr&&) = delete;
  StagedAmr(const StagedAmr&) = delete;
  StagedAmr& operator=(const StagedAmr&) = delete;
  ~StagedAmr();

  /// @brief Adds the block folder, then the .vthb (the index that names the blocks), to
  /// @p outputs; this object must outlive its commit.
  void addTo(OutputSet& outputs) const;

  /// @brief Moves the data set into place alone (an OutputSet of its own).
  /// @throw OutputError when a move fails; the earlier data set, if any, is then in place.
  void commit() const;

 private:
  std::filesystem::path staging_;  ///< the staging folder: `<stem>.vthb` and `<stem>/`
  std::filesystem::path target_;   ///< the .vthb's final path
  int interrupt_slot_ = -1;        ///< the staging folder goes with an interrupted run
};

/// @brief The adaptive field as a VTK overlapping AMR data set (vtkOverlappingAMR, written
/// by vtkXMLUniformGridAMRWriter): @p vthb_path (e.g. `irradiance.vthb`) and the folder of
/// ImageData blocks beside it that VTK names after its stem (`irradiance/`), point data
/// `irradiance_w_m2` and each of @p scaled, Float32, with coarse cells
/// that a finer level covers blanked (vtkAMRUtilities::BlankCells).
///
/// Levels follow the octree's resolution: level l has spacing block_voxels / 2^(l+1) voxels,
/// so a coarse block is 2 cells a side at level 0 and a final block sits at the level where
/// its shortest edge is 2 cells (an isotropic octree's own level; a block halved along some
/// axes only, at the level of its shortest edge). Level 0 is the whole box in one block; level
/// l ≥ 1 has one block per coarse block that holds final blocks of level ≥ l, the box around
/// their level-l cubes, so that every level lies inside the one below it. Every value is the
/// lattice's own (evaluated or interpolated, 0 where not computed), as in the .vti.
///
/// Bounded as the .vti is: levels are written from the coarsest while all written blocks
/// together keep under 16.7 M points and 10 000 files; the finer levels beyond are left out
/// (irradiance.vdb keeps every voxel). Level 0 is always written.
///
/// @return The staged files; nothing is in place until their commit().
/// @throw OutputError when the staging folder cannot be made or VTK's writer fails.
[[nodiscard]] StagedAmr writeAmr(const std::filesystem::path& vthb_path, const ObserverField& field,
                                 const std::vector<ScaledArray>& scaled);

/// @brief The number of AMR levels writeAmr() writes of @p field (for tests and the run's
/// summary): at most the field's resolution levels, fewer where the budget cuts them.
int amrLevels(const ObserverField& field);

}  // namespace glint
