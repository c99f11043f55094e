// The cubature scheme (IntegrationScheme::Cubature): a degree-7 product rule per piece of the
// exact surface map, as a rule of the refinement engine.
#include <algorithm>
#include <cmath>
#include <span>

#include "facets/detail/refine.h"
#include "facets/detail/schemes.h"
#include "facets/triangle_rule.h"

namespace glint::detail {
namespace {

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

// A piece of the surface map. It starts from its bound alone (estimate 0, error = upper): the
// rule and its check cost 25 kernel evaluations, which only resolved pieces whose bound
// matters are worth.
struct CubaturePiece {
  SubFacet facet;
  double estimate = 0.0;    // the rule's, once sampled
  double upper = 0.0;       // bound of its true contribution (+∞ if unbounded)
  double unresolved = 0.0;  // bound of the terms the rule would not resolve (0: resolved)
  double error = 0.0;       // the bound until sampled, then the rule's error (or the bound)
  bool sampled = false;

  [[nodiscard]] double value() const { return estimate; }
};

class CubatureRule {
 public:
  using Piece = CubaturePiece;
  static constexpr bool kSignedErrors = false;
  static constexpr bool kUnboundedErrorIsInfinite = false;

  CubatureRule(const ObserverSetting& s, std::span<const Candidate> candidates)
      : s_(s), candidates_(candidates), limits_(cubatureLimits()) {}

  void seed(Refinement<CubatureRule>& r) const {
    forEachSeen(s_, candidates_, [&](const Candidate& lit, const Frame& f) {
      Piece piece;
      piece.facet = lit.facet;
      PatchGeometry g = lit.geometry;
      // A candidate split by boundBall() has its corners from 1→4 subdivision; the pieces
      // here are those of the surface map, over the same barycentric triangle.
      if (lit.facet.depth > 0) {
        const SurfaceMap& map = s_.maps[lit.facet.coarse];
        piece.facet = map.subFacet(lit.facet.bary, lit.facet.depth, lit.facet.rim_edges);
        g = map.geometry(s_.target, piece.facet);
      }
      r.add(bounded(piece, g, f));
    });
  }

  [[nodiscard]] static Step next(const Piece& piece, int max_depth) {
    if (piece.facet.depth >= max_depth) return Step::Freeze;
    return !piece.sampled && piece.unresolved == 0.0 ? Step::Improve : Step::Split;
  }

  // A resolved piece: the rule and its embedded check. Their difference is the lower rule's
  // error, an overestimate of the rule's; the piece is split while it matters.
  void improve(Piece& piece, Refinement<CubatureRule>& r) const {
    const Frame f = s_.frame(s_.target.object[piece.facet.coarse]);
    const RuleResult rule =
        ruleIrradiance(s_.maps[piece.facet.coarse], piece.facet, f.observer_m, f.beam, f.material);
    r.count(rule.evaluations);
    piece.sampled = true;
    piece.estimate = rule.value;
    if (!rule.ok) piece.unresolved = piece.upper;  // known only by its bound: split further
    piece.error = std::max(std::abs(rule.value - rule.check), piece.unresolved);
  }

  // A piece the rule cannot be trusted with yet (lobe, beam edge, terminator or near field
  // unresolved), or whose rule error is still in the way: its four children replace it, each
  // known by its bound until it is resolved and sampled in turn. Most pieces near a glint are
  // proven dark this way without a sample.
  void split(const Piece& parent, Refinement<CubatureRule>& r) const {
    const Frame f = s_.frame(s_.target.object[parent.facet.coarse]);
    const SurfaceMap& map = s_.maps[parent.facet.coarse];
    for (const SubFacet& child : map.split(parent.facet)) {
      Piece piece;
      piece.facet = child;
      piece = bounded(piece, map.geometry(s_.target, child), f);
      if (piece.upper == 0.0) continue;  // provably dark
      r.add(piece);
    }
  }

 private:
  // The piece known by its bound alone.
  Piece bounded(Piece piece, const PatchGeometry& g, const Frame& f) const {
    const ContributionBound b = contributionBound(g, f.observer_m, f.beam, f.material, limits_);
    piece.upper = b.upper_w_m2;
    piece.unresolved = b.unresolved_w_m2;
    piece.error = b.upper_w_m2;
    return piece;
  }

  const ObserverSetting& s_;
  std::span<const Candidate> candidates_;
  ResolutionLimits limits_;
};

}  // namespace

ObserverResult integrateCubature(const ObserverSetting& s, std::span<const Candidate> candidates,
                                 Workspace& ws) {
  CubatureRule rule(s, candidates);
  return refine(rule, ws.kept<RefineState<CubaturePiece>>(), s.options);
}

}  // namespace glint::detail
