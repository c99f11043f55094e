#pragma once
/// @file
/// @brief Where the adaptive field keeps the candidate pieces its blocks' bounds kept: each
/// distinct piece once, the blocks holding 4-byte indices. Internal to observers/.
///
/// A block's bound splits candidate facets to tighten itself, and its children inherit and
/// mostly keep the same pieces. Stored per block, those lists were the field's memory: about
/// 400 bytes a piece, hundreds to thousands of pieces a block, tens of thousands of blocks a
/// level (4.9 GB peak on bench/scenes/cylinder_quarter.json at 0.05 m).

#include <tbb/concurrent_vector.h>

#include <array>
#include <cstdint>
#include <memory>
#include <mutex>
#include <unordered_map>

#include "facets/integrator.h"

namespace glint::field {

/// @brief An append-only set of candidate pieces, safe to intern into from many threads.
///
/// A piece is named by its coarse facet and the barycentric corners of its split path, which
/// 1→4 splitting makes exact (dyadic) numbers: the same piece reached from two blocks is the
/// same entry. Indices depend on thread scheduling; a list of indices, in order, does not.
class PiecePool {
 public:
  PiecePool();

  /// @brief The index of @p piece, adding it if it is new.
  std::uint32_t intern(const Candidate& piece);

  /// @brief The piece at @p index (from intern()); stable while the pool lives.
  [[nodiscard]] const Candidate& operator[](std::uint32_t index) const { return pieces_[index]; }

  [[nodiscard]] std::size_t size() const { return pieces_.size(); }

 private:
  struct Key {
    std::uint32_t coarse = 0;
    std::array<Vec3, 3> bary{};
    bool operator==(const Key&) const = default;
  };
  struct KeyHash {
    std::size_t operator()(const Key& k) const;
  };
  struct Shard {
    std::mutex mutex;
    std::unordered_map<Key, std::uint32_t, KeyHash> index;
  };
  static constexpr std::size_t kShards = 64;

  std::unique_ptr<std::array<Shard, kShards>> shards_;
  tbb::concurrent_vector<Candidate> pieces_;
};

}  // namespace glint::field
