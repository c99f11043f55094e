#include "facets/integrator.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "facets/detail/culling.h"
#include "facets/detail/patch_models.h"
#include "facets/detail/surface_cache.h"
#include "facets/lobe_rule.h"
#include "facets/occluder.h"
#include "facets/sum.h"
#include "facets/triangle_rule.h"

namespace glint {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// An error estimate above this (W/m², far beyond any physical irradiance) is counted as
// unbounded instead of summed. The running sums add and subtract every leaf's error as it
// changes: two bounds near the largest double (a piece seen edge-on) overflowed them to +∞, and
// ∞ − x stays ∞, so the running total never looked done, the exact total that would have
// said so was never taken, and one observer ran to the evaluation limit (4e6 evaluations and
// 1.3 GB of workspace at a point 0.14 m off the cylinder quarter's lit side, where 164 do).
// Counted, such a leaf still blocks "done" until it is refined; summed below this, a billion
// leaves stay finite.
constexpr double kLargestSummedError = 1e100;

// Whether an error estimate counts as unbounded (NaN included): see kLargestSummedError.
bool unboundedError(double error_w_m2) { return !(error_w_m2 <= kLargestSummedError); }

// A leaf of one observer's refinement: a sub-facet, its own centre estimate and, once
// refined, the estimates of its four children (whose positions split() regenerates on demand,
// which is cheaper than storing them).
//
// A leaf's error is accounted in one of two ways. Resolved leaves with children (their
// samples resolve a smooth integrand) contribute their signed change ΔE = E'_O − E_O; the
// observer's error estimate takes |Σ ΔE|, the change of the total under one more level, in
// which the alternating midpoint errors across a resolved lobe cancel as they do in the true
// total. Every other leaf contributes a magnitude: its bound U until it has children, then
// max(|ΔE|, U_unresolved), U_unresolved bounding the terms its samples may have missed. A resolved
// leaf whose |ΔE| is negligible even summed over every leaf also counts as a magnitude: it
// needs no credit for cancellation, and the level-by-level sweep of the signed leaves (see
// HeapEntry) is spared the places that do not matter.
struct Leaf {
  SubFacet facet;
  double estimate = 0.0;    // E_O at this facet's centre
  double refined = 0.0;     // Σ E_On of the children, once has_children
  double upper = 0.0;       // bound of the facet's true contribution (+∞ if unbounded)
  double unresolved = 0.0;  // bound of the terms its samples do not resolve (0: resolved)
  double error = 0.0;       // magnitude used for priority (and for the sum if not signed)
  std::array<double, 4> child_estimate{};
  std::array<double, 4> child_upper{};
  std::array<double, 4> child_unresolved{};
  bool has_children = false;
  bool significant = false;  // resolved and |ΔE| not negligible: accounted signed
  // Cubature leaves start from their bound alone (estimate 0, error = upper): the rule and its
  // check cost 25 kernel evaluations, which only resolved pieces whose bound matters are worth.
  bool sampled = true;

  [[nodiscard]] double value() const { return has_children ? refined : estimate; }
  [[nodiscard]] bool signedError() const {
    return has_children && unresolved == 0.0 && significant;
  }
};

// Heap priority: larger first. Leaves with a magnitude error are ranked by it; leaves with a
// signed error shallowest first (ties by |ΔE|), so a resolved region is refined a whole level
// at a time and its change of total stays the classical two-level estimate: refining only the
// largest |ΔE| would push a lobe's peak deeper than its tails and leave their same-signed
// O(h²) differences uncancelled.
struct HeapEntry {
  int rank;         // compared first: 0 for magnitudes, −depth for signed errors
  double priority;  // then the error
  std::uint32_t leaf;
};

// Ties broken by slot, so the order never depends on anything but the input.
bool heapLess(const HeapEntry& a, const HeapEntry& b) {
  if (a.rank != b.rank) return a.rank < b.rank;
  if (a.priority != b.priority) return a.priority < b.priority;
  return a.leaf > b.leaf;
}

class LeafHeap {
 public:
  void clear() { entries_.clear(); }
  [[nodiscard]] bool empty() const { return entries_.empty(); }
  [[nodiscard]] const std::vector<HeapEntry>& entries() const { return entries_; }
  void push(int rank, double priority, std::uint32_t slot) {
    entries_.push_back({rank, priority, slot});
    std::push_heap(entries_.begin(), entries_.end(), heapLess);
  }
  std::uint32_t pop() {
    std::pop_heap(entries_.begin(), entries_.end(), heapLess);
    const std::uint32_t slot = entries_.back().leaf;
    entries_.pop_back();
    return slot;
  }

 private:
  std::vector<HeapEntry> entries_;
};

// The observer's running error budget: Σ value, |Σ signed ΔE| + Σ magnitudes, and the number
// of leaves whose error is unbounded. Compensated: a leaf's bound is added and later taken out
// again, and near the target those bounds are many orders above the total; a plain running
// sum keeps about 1e-16 of the largest of them as a residue (see adaptiveLobe()).
struct Totals {
  CompensatedSum value_sum, change_sum, magnitude_sum;
  std::int64_t unbounded = 0;

