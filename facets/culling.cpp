#include "facets/detail/culling.h"

#include <algorithm>
#include <cmath>
#include <memory>

#include "facets/occluder.h"
#include "facets/reflection.h"

namespace glint {
namespace {

// How much of an occlusion ray from the centre of @p g toward @p d to ignore. Where some normal
// of the facet is perpendicular to d, the facet straddles its own terminator or horizon: the
// kernel already clips it there (cos θ modelled linearly between the corners), and a ray from
// its centre may run into the facet's own neighbourhood at a grazing angle. Such a ray ignores
// what lies within two facet radii, about where a convex surface's own re-entry ends.
double localSkip(const PatchGeometry& g, const Vec3& d) {
  const bool straddles = g.cone_rad >= 0.5 * kPi || glm::dot(d, g.normal) < std::sin(g.cone_rad);
  return straddles ? 2.0 * g.radius_m : 0.0;
}

// Where the occlusion rays of a facet (geometry g, world frame) start: its centre, lifted
// off the surface (Occluder::lift_m).
Vec3 rayOrigin(const Occluder& occluder, const Target& target, const PatchGeometry& g,
               std::uint32_t object, std::uint32_t coarse) {
  return g.centre_m + target.objects[object].origin_m + occluder.lift_m(coarse) * g.normal;
}

// A band holding both bands: their union where they share an axis (a quadric's pieces take
// theirs from its principal axes, so a cylinder's all have the same), else none.
NormalBand enclosingBand(const NormalBand& a, const NormalBand& b) {
  if (a.axis == Vec3(0.0) || b.axis == Vec3(0.0)) return {};
  if (a.axis == b.axis) {
    return {a.axis, std::min(a.sin_lo, b.sin_lo), std::max(a.sin_hi, b.sin_hi)};
  }
  if (a.axis == -b.axis) {
    return {a.axis, std::min(a.sin_lo, -b.sin_hi), std::max(a.sin_hi, -b.sin_lo)};
  }
  return {};
}

// The smallest ball and cone (about the mean axis) holding both geometries' own.
PatchGeometry enclosing(const PatchGeometry& a, const PatchGeometry& b) {
  PatchGeometry g;
  g.centre_m = 0.5 * (a.centre_m + b.centre_m);
  g.radius_m = std::max(glm::length(a.centre_m - g.centre_m) + a.radius_m,
                        glm::length(b.centre_m - g.centre_m) + b.radius_m);
  g.normal = tryNormalize(a.normal + b.normal).value_or(a.normal);
  g.cone_rad = std::min(kPi, std::max(angleBetween(g.normal, a.normal) + a.cone_rad,
                                      angleBetween(g.normal, b.normal) + b.cone_rad));
  g.area_bound_m2 = a.area_bound_m2 + b.area_bound_m2;
  g.band = enclosingBand(a.band, b.band);
  return g;
}

}  // namespace

void FacetIntegrator::buildOccluder() {
  const bool self_shadowing = options_.occlusion && needsOcclusion(*target_);
  if (self_shadowing || options_.terrain) {
    occluder_ =
        std::make_shared<const Occluder>(*target_, 2, self_shadowing, options_.terrain.get());
  }
}

void FacetIntegrator::cull() {
  cull_.occlusion = occluder_ != nullptr;
  // One shadow ray speaks for one beam: under a swept beam nothing is culled as shadowed.
  const Occluder* shadows = beam_.swept() ? nullptr : occluder_.get();
  cull_.coarse_facets = target_->facetCount();
  for (std::uint32_t i = 0; i < target_->facetCount(); ++i) {
    const std::uint32_t obj = target_->object[i];
    const PatchGeometry g = patchGeometry(*target_, coarseSubFacet(*target_, i), options_.normals);
    if (!(g.area_m2 > 0.0)) {
      ++cull_.degenerate;
      continue;
    }
    const Beam& beam = object_beams_[obj];
    switch (lightVerdict(g, beam)) {
      case LightVerdict::OutsideBeam:
        ++cull_.outside_beam;
        if (glm::dot(g.centre_m - beam.origin_m, beam.direction) + g.radius_m < 0.0)
          ++cull_.behind_laser;
        break;
      case LightVerdict::FacesAway:
        ++cull_.facing_away;
        break;
      case LightVerdict::MayBeLit:
        if (shadows != nullptr) {
          // The shadow ray runs back along the beam to the laser's plane.
          const Vec3 from = rayOrigin(*shadows, *target_, g, obj, i);
          if (!shadows->rayClear(from, -beam_.direction,
                                 glm::dot(from - beam_.origin_m, beam_.direction),
                                 localSkip(g, -beam_.direction))) {
            ++cull_.shadowed;
            break;
          }
        }
        lit_.push_back({coarseSubFacet(*target_, i), obj, g, g.cone_rad, g.radius_m});
        break;
    }
  }
  cull_.lit = lit_.size();
}

void FacetIntegrator::buildClusters() {
  auto clusters = std::make_shared<LitClusters>();
  constexpr std::uint32_t leaf = LitClusters::kLeaf;
  std::vector<LitClusters::Node>& base = clusters->levels.emplace_back();
  for (std::size_t first = 0; first < lit_.size(); first += leaf) {
    const std::size_t end = std::min(lit_.size(), first + leaf);
    LitClusters::Node node{lit_[first].geometry, lit_[first].object, false};
    for (std::size_t k = first; k < end; ++k) {
      const Candidate& c = lit_[k];
      node.mixed = node.mixed || c.object != node.object;
      // The lobe scheme bounds a coarse facet by its surface map's geometry.
      const PatchGeometry own = (*maps_)[c.facet.coarse].geometry(*target_, c.facet);
      node.geometry = enclosing(enclosing(node.geometry, c.geometry), own);
    }
    base.push_back(node);
  }
  while (clusters->levels.back().size() > 1) {
    const std::vector<LitClusters::Node>& below = clusters->levels.back();
    std::vector<LitClusters::Node> above;
    for (std::size_t k = 0; k < below.size(); k += 2) {
      if (k + 1 == below.size()) {
        above.push_back(below[k]);
        continue;
      }
      const LitClusters::Node &a = below[k], &b = below[k + 1];
      above.push_back({enclosing(a.geometry, b.geometry), a.object,
                       a.mixed || b.mixed || a.object != b.object});
    }
    clusters->levels.push_back(std::move(above));
  }
  clusters_ = std::move(clusters);
}

namespace detail {

bool visiblePastOccluder(const Occluder& occluder, const Target& target, const Candidate& c,
                         const Vec3& observer_m) {
  const Vec3 from = rayOrigin(occluder, target, c.geometry, c.object, c.facet.coarse);
  const auto toward = tryNormalize(observer_m - from);
  return !toward || occluder.segmentClear(from, observer_m, localSkip(c.geometry, *toward));
}

}  // namespace detail
}  // namespace glint
