// The lobe scheme (IntegrationScheme::Lobe): the lobe rule (lobe_rule.h) per piece of the exact
// surface map, its error the change under one 1→4 split, as a rule of the refinement engine.
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <vector>

#include "facets/detail/refine.h"
#include "facets/detail/schemes.h"
#include "facets/lobe_rule.h"

namespace glint::detail {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// A piece of the lobe scheme. Its six nodes (and, once refined, the nine new nodes of its
// children) live in the node pool, so the children inherit them.
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
  bool refined_ok = false;  // value and error known (by its children, or embedded)
  // Value and error from the coarse facet's diffuse moments, not yet sampled: where the error is
  // among the largest, the facet is sampled as any other (and keeps the moments until then).
  bool from_moments = false;
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

// The nodes of one observer's pieces, kLobeNodes per sampled piece (kept in the workspace).
struct LobeNodePool {
  std::vector<LobeNode> nodes;
};

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

class LobeRule {
 public:
  using Piece = LobePiece;
  static constexpr bool kSignedErrors = false;
  static constexpr bool kUnboundedErrorIsInfinite = true;

  LobeRule(const ObserverSetting& s, std::span<const Candidate> candidates, SurfaceCache& surfaces,
           std::vector<LobeNode>& pool)
      : s_(s), candidates_(candidates), surfaces_(surfaces), pool_(pool) {
    pool_.clear();
  }

  void seed(Refinement<LobeRule>& r) {
    auto consider = [&](const Candidate& lit) {
      const Frame f = s_.frame(lit.object);
      if (!mayFaceObserver(lit.geometry, f.observer_m)) return;
      // A candidate split by boundBall() has its corners from 1→4 subdivision; the pieces
      // here are those of the surface map, over the same barycentric triangle. A coarse facet's
      // corners are the map's own (it interpolates them), so it needs no lookup.
      const SubFacet facet = lit.facet.depth == 0
                                 ? lit.facet
                                 : surfaces_.subFacet(s_.maps[lit.facet.coarse], lit.facet.bary,
                                                      lit.facet.depth, lit.facet.rim_edges);
      const PatchGeometry g = surfaces_.geometry(s_.target, s_.maps[facet.coarse], facet);
      Piece piece = bounded(facet, g, f);
      // The occlusion ray last: of a mesh's thousands of lit facets an observer's bound keeps a
      // few, and the ray costs more than the bound.
      if (piece.upper == 0.0 || !s_.visible(lit)) return;
      if (lit.facet.depth == 0) fromMoments(piece, g, f);
      r.add(piece);
    };
    if (s_.clusters != nullptr && candidates_.data() == s_.lit.data()) {
      // Every lit facet: through the hierarchy, so that a run of them dark for this observer
      // costs one bound. In their order whatever is pruned (the totals then add up alike).
      forEachLitCandidate(
          *s_.clusters, s_.lit,
          [&](const LitClusters::Node& node) {
            const Frame f = s_.frame(node.object);
            return contributionBound(node.geometry, f.observer_m, f.beam, f.material,
                                     lobeLimits(f.material.lobe.sigma))
                       .upper_w_m2 == 0.0;
          },
          consider);
    } else {
      for (const Candidate& lit : candidates_) consider(lit);
    }
  }

  [[nodiscard]] static Step next(const Piece& piece, int max_depth) {
    if (piece.unresolved == 0.0 && (!piece.refined_ok || piece.from_moments)) return Step::Improve;
    return piece.facet.depth + 1 >= max_depth ? Step::Freeze : Step::Split;
  }