  void account(const Leaf& leaf, int sign) {
    value_sum.add(sign * leaf.value());
    if (leaf.signedError()) {
      change_sum.add(sign * (leaf.refined - leaf.estimate));
    } else if (unboundedError(leaf.error)) {  // +∞, or a NaN that must count as +∞
      unbounded += sign;
    } else {
      magnitude_sum.add(sign * leaf.error);
    }
  }
  [[nodiscard]] double value() const { return value_sum.value(); }
  [[nodiscard]] double signedChange() const { return change_sum.value(); }
  [[nodiscard]] double magnitude() const { return magnitude_sum.value(); }
  [[nodiscard]] double error() const { return std::abs(signedChange()) + magnitude(); }
};

// The cubature rule: 4 × 4 conical product points, exact to degree 7; its error is estimated
// by the 3 × 3 rule (degree 5) on the same piece, an overestimate once the piece is resolved.
constexpr int kRulePointsPerAxis = 4;

// When the cubature rule's samples resolve a piece. Its 16 points sit about a quarter of the
// piece apart, so a lobe whose normal spread over the piece is 4σ (8σ across) is sampled every
// ~2σ or closer: a peak between samples keeps ≥ e^-0.5 of its value at the nearest one, and
// the degree-5 check differs from the rule wherever they under-resolve it. (On the paper's 186
// observers 3σ costs 30 % more evaluations; 6σ saves under 1 %.) The kernel stops at the
// terminator and the horizon, a jump no polynomial rule resolves: a piece that may straddle
// either leaves its specular term unresolved (flat lobe or not), so it is refined on its bound.
// Near the observer 1/d² and the directions vary on the scale of d: a quarter of d is smooth
// enough for degree 7.
ResolutionLimits cubatureLimits() {
  ResolutionLimits limits;
  limits.lobe = 4.0;
  limits.clipped_log_variation = -1.0;
  limits.near_field = 0.25;
  return limits;
}

// ∫ over the piece of the coarse facet with barycentric corners f.bary by the cubature rule
// (`value`) and by the embedded lower rule (`check`), in the exact surface map. `ok` turns false
// when a sample falls where the map breaks down.
struct RuleResult {
  double value = 0.0;
  double check = 0.0;
  bool ok = true;
  std::int64_t evaluations = 0;
};

RuleResult ruleIrradiance(const SurfaceMap& map, const SubFacet& f, const Vec3& observer_m,
                          const Beam& beam, const Material& material) {
  const Vec3 e1 = f.bary[1] - f.bary[0], e2 = f.bary[2] - f.bary[0];
  const double area_uv = 0.5 * std::abs(e1[1] * e2[2] - e1[2] * e2[1]);
  // The rules are built once; fetching them per piece would pass a once-flag per call.
  static const std::span<const TriangleNode> kRule = conicalProductRule(kRulePointsPerAxis);
  static const std::span<const TriangleNode> kCheck = conicalProductRule(kRulePointsPerAxis - 1);
  RuleResult r;
  auto apply = [&](std::span<const TriangleNode> rule) {
    double sum = 0.0;
    for (const TriangleNode& node : rule) {
      const Vec3 b = node.bary[0] * f.bary[0] + node.bary[1] * f.bary[1] + node.bary[2] * f.bary[2];
      const SurfacePoint p = map.at(b);
      ++r.evaluations;
      if (!p.valid) {
        r.ok = false;
        continue;
      }
      sum += node.weight * pointIrradiance(p.position_m, p.normal, p.jacobian_m2, observer_m,
                                           beam.at(p.position_m), material,
                                           beam.return_extinction_per_m);
    }
    return area_uv * sum;
  };
  r.value = apply(kRule);
  r.check = apply(kCheck);
  return r;
}

// A piece of the lobe scheme. Its six nodes (and, once refined, the nine new nodes of its
// children) live in the workspace's node pool, so the children inherit them.
struct LobePiece {
  SubFacet facet;               // corners placed by the surface map
  double upper = 0.0;           // bound of its true contribution (+∞ if unbounded)
  double specular_upper = 0.0;  // bound of its specular part alone
  double unresolved = 0.0;      // bound of what the rule cannot be trusted with (0: resolved)
  double estimate = 0.0;        // the rule on the piece, once sampled
  double refined = 0.0;         // Σ of the rule on its children, once refined (or the estimate)
  // A magnitude: the bound until refined, then |refined − estimate| (or the embedded error).
  double error = 0.0;
  std::array<double, 4> child_estimate{};
  std::uint32_t nodes = 0;  // offset of its 15 nodes in the pool, once sampled
  bool sampled = false;
  bool refined_ok = false;      // value and error known (by its children, or embedded)
  bool children_known = false;  // child_estimate and nodes 6–14 hold its children's

