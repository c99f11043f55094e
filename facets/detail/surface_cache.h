#pragma once
// A per-thread memo of the observer-independent geometry the lobe scheme asks for again and
// again, observer after observer: the surface at the dyadic nodes of its pieces (SurfaceMap::at,
// a quadric projection each) and the bound geometry of the pieces (patchGeometry, a normal cone
// and a ball each). Only the observer-dependent work is then left per observer.

#include <cstdint>
#include <unordered_map>

#include "facets/patch.h"
#include "facets/surface_map.h"
#include "facets/target.h"

namespace glint::detail {

class SurfaceCache {
 public:
  /// Binds the cache to one target (any id unique to it); a different one clears it.
  void bind(std::uint64_t target_id);

  /// map.at(bary).
  SurfacePoint at(const SurfaceMap& map, const Vec3& bary);

  /// map.geometry(target, f): the bound geometry of a piece of the surface map.
  PatchGeometry geometry(const Target& target, const SurfaceMap& map, const SubFacet& f);

  /// map.split(f), its corners from at().
  std::array<SubFacet, 4> split(const SurfaceMap& map, const SubFacet& f);

  /// map.subFacet(bary, depth, rim_edges), its corners from at().
  SubFacet subFacet(const SurfaceMap& map, const std::array<Vec3, 3>& bary, std::uint8_t depth,
                    std::uint8_t rim_edges);

 private:
  // Each memo is cleared when it reaches this many entries: about 5 MB of points and 20 MB of
  // pieces per thread at most, which holds every piece a quadric target's glints need.
  static constexpr std::size_t kMaxEntries = std::size_t{1} << 16;

  std::uint64_t target_id_ = 0;
  std::unordered_map<std::uint64_t, SurfacePoint> points_;
  std::unordered_map<std::uint64_t, PatchGeometry> pieces_;
};

}  // namespace glint::detail