  // Samples the piece (if its nodes are not inherited) and, unless its light is diffuse and its
  // embedded estimate settles it, its four children: the change is the piece's error estimate,
  // and the children's sum its value.
  void improve(Piece& piece, Refinement<LobeRule>& r) {
    if (piece.from_moments) {  // the moments' error was too large: sampled as any other piece
      piece.from_moments = false;
      piece.refined_ok = false;
      piece.refined = piece.estimate = 0.0;
    }
    const Frame f = s_.frame(s_.target.object[piece.facet.coarse]);
    const SurfaceMap& map = s_.maps[piece.facet.coarse];
    const double sigma = f.material.lobe.sigma;
    // A piece whose specular term is below this is not worth its sigma points: a hundredth of
    // the error budget shared among the pieces (the running total may still grow: the budget
    // only rises, so this errs small).
    const double negligible = 0.01 * r.budget() / static_cast<double>(r.livePieces() + 16);
    const auto& b = piece.facet.bary;
    const std::array<Vec3, 6> node_bary{
        b[0], b[1], b[2], 0.5 * (b[0] + b[1]), 0.5 * (b[1] + b[2]), 0.5 * (b[2] + b[0])};
    if (!piece.sampled) {
      piece.nodes = static_cast<std::uint32_t>(pool_.size());
      pool_.resize(pool_.size() + kLobeNodes);
      for (int j = 0; j < 6; ++j) {
        pool_[piece.nodes + j] =
            lobeNode(surfaces_.at(map, node_bary[j]), f.observer_m, f.beam, f.material);
      }
      r.count(6);
      const LobeNode* n = &pool_[piece.nodes];
      const LobeEstimate e = lobeRule(PieceSampler(map, b, f.observer_m, f.beam, f.material),
                                      {n, n + 1, n + 2, n + 3, n + 4, n + 5},
                                      parameterArea(piece.facet), sigma, negligible,
                                      /*embedded=*/true);
      r.count(e.evaluations);
      piece.sampled = true;
      piece.estimate = e.irradiance_w_m2;
      if (!e.ok) {
        piece.unresolved = piece.upper;  // known by its bound alone: split further
      } else if (piece.specular_upper <= negligible && e.diffuse_error_w_m2 < kInf) {
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
      LobeNode* n = &pool_[piece.nodes];
      for (int k = 0; k < 3; ++k) {  // children 0–2 hold the nine new midpoints between them
        const std::array<int, 6>& c = kChildNodes[k];
        for (int e = 0; e < 3; ++e) {
          const Vec3 mid = 0.5 * (node_bary[c[e]] + node_bary[c[(e + 1) % 3]]);
          n[c[3 + e]] = lobeNode(surfaces_.at(map, mid), f.observer_m, f.beam, f.material);
        }
      }
      r.count(9);
      piece.refined = 0.0;
      double rule_error = 0.0;
      bool ok = true;
      for (int k = 0; k < 4; ++k) {
        const std::array<int, 6>& c = kChildNodes[k];
        const std::array<Vec3, 3> child{node_bary[c[0]], node_bary[c[1]], node_bary[c[2]]};
        const LobeEstimate e =
            lobeRule(PieceSampler(map, child, f.observer_m, f.beam, f.material),
                     {n + c[0], n + c[1], n + c[2], n + c[3], n + c[4], n + c[5]},
                     0.25 * parameterArea(piece.facet), sigma, negligible);
        r.count(e.evaluations);
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
  }

  // Unresolved pieces are split on their bounds alone, refined ones into their children, which
  // inherit their nodes and estimates and are refined in turn when their error (the bound,
  // until refined) is among the largest.
  void split(const Piece& parent, Refinement<LobeRule>& r) {
    const Frame f = s_.frame(s_.target.object[parent.facet.coarse]);
    const std::array<SubFacet, 4> children =
        surfaces_.split(s_.maps[parent.facet.coarse], parent.facet);
    for (int k = 0; k < 4; ++k) {
      Piece child = bounded(children[k], f);
      if (child.upper == 0.0) continue;  // provably dark
      if (parent.children_known) {
        child.sampled = true;
        // Known to within its bound until refined in turn (its error is that bound).
        child.estimate = std::clamp(parent.child_estimate[k], 0.0, child.upper);
        child.nodes = static_cast<std::uint32_t>(pool_.size());
        pool_.resize(pool_.size() + kLobeNodes);
        for (int j = 0; j < 6; ++j) {
          pool_[child.nodes + j] = pool_[parent.nodes + kChildNodes[k][j]];
        }
      }
      r.add(child);
    }
  }

 private:
  // A whole coarse facet far from the observer whose specular part is bounded below what its
  // diffuse moments leave uncertain: known from them (diffuse_moments.h) to within their error
  // and the specular bound, without a sample. Where that error is among the largest, the facet
  // is sampled as if it had never had them (the remainder bound is a worst case; the rules on
  // the whole facet are cheaper than four children).
  // @p g bounds the facet as its map places it (the piece's own bounds).
  void fromMoments(Piece& piece, const PatchGeometry& g, const Frame& f) const {
    if (s_.diffuse_moments == nullptr || !(f.material.diffuse_reflectance > 0.0) ||
        f.beam.return_extinction_per_m > 0.0) {
      return;
    }
    const SurfaceMap& map = s_.maps[piece.facet.coarse];
    const std::optional<DiffuseEstimate> e =
        diffuseFromMoments(s_.diffuse_moments->get(map, g, f.beam, f.material), g, f.observer_m);
    if (!e || !(piece.specular_upper <= e->error_w_m2)) return;
    piece.refined_ok = true;
    piece.from_moments = true;
    piece.refined = std::min(e->irradiance_w_m2, piece.upper);
    piece.estimate = piece.refined;
    piece.error = e->error_w_m2 + piece.specular_upper;
    // Beyond the rigorous bound the model has failed: known only to within that bound.
    if (!(e->irradiance_w_m2 <= piece.upper)) piece.error = std::max(piece.error, piece.upper);
  }

  // The piece known by its bound alone.
  Piece bounded(const SubFacet& facet, const Frame& f) {
    return bounded(facet, surfaces_.geometry(s_.target, s_.maps[facet.coarse], facet), f);
  }
  // The same, its bound geometry @p g already at hand.
  static Piece bounded(const SubFacet& facet, const PatchGeometry& g, const Frame& f) {
    const ContributionBound b =
        contributionBound(g, f.observer_m, f.beam, f.material, lobeLimits(f.material.lobe.sigma));
    Piece piece;
    piece.facet = facet;
    piece.upper = b.upper_w_m2;
    piece.specular_upper = b.specular_w_m2;
    piece.unresolved = b.unresolved_w_m2;
    piece.error = b.upper_w_m2;
    return piece;
  }

  const ObserverSetting& s_;
  std::span<const Candidate> candidates_;
  SurfaceCache& surfaces_;
  std::vector<LobeNode>& pool_;
};

}  // namespace

ObserverResult integrateLobe(const ObserverSetting& s, std::span<const Candidate> candidates,
                             Workspace& ws) {
  LobeRule rule(s, candidates, ws.surfaces, ws.kept<LobeNodePool>().nodes);
  return refine(rule, ws.kept<RefineState<LobePiece>>(), s.options);
}

}  // namespace glint::detail