  [[nodiscard]] double value() const { return refined_ok ? refined : estimate; }
};

// The pool layout of a refined piece: its own nodes (corners 0–2, midpoints of 01, 12, 20) at
// 0–5, then the midpoints of its children's edges at 6–14, and for each child (in split()'s
// order) where its own six nodes sit.
constexpr int kLobeNodes = 15;
constexpr std::array<std::array<int, 6>, 4> kChildNodes{{
    {0, 3, 5, 6, 7, 8},     // (b0, m01, m20)
    {3, 1, 4, 9, 10, 11},   // (m01, b1, m12)
    {5, 4, 2, 12, 13, 14},  // (m20, m12, b2)
    {3, 4, 5, 11, 12, 7},   // (m01, m12, m20)
}};

// When the lobe rule may be trusted with a piece: its normals (with the half vector's turn
// across it) spread at most this much, so that q = H/(H·n) − n is close enough to quadratic
// for its interpolant to place the specular point (tan's cubic term is ~1 % of q here), and
// its radius is at most half the observer's distance, beyond which 1/d² bends faster than a
// split's change shows. (The brute-force cross-check achieved the same errors at a quarter,
// a half and the whole distance; a quarter cost near observers 1.4–3× the evaluations.)
constexpr double kLobeSpreadRad = 0.3;
ResolutionLimits lobeLimits(double sigma) {
  ResolutionLimits limits;
  limits.lobe = kLobeSpreadRad / sigma;
  limits.clipped_log_variation = std::numeric_limits<double>::infinity();
  limits.near_field = 0.5;
  limits.clips_beam_edges = true;
  return limits;
}

double parameterArea(const SubFacet& f) {
  const Vec3 e1 = f.bary[1] - f.bary[0], e2 = f.bary[2] - f.bary[0];
  return 0.5 * std::abs(e1[1] * e2[2] - e1[2] * e2[1]);
}

}  // namespace

struct IntegratorWorkspace::Impl {
  std::vector<Leaf> leaves;
  std::vector<std::uint32_t> free_slots;
  LeafHeap bounded;                    // leaves with a magnitude error
  LeafHeap resolved;                   // leaves with a signed error
  std::vector<std::uint32_t> frozen;   // leaves that may not split further (depth limit)
  std::vector<SubFacet> stack;         // the uniform twin's traversal
  std::vector<Vec3> observer_local_m;  // the observer in each object's frame
  std::vector<LobePiece> pieces;       // the lobe scheme's leaves
  std::vector<LobeNode> lobe_nodes;    // their nodes, kLobeNodes per sampled piece
  detail::SurfaceCache surfaces;       // the lobe scheme's geometry, kept between observers

  void reset() {
    pieces.clear();
    lobe_nodes.clear();
    leaves.clear();
    free_slots.clear();
    bounded.clear();
    resolved.clear();
    frozen.clear();
    stack.clear();
  }

  std::uint32_t store(const Leaf& leaf) {
    if (!free_slots.empty()) {
      const std::uint32_t slot = free_slots.back();
      free_slots.pop_back();
      leaves[slot] = leaf;
      return slot;
    }
    leaves.push_back(leaf);
    return static_cast<std::uint32_t>(leaves.size() - 1);
  }

  void push(std::uint32_t slot) {
    Leaf& leaf = leaves[slot];
    // A NaN error would break the heap's order and hide the leaf: it counts as unbounded.
    if (std::isnan(leaf.error)) leaf.error = kInf;
    if (leaf.signedError()) {
      resolved.push(-static_cast<int>(leaf.facet.depth), leaf.error, slot);
    } else {
      bounded.push(0, leaf.error, slot);
    }
  }

  // Exact totals over every live leaf, compensated, to confirm what the running sums suggest.
  Totals exactTotals() const {
    Totals t;
    for (const HeapEntry& h : bounded.entries()) t.account(leaves[h.leaf], 1);
    for (const HeapEntry& h : resolved.entries()) t.account(leaves[h.leaf], 1);
    for (std::uint32_t slot : frozen) t.account(leaves[slot], 1);
    return t;
  }
};

std::vector<std::string> integrationSchemeNames() { return {"paper", "cubature", "lobe"}; }

std::optional<IntegrationScheme> integrationSchemeByName(std::string_view name) {
  const std::vector<std::string> names = integrationSchemeNames();
  const auto it = std::find(names.begin(), names.end(), name);
  if (it == names.end()) return std::nullopt;
  return static_cast<IntegrationScheme>(it - names.begin());
}

IntegratorWorkspace::IntegratorWorkspace() : impl_(std::make_unique<Impl>()) {}
IntegratorWorkspace::~IntegratorWorkspace() = default;
IntegratorWorkspace::IntegratorWorkspace(IntegratorWorkspace&&) noexcept = default;
IntegratorWorkspace& IntegratorWorkspace::operator=(IntegratorWorkspace&&) noexcept = default;

