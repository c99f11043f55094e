// FacetIntegrator::boundBall() (integrator.h): the bound of what any observer in a ball can
// receive, with which the observer field (observers/) drops, keeps and splits candidates.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "facets/detail/patch_models.h"
#include "facets/integrator.h"
#include "facets/reflection.h"
#include "facets/sum.h"

namespace glint {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Marks in @p drop the weakest candidates (by @p bounds) while their bounds, added to
// @p inherited_dropped_w_m2, stay within @p allowance_w_m2; returns that sum. Sorting an index
// keeps the candidates' order, and so the integration's, independent of the bounds.
double dropWeakest(const std::vector<double>& bounds, double inherited_dropped_w_m2,
                   double allowance_w_m2, std::vector<char>& drop) {
  thread_local std::vector<std::uint32_t> order;
  order.resize(bounds.size());
  for (std::uint32_t k = 0; k < order.size(); ++k) order[k] = k;
  std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
    return bounds[a] != bounds[b] ? bounds[a] < bounds[b] : a < b;
  });
  CompensatedSum dropped;
  dropped.add(inherited_dropped_w_m2);
  drop.assign(bounds.size(), 0);
  for (std::uint32_t k : order) {
    // Only a finite bound proven within the allowance is dropped: an unbounded candidate never
    // is, whatever the allowance (sorted last, it ends the loop).
    if (!(bounds[k] < kInf) || !(dropped.value() + bounds[k] <= allowance_w_m2)) break;
    dropped.add(bounds[k]);
    drop[k] = 1;
  }
  return dropped.value();
}

}  // namespace

BallBound FacetIntegrator::boundBall(const Vec3& centre_m, double radius_m,
                                     std::span<const Candidate> inherited,
                                     double inherited_dropped_w_m2, const BallBoundOptions& options,
                                     std::vector<Candidate>& kept) const {
  BallBound result;
  kept.clear();
  // kept doubles as the work list: entries before i are final, with their bound in `bounds`;
  // a split candidate is replaced by its first child in place and the others at the end.
  thread_local std::vector<double> bounds;
  bounds.clear();
  for (const Candidate& c : inherited) kept.push_back(c);
  std::size_t i = 0;
  while (i < kept.size()) {
    const Candidate c = kept[i];
    const Vec3 x = centre_m - target_->objects[c.object].origin_m;
    double upper = 0.0;
    if (mayFaceObserver(c.geometry, x, radius_m)) {
      const Material& material = target_->materials[target_->objects[c.object].material];
      upper = contributionBound(c.geometry, x, object_beams_[c.object], material,
                                options_.resolution, radius_m)
                  .upper_w_m2;
      ++result.bound_evaluations;
    }
    if (upper == 0.0) {  // provably nothing: drop for free
      kept[i] = kept.back();
      kept.pop_back();
      continue;
    }
    // Splitting tightens the bound only where the cone is wider than the angle under which
    // the region sees the facet: the half vector cannot be pinned down finer than that. A
    // candidate larger than the region that the region reaches has no bound at all: split, its
    // pieces the region does not reach get one (a flat mirror beside an observer, whose cone
    // is 0, above all); one smaller than the region stays reached however it is split.
    const double d = glm::length(x - c.geometry.centre_m);
    const double reach = c.geometry.radius_m + radius_m;
    const double region_angle = d > reach ? std::asin(reach / d) : kPi;
    const bool tighter = std::isfinite(upper) ? c.geometry.cone_rad > 0.5 * region_angle
                                              : c.geometry.radius_m > radius_m;
    if (upper > options.drop_allowance_w_m2 && c.facet.depth < options.max_split_depth && tighter) {
      detail::withPatchModel(*target_, c.facet.coarse, [&](const auto& model) {
        const std::array<SubFacet, 4> children = model.split(c.facet);
        kept[i] = {children[0], c.object,
                   model.template geometry<true>(children[0], options_.normals), c.fan_rad,
                   c.fan_radius_m};
        for (int k = 1; k < 4; ++k) {
          kept.push_back({children[k], c.object,
                          model.template geometry<true>(children[k], options_.normals), c.fan_rad,
                          c.fan_radius_m});
        }
      });
      continue;  // kept[i] is now the first child
    }
    bounds.resize(kept.size());
    bounds[i] = upper;
    ++i;
  }
  bounds.resize(kept.size());

  thread_local std::vector<char> drop;
  const double dropped_w_m2 =
      dropWeakest(bounds, inherited_dropped_w_m2, options.drop_allowance_w_m2, drop);
  CompensatedSum total;
  CompensatedSum narrow;
  std::size_t out = 0;
  for (std::size_t k = 0; k < kept.size(); ++k) {
    if (drop[k] != 0) continue;
    total.add(bounds[k]);
    // The light of the whole coarse facet fills at least its own width plus what its cone
    // and lobe (±2 widths in the normal, twice that after reflection) spread over the distance.
    const Candidate& c = kept[k];
    const TargetObject& obj = target_->objects[c.object];
    // The narrowest term of the material: its light is the narrowest the facet sends.
    const Material& material = target_->materials[obj.material];
    const Vec3 x = centre_m - obj.origin_m;
    // ABg's wings are broad: its width is taken where the region sees the facet.
    const double theta_n_min =
        material.abg ? minHalfVectorAngle(c.geometry, x, object_beams_[c.object], radius_m) : 0.0;
    const double lobe_rad =
        material.narrowestWidthRad(theta_n_min).value_or(material.lobe.widthRad());
    const double d_min =
        std::max(0.0, glm::length(x - c.geometry.centre_m) - c.fan_radius_m - radius_m);
    const double width = 2.0 * c.fan_radius_m + 4.0 * d_min * (c.fan_rad + 2.0 * lobe_rad);
    // A width that cannot be computed counts as narrow: the block then looks closer.
    if (!(width >= std::sqrt(3.0) * options.sample_spacing_m)) {
      narrow.add(bounds[k]);
      result.resolving_spacing_m = std::min(result.resolving_spacing_m, width / std::sqrt(3.0));
    }
    kept[out++] = c;
  }
  kept.resize(out);
  result.dropped_w_m2 = dropped_w_m2;
  result.upper_w_m2 = total.value() + result.dropped_w_m2;
  result.narrow_w_m2 = narrow.value();
  return result;
}

}  // namespace glint
