#pragma once
/// @file
/// @brief What the adaptive field (observers/field_builder.cpp) and its dense twin
/// (observers/dense_field.cpp) share: the observer lattice, the per-thread grids they write, and
/// the bookkeeping of their statistics. Internal to observers/; brings in OpenVDB.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>

#include "observers/field.h"
#include "observers/field_grids.h"

namespace glint::field {

using Index3 = std::array<int, 3>;

/// The lattice points of a field: n[a] per axis, each point keyed by one integer.
struct Lattice {
  Index3 n;  ///< points per axis

  [[nodiscard]] std::uint64_t key(int i, int j, int k) const {
    return (static_cast<std::uint64_t>(i) * static_cast<std::uint64_t>(n[1]) +
            static_cast<std::uint64_t>(j)) *
               static_cast<std::uint64_t>(n[2]) +
           static_cast<std::uint64_t>(k);
  }
  [[nodiscard]] std::int64_t count() const { return static_cast<std::int64_t>(n[0]) * n[1] * n[2]; }
};

/// @brief The voxels a block of lattice points @p o .. @p o + @p size owns, as an inclusive
/// OpenVDB box: [o, o + size) per axis, and the last lattice point of an axis where the block
/// touches the lattice's end; a plane's one layer along its normal.
inline openvdb::CoordBBox ownedBox(const Index3& o, const Index3& size, const Lattice& lattice) {
  openvdb::Coord lo(o[0], o[1], o[2]), hi;
  for (int a = 0; a < 3; ++a) {
    const std::size_t sa = static_cast<std::size_t>(a);
    const int end = o[sa] + size[sa];
    hi[a] = lattice.n[sa] == 1 ? 0 : end == lattice.n[sa] - 1 ? end : end - 1;
  }
  return {lo, hi};
}

/// @brief Calls fn(origin, size) for every block of the coarsest level. A plane's lattice has
/// one layer (n[2] == 1): its blocks are squares at k = 0.
template <class Fn>
void forEachCoarseBlock(const Lattice& lattice, int size, Fn&& fn) {
  const bool flat = lattice.n[2] == 1;
  for (int i = 0; i + 1 < lattice.n[0]; i += size)
    for (int j = 0; j + 1 < lattice.n[1]; j += size)
      for (int k = 0; flat ? k == 0 : k + 1 < lattice.n[2]; k += size) fn(Index3{i, j, k}, size);
}

/// @brief A VoxelStatus as the float the status grid stores.
inline float statusCode(VoxelStatus s) { return static_cast<float>(static_cast<int>(s)); }

/// @brief @p bound_w_m2 as the least float not below it (the largest finite float for +∞ or
/// beyond), so that a bound stored in a float grid stays a bound.
inline float boundAsFloat(double bound_w_m2) {
  constexpr float kLargest = std::numeric_limits<float>::max();
  // +∞, NaN and whatever a float cannot hold: the largest float, never an ∞ in an output.
  if (!(bound_w_m2 < static_cast<double>(kLargest))) return kLargest;
  const float rounded = static_cast<float>(bound_w_m2);
  return static_cast<double>(rounded) >= bound_w_m2 ? rounded : std::nextafter(rounded, kLargest);
}

/// @brief Counts an unconverged point at @p x in @p stats and keeps its irradiance plus error
/// at lattice point @p p of @p upper (FieldGrids::upper; a NaN counts as +∞).
void noteUnconverged(FieldStats& stats, openvdb::FloatGrid::Accessor& upper,
                     const openvdb::Coord& p, const Vec3& x, double irradiance_w_m2,
                     double error_w_m2);

/// @brief Counts a point whose irradiance is not finite, remembering the first.
void noteNonFinite(FieldStats& stats, const Vec3& x);

/// @brief Empty grids for @p spec's lattice, named and placed in the world.
std::unique_ptr<FieldGrids> makeGrids(const FieldSpec& spec);

/// @brief Moves @p from into @p into. Threads write into their own grids over disjoint voxels,
/// so merging them is a union.
void mergeInto(FieldGrids& into, FieldGrids& from);

/// @brief One thread's grids with their accessors.
struct ThreadGrids {
  std::unique_ptr<FieldGrids> grids;
  openvdb::FloatGrid::Accessor irradiance;
  openvdb::FloatGrid::Accessor level;
  openvdb::FloatGrid::Accessor status;
  openvdb::FloatGrid::Accessor upper;

  explicit ThreadGrids(const FieldSpec& spec)
      : grids(makeGrids(spec)),
        irradiance(grids->irradiance->getAccessor()),
        level(grids->level->getAccessor()),
        status(grids->status->getAccessor()),
        upper(grids->upper->getAccessor()) {}
};

/// @brief Fills in the statistics read off the finished grids (active voxels, their memory).
void finishStats(const FieldGrids& grids, FieldStats& stats);

/// @brief Throws std::invalid_argument where @p spec cannot describe a lattice.
void validateFieldSpec(const FieldSpec& spec);

}  // namespace glint::field