namespace {

void validateAccuracy(const IntegratorOptions& o) {
  if (!(o.tolerance >= 0.0) || !(o.floor_w_m2 >= 0.0) || !std::isfinite(o.floor_w_m2) ||
      o.max_depth < 0 || o.max_depth > 30 || o.max_evaluations < 1) {
    throw std::invalid_argument("FacetIntegrator: accuracy options out of range");
  }
}

}  // namespace

FacetIntegrator FacetIntegrator::withAccuracy(double tolerance, double floor_w_m2) const {
  FacetIntegrator copy = *this;  // the target shared; culling, maps and occluder as they are
  copy.options_.tolerance = tolerance;
  copy.options_.floor_w_m2 = floor_w_m2;
  validateAccuracy(copy.options_);
  return copy;
}

FacetIntegrator FacetIntegrator::withReturnExtinction(double per_m) const {
  FacetIntegrator copy = *this;  // the surface maps hold geometry only: shared as they are
  copy.beam_.return_extinction_per_m = per_m;
  for (Beam& b : copy.object_beams_) b.return_extinction_per_m = per_m;
  return copy;
}

FacetIntegrator::FacetIntegrator(Target target, const Beam& beam, const IntegratorOptions& options)
    : target_(std::make_shared<const Target>(std::move(target))), beam_(beam), options_(options) {
  static std::atomic<std::uint64_t> instances{0};
  id_ = ++instances;
  validateAccuracy(options_);
  object_beams_.reserve(target_->objects.size());
  for (const TargetObject& obj : target_->objects) {
    object_beams_.push_back(beam_.relativeTo(obj.origin_m));
  }
  cull();
  if (options_.scheme != IntegrationScheme::Paper) {
    maps_.reserve(target_->facetCount());
    for (std::uint32_t i = 0; i < target_->facetCount(); ++i) maps_.emplace_back(*target_, i);
  }
  if (options_.scheme == IntegrationScheme::Lobe) buildClusters();
}

void FacetIntegrator::prepareObserver(const Vec3& observer_m, IntegratorWorkspace::Impl& ws) const {
  ws.reset();
  ws.surfaces.bind(id_);
  ws.observer_local_m.resize(target_->objects.size());
  for (std::size_t k = 0; k < target_->objects.size(); ++k) {
    ws.observer_local_m[k] = observer_m - target_->objects[k].origin_m;
  }
}

ObserverResult FacetIntegrator::adaptive(const Vec3& observer_m,
                                         IntegratorWorkspace& workspace) const {
  return adaptive(observer_m, lit_, workspace);
}

