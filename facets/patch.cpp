#include "facets/patch.h"

#include "facets/detail/patch_models.h"

namespace glint {

SubFacet coarseSubFacet(const Target& target, std::uint32_t facet) {
  return {target.corners_m[facet],
          {Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)},
          facet,
          0,
          target.rim_edges[facet]};
}

std::array<SubFacet, 4> split(const Target& target, const SubFacet& f) {
  return detail::withPatchModel(target, f.coarse, [&](const auto& m) { return m.split(f); });
}

void subFacetsAtDepth(const Target& target, std::uint32_t facet, int level,
                      std::vector<SubFacet>& out) {
  out.clear();
  std::vector<SubFacet> stack(1, coarseSubFacet(target, facet));
  while (!stack.empty()) {
    const SubFacet f = stack.back();
    stack.pop_back();
    if (f.depth < level) {
      for (const SubFacet& child : split(target, f)) stack.push_back(child);
    } else {
      out.push_back(f);
    }
  }
}

PatchGeometry patchGeometry(const Target& target, const SubFacet& f, NormalModel normals) {
  return detail::withPatchModel(
      target, f.coarse, [&](const auto& m) { return m.template geometry<true>(f, normals); });
}

}  // namespace glint
