#include "observers/detail/piece_pool.h"

#include <bit>

namespace glint::field {

PiecePool::PiecePool() : shards_(std::make_unique<std::array<Shard, kShards>>()) {}

std::size_t PiecePool::KeyHash::operator()(const Key& k) const {
  // A word at a time (every piece a block keeps is interned, so this runs in the bound loop):
  // each word multiplied in and its high bits folded down. + 0.0 makes -0 hash as 0, as ==
  // compares them.
  std::uint64_t h = 0x9e3779b97f4a7c15ull ^ k.coarse;
  const auto mix = [&h](std::uint64_t v) {
    h = (h ^ v) * 0xff51afd7ed558ccdull;
    h ^= h >> 32;
  };
  for (const Vec3& corner : k.bary) {
    for (int a = 0; a < 3; ++a) mix(std::bit_cast<std::uint64_t>(corner[a] + 0.0));
  }
  return static_cast<std::size_t>(h);
}

std::uint32_t PiecePool::intern(const Candidate& piece) {
  const Key key{piece.facet.coarse, piece.facet.bary};
  Shard& shard = (*shards_)[KeyHash{}(key) % kShards];
  const std::lock_guard lock(shard.mutex);
  const auto found = shard.index.find(key);
  if (found != shard.index.end()) return found->second;
  const auto index = static_cast<std::uint32_t>(pieces_.push_back(piece) - pieces_.begin());
  shard.index.emplace(key, index);
  return index;
}

}  // namespace glint::field