ObserverResult FacetIntegrator::adaptive(const Vec3& observer_m,
                                         std::span<const Candidate> candidates,
                                         IntegratorWorkspace& workspace) const {
  IntegratorWorkspace::Impl& ws = *workspace.impl_;
  prepareObserver(observer_m, ws);
  if (options_.scheme == IntegrationScheme::Lobe) return adaptiveLobe(observer_m, candidates, ws);
  const IntegratorOptions& opt = options_;
  ObserverResult result;
  Totals totals;  // running; confirmed by exactTotals() before stopping
  auto budget = [&](double total) {
    return std::max(opt.tolerance * std::abs(total), opt.floor_w_m2);
  };
  auto done = [&](const Totals& t) { return t.unbounded == 0 && t.error() <= budget(t.value()); };

  const bool cubature = opt.scheme == IntegrationScheme::Cubature;
  const ResolutionLimits limits = cubature ? cubatureLimits() : opt.resolution;
  for (const Candidate& lit : candidates) {
    const Vec3& x = ws.observer_local_m[lit.object];
    if (!mayFaceObserver(lit.geometry, x) ||
        !detail::visible(occluder_.get(), *target_, lit, observer_m))
      continue;
    const Beam& beam = object_beams_[lit.object];
    const Material& material = target_->materials[target_->objects[lit.object].material];
    Leaf leaf;
    leaf.facet = lit.facet;
    PatchGeometry g = lit.geometry;
    if (cubature) {
      // A candidate split by boundBall() has its corners from 1→4 subdivision; the pieces
      // here are those of the surface map, over the same barycentric triangle.
      if (lit.facet.depth > 0) {
        leaf.facet =
            maps_[lit.facet.coarse].subFacet(lit.facet.bary, lit.facet.depth, lit.facet.rim_edges);
        g = maps_[lit.facet.coarse].geometry(*target_, leaf.facet);
      }
      leaf.sampled = false;
    } else {
      leaf.estimate = facetIrradiance(g, x, beam, material);
      ++result.evaluations;
    }
    const ContributionBound b = contributionBound(g, x, beam, material, limits);
    leaf.upper = b.upper_w_m2;
    leaf.unresolved = b.unresolved_w_m2;
    leaf.error = b.upper_w_m2;
    totals.account(leaf, 1);
    ws.push(ws.store(leaf));
  }

  Totals frozen;  // what leaves at the depth limit hold: no further work can reduce it
  auto freeze = [&](std::uint32_t slot) {
    ws.frozen.push_back(slot);
    frozen.account(ws.leaves[slot], 1);
    result.depth_limited = true;
  };

  while (true) {
    if (done(totals)) {
      totals = ws.exactTotals();
      if (done(totals)) break;
    }
    if (result.evaluations >= opt.max_evaluations) break;
    if (frozen.unbounded > 0 || frozen.magnitude() > budget(totals.value())) break;
    // Work on whichever part of the error stands in the way.
    const bool magnitude_first =
        totals.unbounded > 0 || totals.magnitude() >= std::abs(totals.signedChange());
    LeafHeap* heap = magnitude_first ? &ws.bounded : &ws.resolved;
    if (heap->empty()) heap = magnitude_first ? &ws.resolved : &ws.bounded;
    if (heap->empty()) break;  // everything left is frozen at the depth limit

    const std::uint32_t slot = heap->pop();
    Leaf& leaf = ws.leaves[slot];
    const std::uint32_t obj = target_->object[leaf.facet.coarse];
    const Vec3& x = ws.observer_local_m[obj];
    const Beam& beam = object_beams_[obj];
    const Material& material = target_->materials[target_->objects[obj].material];

    if (!leaf.has_children) {
      // The paper's step: evaluate the four children, E'_O = Σ E_On, ΔE_O = E'_O − E_O.
      if (leaf.facet.depth >= opt.max_depth) {
        freeze(slot);
        continue;
      }
      totals.account(leaf, -1);
      if (cubature) {
        if (!leaf.sampled && leaf.unresolved == 0.0) {
          // A resolved piece: the rule and its embedded check. Their difference is the lower
          // rule's error, an overestimate of the rule's; the piece is split while it matters.
          const RuleResult r =
              ruleIrradiance(maps_[leaf.facet.coarse], leaf.facet, x, beam, material);
          result.evaluations += r.evaluations;
          leaf.sampled = true;
          leaf.estimate = r.value;
          if (!r.ok) leaf.unresolved = leaf.upper;  // known only by its bound: split further
          leaf.error = std::max(std::abs(r.value - r.check), leaf.unresolved);
          totals.account(leaf, 1);
          ws.push(slot);
          continue;
        }
        // A piece the rule cannot be trusted with yet (lobe, beam edge, terminator or near
        // field unresolved), or whose rule error is still in the way: its four children
        // replace it, each known by its bound until it is resolved and sampled in turn. Most
        // pieces near a glint are proven dark this way without a sample.
        const Leaf parent = leaf;
        ws.free_slots.push_back(slot);
        for (const SubFacet& child : maps_[parent.facet.coarse].split(parent.facet)) {
          const PatchGeometry g = maps_[parent.facet.coarse].geometry(*target_, child);
          const ContributionBound b = contributionBound(g, x, beam, material, limits);
          if (b.upper_w_m2 == 0.0) continue;  // provably dark
          Leaf c;
          c.facet = child;
          c.sampled = false;
          c.upper = b.upper_w_m2;
          c.unresolved = b.unresolved_w_m2;
          c.error = b.upper_w_m2;
          totals.account(c, 1);
          ws.push(ws.store(c));
        }
        continue;
      }
      detail::withPatchModel(*target_, leaf.facet.coarse, [&](const auto& model) {
        const std::array<SubFacet, 4> children = model.split(leaf.facet);
        leaf.refined = 0.0;
        for (int k = 0; k < 4; ++k) {
          const PatchGeometry g = model.template geometry<true>(children[k], opt.normals);
          leaf.child_estimate[k] = facetIrradiance(g, x, beam, material);
          const ContributionBound b = contributionBound(g, x, beam, material, opt.resolution);
          leaf.child_upper[k] = b.upper_w_m2;
          leaf.child_unresolved[k] = b.unresolved_w_m2;
          leaf.refined += leaf.child_estimate[k];
        }
      });
      result.evaluations += 4;
      leaf.has_children = true;
      const double delta = std::abs(leaf.refined - leaf.estimate);
      leaf.error = std::max(delta, leaf.unresolved);
      const std::size_t live = ws.leaves.size() - ws.free_slots.size();
      leaf.significant = delta > 0.1 * budget(totals.value()) / static_cast<double>(live);
      totals.account(leaf, 1);
      ws.push(slot);
      continue;
    }

    // Replace the leaf by its children; each is refined in turn when its error (its bound,
    // until it has children of its own) is among the largest.
    if (leaf.facet.depth + 1 >= opt.max_depth) {
      freeze(slot);
      continue;
    }
    totals.account(leaf, -1);
    const Leaf parent = leaf;
    ws.free_slots.push_back(slot);
    const std::array<SubFacet, 4> children = split(*target_, parent.facet);
    for (int k = 0; k < 4; ++k) {
      Leaf child;
      child.facet = children[k];
      child.estimate = parent.child_estimate[k];
      child.upper = parent.child_upper[k];
      child.unresolved = parent.child_unresolved[k];
      child.error = child.upper;
      totals.account(child, 1);
      ws.push(ws.store(child));
    }
  }

  totals = ws.exactTotals();
  result.irradiance_w_m2 = totals.value();
  result.error_estimate_w_m2 = totals.error();
  result.converged = done(totals);
  return result;
}

