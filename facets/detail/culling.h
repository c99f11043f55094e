#pragma once
// The observer-independent culling of FacetIntegrator (culling.cpp): which coarse facets no
// observer can receive light from, bounds over runs of the lit ones, and the visibility ray
// between a facet and an observer.

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "facets/integrator.h"
#include "facets/patch.h"

namespace glint {

class Occluder;

// A hierarchy of bounds over the lit facets, in their order: an observer that sees every lit
// facet (glint points) receives light from few of a mesh's thousands, and a node whose bound is
// 0 for it rules out all its facets at once, where each would have cost a bound of its own.
// Nodes never mix objects (each has its frame, beam and material). Level 0 groups kLeaf
// consecutive facets; each level above pairs the one below. A node's geometry holds its
// facets' own (the candidates' and their surface maps': ball, normal cone, area bound), so its
// bound is at least any of theirs, and 0 only where each of theirs is.
struct LitClusters {
  static constexpr std::uint32_t kLeaf = 8;
  struct Node {
    PatchGeometry geometry;  // centre, normal, radius, cone and area bound only
    std::uint32_t object = 0;
    bool mixed = false;  // spans two objects: never bounded, always opened
  };
  std::vector<std::vector<Node>> levels;  // levels[0]: runs of kLeaf facets of lit_
};

namespace detail {

// Whether the observer sees the candidate's centre past the rest of the target (an occluder is
// given only where the target can shadow itself).
bool visiblePastOccluder(const Occluder& occluder, const Target& target, const Candidate& c,
                         const Vec3& observer_m);
inline bool visible(const Occluder* occluder, const Target& target, const Candidate& c,
                    const Vec3& observer_m) {
  return occluder == nullptr || visiblePastOccluder(*occluder, target, c, observer_m);
}

// Calls visit(c) for each of @p lit (the candidates the clusters were built over) in their
// order, but not for those under a node that dark(node) rules out (asked only of nodes within
// one object).
template <class Dark, class Visit>
void forEachLitCandidate(const LitClusters& clusters, std::span<const Candidate> lit, Dark&& dark,
                         Visit&& visit) {
  const auto& levels = clusters.levels;
  auto descend = [&](auto&& self, std::size_t level, std::size_t index) -> void {
    const LitClusters::Node& node = levels[level][index];
    if (!node.mixed && dark(node)) return;
    if (level == 0) {
      const std::size_t first = index * LitClusters::kLeaf;
      const std::size_t end = std::min(lit.size(), first + LitClusters::kLeaf);
      for (std::size_t k = first; k < end; ++k) visit(lit[k]);
      return;
    }
    // A level may end with a node carried up alone: its one child.
    const std::size_t children = levels[level - 1].size();
    for (std::size_t c = 2 * index; c < std::min(children, 2 * index + 2); ++c) {
      self(self, level - 1, c);
    }
  };
  if (!levels.empty() && !levels.back().empty()) descend(descend, levels.size() - 1, 0);
}

}  // namespace detail
}  // namespace glint
