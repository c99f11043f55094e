#pragma once
/// @file
/// @brief Whole-lattice float arrays of an observer box as OpenVDB files: the aggregated maps of
/// `glint batch`, and the irradiance of a scenario read back when a study resumes.

#include <map>
#include <ostream>
#include <string>
#include <vector>

#include "observers/field.h"

namespace glint {

/// @brief One named float array over the lattice of a FieldSpec, indexed
/// [(k · nodes[1] + j) · nodes[0] + i] like ObserverField::irradianceLattice().
struct LatticeChannel {
  std::string name;
  std::string units;
  const std::vector<float>* values = nullptr;
};

/// @brief File metadata: strings and numbers.
struct LatticeMeta {
  std::map<std::string, std::string> strings;
  std::map<std::string, double> numbers;
};

/// @brief Writes each channel as a FloatGrid with the lattice's transform (index (i, j, k) =
/// lattice point (i, j, k)); voxels are active where the value is not 0.
/// @throw std::invalid_argument when a channel's size is not the lattice's.
void writeLatticeVdb(std::ostream& out, const FieldSpec& spec,
                     const std::vector<LatticeChannel>& channels, const LatticeMeta& meta);

/// @brief Reads the active voxels of FloatGrid @p grid_name of a VDB file onto the lattice of
/// @p spec (0 elsewhere). Voxels outside the lattice are an error.
/// @throw std::runtime_error when the file cannot be read, has no such grid, or does not fit.
std::vector<float> readLatticeVdb(const std::string& path, const std::string& grid_name,
                                  const FieldSpec& spec);

}  // namespace glint