ObserverResult FacetIntegrator::adaptiveLobe(const Vec3& observer_m,
                                             std::span<const Candidate> candidates,
                                             IntegratorWorkspace::Impl& ws) const {
  const IntegratorOptions& opt = options_;
  ObserverResult result;
  // Running sums (value, magnitudes, unbounded count), confirmed exactly before stopping.
  // Compensated, as in Totals: the bounds added and later taken out again near the target
  // are many orders above the total, and a plain sum kept about 1e-16 of the largest as a
  // residue. At a point 0.14 m off the cylinder quarter's lit side (field at 0.05 m) that
  // residue alone exceeded the budget: the running total never looked done, the exact one that
  // would have said so was never taken, and the observer ran to the evaluation limit (4e6
  // evaluations, 1.3 GB of workspace) where 164 suffice.
  struct PieceTotals {
    CompensatedSum value_sum, magnitude_sum;
    std::int64_t unbounded = 0;
    void account(const LobePiece& p, int sign) {
      value_sum.add(sign * p.value());
      if (unboundedError(p.error)) {
        unbounded += sign;
      } else {
        magnitude_sum.add(sign * p.error);
      }
    }
  } totals;
  auto account = [&](const LobePiece& p, int sign) { totals.account(p, sign); };
  auto value = [&] { return totals.value_sum.value(); };
  auto budget = [&](double total) {
    return std::max(opt.tolerance * std::abs(total), opt.floor_w_m2);
  };
  std::vector<std::uint32_t>& frozen = ws.frozen;  // at the depth limit
  double frozen_magnitude = 0.0;
  std::int64_t frozen_unbounded = 0;
  auto exact = [&]() {
    totals = {};
    for (const HeapEntry& h : ws.bounded.entries()) account(ws.pieces[h.leaf], 1);
    for (std::uint32_t slot : frozen) account(ws.pieces[slot], 1);
  };
  auto done = [&]() {
    return totals.unbounded == 0 && totals.magnitude_sum.value() <= budget(value());
  };
  // A piece whose specular term is below this is not worth its sigma points: a hundredth of
  // the error budget shared among the pieces (the running total may still grow: the budget
  // only rises, so this errs small).
  auto negligible = [&]() {
    const std::size_t live = ws.pieces.size() - ws.free_slots.size();
    return 0.01 * budget(value()) / static_cast<double>(live + 16);
  };
  auto store = [&](const LobePiece& p) {
    std::uint32_t slot;
    if (!ws.free_slots.empty()) {
      slot = ws.free_slots.back();
      ws.free_slots.pop_back();
      ws.pieces[slot] = p;
    } else {
      slot = static_cast<std::uint32_t>(ws.pieces.size());
      ws.pieces.push_back(p);
    }
    LobePiece& stored = ws.pieces[slot];
    if (std::isnan(stored.error)) stored.error = kInf;  // a NaN must count as unbounded
    ws.bounded.push(0, stored.error, slot);
    account(stored, 1);
  };
  auto bounded = [&](const SubFacet& f, const Vec3& x, const Beam& beam, const Material& material) {
    const PatchGeometry g = ws.surfaces.geometry(*target_, maps_[f.coarse], f);
    const ContributionBound b =
        contributionBound(g, x, beam, material, lobeLimits(material.lobe.sigma));
    LobePiece p;
    p.facet = f;
    p.upper = b.upper_w_m2;
    p.specular_upper = b.specular_w_m2;
    p.unresolved = b.unresolved_w_m2;
    p.error = b.upper_w_m2;
    return p;
  };

  auto consider = [&](const Candidate& lit) {
    const Vec3& x = ws.observer_local_m[lit.object];
    if (!mayFaceObserver(lit.geometry, x)) return;
    const Beam& beam = object_beams_[lit.object];
    const Material& material = target_->materials[target_->objects[lit.object].material];
    // A candidate split by boundBall() has its corners from 1→4 subdivision; the pieces
    // here are those of the surface map, over the same barycentric triangle. A coarse facet's
    // corners are the map's own (it interpolates them), so it needs no lookup.
    const SubFacet f = lit.facet.depth == 0
                           ? lit.facet
                           : ws.surfaces.subFacet(maps_[lit.facet.coarse], lit.facet.bary,
                                                  lit.facet.depth, lit.facet.rim_edges);
    const LobePiece p = bounded(f, x, beam, material);
    // The occlusion ray last: of a mesh's thousands of lit facets an observer's bound keeps a
    // few, and the ray costs more than the bound.
    if (p.upper == 0.0 || !detail::visible(occluder_.get(), *target_, lit, observer_m)) return;
    store(p);
  };
  if (clusters_ && candidates.data() == lit_.data()) {
    // Every lit facet: through the hierarchy, depth first, so the facets are considered in
    // their order whatever is pruned (the totals then add up in the same order).
    const auto& levels = clusters_->levels;
    auto descend = [&](auto&& self, std::size_t level, std::size_t index) -> void {
      const LitClusters::Node& node = levels[level][index];
      if (!node.mixed) {
        const std::uint32_t obj = node.object;
        const Material& material = target_->materials[target_->objects[obj].material];
        const ContributionBound b =
            contributionBound(node.geometry, ws.observer_local_m[obj], object_beams_[obj], material,
                              lobeLimits(material.lobe.sigma));
        if (b.upper_w_m2 == 0.0) return;
      }
      if (level == 0) {
        const std::size_t first = index * LitClusters::kLeaf;
        const std::size_t end = std::min(lit_.size(), first + LitClusters::kLeaf);
        for (std::size_t k = first; k < end; ++k) consider(lit_[k]);
        return;
      }
      // A level may end with a node carried up alone: its one child.
      const std::size_t children = levels[level - 1].size();
      for (std::size_t c = 2 * index; c < std::min(children, 2 * index + 2); ++c) {
        self(self, level - 1, c);
      }
    };
    if (!levels.empty() && !levels.back().empty()) descend(descend, levels.size() - 1, 0);
  } else {
    for (const Candidate& lit : candidates) consider(lit);
  }

  while (true) {
    if (done()) {
      exact();
      if (done()) break;
    }
    if (result.evaluations >= opt.max_evaluations) break;
    if (frozen_unbounded > 0 || frozen_magnitude > budget(value())) break;
    if (ws.bounded.empty()) break;  // everything left is frozen at the depth limit
    const std::uint32_t slot = ws.bounded.pop();
    LobePiece piece = ws.pieces[slot];
    const std::uint32_t obj = target_->object[piece.facet.coarse];
    const Vec3& x = ws.observer_local_m[obj];
    const Beam& beam = object_beams_[obj];
    const Material& material = target_->materials[target_->objects[obj].material];
    const SurfaceMap& map = maps_[piece.facet.coarse];
    const double sigma = material.lobe.sigma;

    if (piece.unresolved == 0.0 && !piece.refined_ok) {
      // Sample the piece (if its nodes are not inherited) and, unless its light is diffuse
      // and its embedded estimate settles it, its four children: the change is the piece's
      // error estimate, and the children's sum its value.
      account(piece, -1);
      const auto& b = piece.facet.bary;
      const std::array<Vec3, 6> node_bary{
          b[0], b[1], b[2], 0.5 * (b[0] + b[1]), 0.5 * (b[1] + b[2]), 0.5 * (b[2] + b[0])};
      if (!piece.sampled) {
        piece.nodes = static_cast<std::uint32_t>(ws.lobe_nodes.size());
        ws.lobe_nodes.resize(ws.lobe_nodes.size() + kLobeNodes);
        for (int j = 0; j < 6; ++j) {
          ws.lobe_nodes[piece.nodes + j] =
              lobeNode(ws.surfaces.at(map, node_bary[j]), x, beam, material);
        }
        result.evaluations += 6;
        const LobeNode* n = &ws.lobe_nodes[piece.nodes];
        const double small = negligible();
        const LobeEstimate e = lobeRule(
            PieceSampler(map, b, x, beam, material), {n, n + 1, n + 2, n + 3, n + 4, n + 5},
            parameterArea(piece.facet), sigma, small, /*embedded=*/true);
        result.evaluations += e.evaluations;
        piece.sampled = true;
        piece.estimate = e.irradiance_w_m2;
        if (!e.ok) {
          piece.unresolved = piece.upper;  // known by its bound alone: split further
        } else if (piece.specular_upper <= small && e.diffuse_error_w_m2 < kInf) {
          // Diffuse light only (the specular part is bounded below negligible: the rule's own
          // lobe may be misplaced, the bound cannot), over a piece that is whole (lit, in view,
          // in the beam): its smooth integrand is known to within the embedded rules'
          // difference, without the children a lobe needs. The specular bound counts as error.
          piece.refined_ok = true;
          piece.refined = std::min(piece.estimate, piece.upper);
          piece.error = e.diffuse_error_w_m2 + piece.specular_upper;
          if (!(piece.estimate <= piece.upper)) piece.error = std::max(piece.error, piece.upper);
        }
      }
      if (piece.unresolved == 0.0 && !piece.refined_ok) {
        LobeNode* n = &ws.lobe_nodes[piece.nodes];
        for (int k = 0; k < 3; ++k) {  // children 0–2 hold the nine new midpoints between them
          const std::array<int, 6>& c = kChildNodes[k];
          for (int e = 0; e < 3; ++e) {
            const Vec3 mid = 0.5 * (node_bary[c[e]] + node_bary[c[(e + 1) % 3]]);
            n[c[3 + e]] = lobeNode(ws.surfaces.at(map, mid), x, beam, material);
          }
        }
        result.evaluations += 9;
        piece.refined = 0.0;
        double rule_error = 0.0;
        bool ok = true;
        for (int k = 0; k < 4; ++k) {
          const std::array<int, 6>& c = kChildNodes[k];
          const std::array<Vec3, 3> child{node_bary[c[0]], node_bary[c[1]], node_bary[c[2]]};
          const LobeEstimate e =
              lobeRule(PieceSampler(map, child, x, beam, material),
                       {n + c[0], n + c[1], n + c[2], n + c[3], n + c[4], n + c[5]},
                       0.25 * parameterArea(piece.facet), sigma, negligible());
          result.evaluations += e.evaluations;
          ok = ok && e.ok;
          piece.child_estimate[k] = e.irradiance_w_m2;
          piece.refined += e.irradiance_w_m2;
          rule_error += e.hidden_error_w_m2;
        }
        if (ok) {
          // The change under splitting, plus what the children's rule may miss that splitting
          // does not show (where a child holds its lobe, parent and child sample it alike).
          piece.refined_ok = true;
          piece.children_known = true;
          piece.error = std::abs(piece.refined - piece.estimate) + rule_error;
          // No rule may claim more than the piece's rigorous bound: beyond it the model has
          // failed, and the piece is known only to within its bound.
          if (!(piece.refined <= piece.upper)) {
            piece.refined = std::min(piece.refined, piece.upper);
            piece.error = std::max(piece.error, piece.upper);
          }
        } else {
          piece.unresolved = piece.upper;
        }
      }
      if (!piece.refined_ok) piece.error = piece.upper;
      ws.pieces[slot] = piece;
      ws.free_slots.push_back(slot);
      // Re-stored (same slot) so that its error enters the heap and the sums afresh.
      store(piece);
      continue;
    }

    // Split: unresolved pieces on their bounds alone, refined ones into their children, which
    // inherit their nodes and estimates and are refined in turn when their error (the bound,
    // until refined) is among the largest.
    if (piece.facet.depth + 1 >= opt.max_depth) {
      frozen.push_back(slot);
      result.depth_limited = true;
      if (unboundedError(piece.error)) {
        ++frozen_unbounded;
      } else {
        frozen_magnitude += piece.error;
      }
      continue;  // stays in the sums: no further work can reduce it
    }
    account(piece, -1);
    ws.free_slots.push_back(slot);
    const std::array<SubFacet, 4> children = ws.surfaces.split(map, piece.facet);
    for (int k = 0; k < 4; ++k) {
      LobePiece child = bounded(children[k], x, beam, material);
      if (child.upper == 0.0) continue;  // provably dark
      if (piece.children_known) {
        child.sampled = true;
        // Known to within its bound until refined in turn (its error is that bound).
        child.estimate = std::clamp(piece.child_estimate[k], 0.0, child.upper);
        child.nodes = static_cast<std::uint32_t>(ws.lobe_nodes.size());
        ws.lobe_nodes.resize(ws.lobe_nodes.size() + kLobeNodes);
        for (int j = 0; j < 6; ++j) {
          ws.lobe_nodes[child.nodes + j] = ws.lobe_nodes[piece.nodes + kChildNodes[k][j]];
        }
      }
      store(child);
    }
  }

  exact();
  result.irradiance_w_m2 = value();
  result.error_estimate_w_m2 = totals.magnitude_sum.value() + (totals.unbounded > 0 ? kInf : 0.0);
  result.converged = done();
  return result;
}

