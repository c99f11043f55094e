#include "facets/detail/surface_cache.h"

#include <cmath>
#include <optional>

namespace glint::detail {
namespace {

// Pieces come from 1→4 splits of the coarse facet's barycentric triangle, so their corners are
// dyadic rationals, exact in binary: x · 2^bits is an integer, here at most `most`. Anything
// else is not memoised.
std::optional<std::uint64_t> dyadic(double x, int bits, double most) {
  const double scaled = x * static_cast<double>(std::uint64_t{1} << bits);  // exact
  if (!(scaled >= 0.0 && scaled <= most) || scaled != std::floor(scaled)) {
    return std::nullopt;
  }
  return static_cast<std::uint64_t>(scaled);
}

// A node by its coordinates (u, v) = (b₁, b₂) on the 2^-16 lattice (17 bits each).
constexpr int kNodeBits = 16;
std::optional<std::uint64_t> nodeKey(std::uint32_t coarse, const Vec3& bary) {
  if (coarse >= (std::uint32_t{1} << 30)) return std::nullopt;
  constexpr double most = 1 << kNodeBits;
  const auto u = dyadic(bary[1], kNodeBits, most), v = dyadic(bary[2], kNodeBits, most);
  if (!u || !v) return std::nullopt;
  return std::uint64_t{coarse} << 34 | *u << 17 | *v;
}

// A piece by its depth and its corners' sum (three times its centroid), which no other piece of
// that depth shares: at depth k the sum's (u, v) is a multiple of 2^-k below 3 (14 bits each
// up to depth 12).
constexpr int kMaxPieceDepth = 12;
std::optional<std::uint64_t> pieceKey(const SubFacet& f) {
  if (f.depth > kMaxPieceDepth) return std::nullopt;
  const Vec3 sum = f.bary[0] + f.bary[1] + f.bary[2];
  const double most = 3.0 * static_cast<double>(1 << f.depth);
  const auto u = dyadic(sum[1], f.depth, most), v = dyadic(sum[2], f.depth, most);
  if (!u || !v) return std::nullopt;
  return std::uint64_t{f.coarse} << 32 | std::uint64_t{f.depth} << 28 | *u << 14 | *v;
}

}  // namespace

void SurfaceCache::bind(std::uint64_t target_id) {
  if (target_id == target_id_) return;
  target_id_ = target_id;
  points_.clear();
  pieces_.clear();
}

SurfacePoint SurfaceCache::at(const SurfaceMap& map, const Vec3& bary) {
  const auto key = nodeKey(map.facet(), bary);
  if (!key) return map.at(bary);
  if (const auto it = points_.find(*key); it != points_.end()) return it->second;
  if (points_.size() >= kMaxEntries) points_.clear();
  return points_.emplace(*key, map.at(bary)).first->second;
}

PatchGeometry SurfaceCache::geometry(const Target& target, const SurfaceMap& map,
                                     const SubFacet& f) {
  const auto key = pieceKey(f);
  if (!key) return map.geometry(target, f);
  if (const auto it = pieces_.find(*key); it != pieces_.end()) return it->second;
  if (pieces_.size() >= kMaxEntries) pieces_.clear();
  return pieces_.emplace(*key, map.geometry(target, f)).first->second;
}

SubFacet SurfaceCache::subFacet(const SurfaceMap& map, const std::array<Vec3, 3>& bary,
                                std::uint8_t depth, std::uint8_t rim_edges) {
  return map.subFacet(bary, depth, rim_edges,
                      {at(map, bary[0]), at(map, bary[1]), at(map, bary[2])});
}

std::array<SubFacet, 4> SurfaceCache::split(const SurfaceMap& map, const SubFacet& f) {
  std::array<SubFacet, 4> out;
  const std::array<SurfaceMap::Child, 4> c = SurfaceMap::children(f);
  for (int k = 0; k < 4; ++k) out[k] = subFacet(map, c[k].bary, c[k].depth, c[k].rim_edges);
  return out;
}

}  // namespace glint::detail
