// The paper's scheme (IntegrationScheme::Paper): a one-point rule per sub-facet, split 1→4
// while the estimate changes (Bailey et al. 2010, §2), as a rule of the refinement engine.
#include <array>
#include <cmath>

#include "facets/detail/patch_models.h"
#include "facets/detail/refine.h"
#include "facets/detail/schemes.h"

namespace glint::detail {
namespace {

// A piece of the paper's scheme: a sub-facet, its own centre estimate and, once refined, the
// estimates of its four children (whose positions split() regenerates on demand, which is
// cheaper than storing them).
//
// Resolved pieces with children (their samples resolve a smooth integrand) account their error
// as the signed change ΔE = E'_O − E_O (refine.h's Totals). Every other piece contributes a
// magnitude: its bound U until it has children, then max(|ΔE|, U_unresolved), U_unresolved
// bounding the terms its samples may have missed. A resolved piece whose |ΔE| is negligible
// even summed over every piece also counts as a magnitude: it needs no credit for
// cancellation, and the level-by-level sweep of the signed pieces is spared the places that do
// not matter.
struct PaperPiece {
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

  [[nodiscard]] double value() const { return has_children ? refined : estimate; }
  [[nodiscard]] bool signedError() const {
    return has_children && unresolved == 0.0 && significant;
  }
  [[nodiscard]] double change() const { return refined - estimate; }
};

class PaperRule {
 public:
  using Piece = PaperPiece;
  static constexpr bool kSignedErrors = true;
  static constexpr bool kUnboundedErrorIsInfinite = false;

  PaperRule(const ObserverSetting& s, std::span<const Candidate> candidates)
      : s_(s), candidates_(candidates) {}

  void seed(Refinement<PaperRule>& r) const {
    forEachSeen(s_, candidates_, [&](const Candidate& lit, const Frame& f) {
      Piece piece;
      piece.facet = lit.facet;
      piece.estimate = facetIrradiance(lit.geometry, f.observer_m, f.beam, f.material);
      r.count(1);
      const ContributionBound b =
          contributionBound(lit.geometry, f.observer_m, f.beam, f.material, s_.options.resolution);
      piece.upper = b.upper_w_m2;
      piece.unresolved = b.unresolved_w_m2;
      piece.error = b.upper_w_m2;
      r.add(piece);
    });
  }

  [[nodiscard]] static Step next(const Piece& piece, int max_depth) {
    // Children are evaluated one level below the piece, and split only where they may be
    // evaluated in turn.
    if (!piece.has_children) return piece.facet.depth >= max_depth ? Step::Freeze : Step::Improve;
    return piece.facet.depth + 1 >= max_depth ? Step::Freeze : Step::Split;
  }

  // The paper's step: evaluate the four children, E'_O = Σ E_On, ΔE_O = E'_O − E_O.
  void improve(Piece& piece, Refinement<PaperRule>& r) const {
    const Frame f = s_.frame(s_.target.object[piece.facet.coarse]);
    withPatchModel(s_.target, piece.facet.coarse, [&](const auto& model) {
      const std::array<SubFacet, 4> children = model.split(piece.facet);
      piece.refined = 0.0;
      for (int k = 0; k < 4; ++k) {
        const PatchGeometry g = model.template geometry<true>(children[k], s_.options.normals);
        piece.child_estimate[k] = facetIrradiance(g, f.observer_m, f.beam, f.material);
        const ContributionBound b =
            contributionBound(g, f.observer_m, f.beam, f.material, s_.options.resolution);
        piece.child_upper[k] = b.upper_w_m2;
        piece.child_unresolved[k] = b.unresolved_w_m2;
        piece.refined += piece.child_estimate[k];
      }
    });
    r.count(4);
    piece.has_children = true;
    const double delta = std::abs(piece.refined - piece.estimate);
    piece.error = std::max(delta, piece.unresolved);
    piece.significant = delta > 0.1 * r.budget() / static_cast<double>(r.livePieces());
  }

  // The piece replaced by its children; each is refined in turn when its error (its bound,
  // until it has children of its own) is among the largest.
  void split(const Piece& parent, Refinement<PaperRule>& r) const {
    const std::array<SubFacet, 4> children = glint::split(s_.target, parent.facet);
    for (int k = 0; k < 4; ++k) {
      Piece child;
      child.facet = children[k];
      child.estimate = parent.child_estimate[k];
      child.upper = parent.child_upper[k];
      child.unresolved = parent.child_unresolved[k];
      child.error = child.upper;
      r.add(child);
    }
  }

 private:
  const ObserverSetting& s_;
  std::span<const Candidate> candidates_;
};

}  // namespace

ObserverResult integratePaper(const ObserverSetting& s, std::span<const Candidate> candidates,
                              Workspace& ws) {
  PaperRule rule(s, candidates);
  return refine(rule, ws.kept<RefineState<PaperPiece>>(), s.options);
}

}  // namespace glint::detail