ObserverResult FacetIntegrator::uniform(const Vec3& observer_m, int level,
                                        IntegratorWorkspace& workspace) const {
  if (level < 0 || level > 30) throw std::invalid_argument("uniform level out of range");
  IntegratorWorkspace::Impl& ws = *workspace.impl_;
  prepareObserver(observer_m, ws);
  ObserverResult result;
  CompensatedSum total;
  for (const Candidate& lit : lit_) {
    const Vec3& x = ws.observer_local_m[lit.object];
    if (!mayFaceObserver(lit.geometry, x) ||
        !detail::visible(occluder_.get(), *target_, lit, observer_m))
      continue;
    const Beam& beam = object_beams_[lit.object];
    const Material& material = target_->materials[target_->objects[lit.object].material];
    detail::withPatchModel(*target_, lit.facet.coarse, [&](const auto& model) {
      ws.stack.clear();
      ws.stack.push_back(lit.facet);
      while (!ws.stack.empty()) {
        const SubFacet f = ws.stack.back();
        ws.stack.pop_back();
        if (f.depth == level) {
          total.add(facetIrradiance(model.template geometry<false>(f, options_.normals), x, beam,
                                    material));
          ++result.evaluations;
        } else {
          for (const SubFacet& c : model.split(f)) ws.stack.push_back(c);
        }
      }
    });
  }
  result.irradiance_w_m2 = total.value();
  return result;
}

}  // namespace glint
