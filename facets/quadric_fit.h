#pragma once
/// @file
/// @brief A quadric through three vertices with prescribed normals: the paper's nine
/// constraints, solved with a rank-revealing SVD, with an honest verdict when it fails.
///
/// The nine constraints alone are always singular: the square of the facet's chord plane, P²,
/// vanishes with zero gradient at every vertex, so Q + βP² satisfies them for any β. glint
/// removes that direction by fitting in the chord-plane frame without a z² term (the member
/// that is a graph over the facet); what remains is unique for curved facets and singular for
/// flat ones, which the SVD reports.

#include <array>
#include <optional>

#include "facets/quadric.h"
#include "facets/vec3.h"

namespace glint {

/// @brief Outcome of a quadric fit. Anything but Ok means: use a PN triangle instead.
enum class QuadricFitStatus {
  Ok,              ///< a unique, well-conditioned quadric that subdivides sanely
  Singular,        ///< the constraints leave more than one quadric (e.g. a flat facet)
  IllConditioned,  ///< unique in exact arithmetic but too close to singular to trust
  Inconsistent,    ///< the quadric's gradient opposes some vertex normals, or vanishes
  Unstable,        ///< projecting edge midpoints onto it fails or moves them too far
  /// Its gradient is not bounded away from zero over the facet's ball (2 L r ≥ |∇Q| at the
  /// centroid, L the gradient's Lipschitz constant): no normal cone narrower than a hemisphere
  /// bounds the facet, and observers refine it blind.
  Unbounded,
};

/// @brief Human-readable name of a fit status, for summaries.
const char* toString(QuadricFitStatus status);

/// @brief The fitted quadric (when Ok) and the conditioning that decided it.
struct QuadricFit {
  QuadricFitStatus status = QuadricFitStatus::Singular;
  std::optional<Quadric> quadric;  ///< oriented so its gradient follows the vertex normals
  /// Second-smallest over largest singular value of the 9×9 system, whose smallest is zero by
  /// construction: how far the fit is from a second, different solution (0: singular).
  double rank_gap = 0.0;
};

/// @brief Thresholds of the fit's verdicts.
struct QuadricFitOptions {
  double singular_below = 1e-12;        ///< rank gap under which the null space is ≥ 2-D
  double ill_conditioned_below = 1e-7;  ///< rank gap under which the solution is not trusted
  double max_midpoint_shift = 0.5;      ///< edge-midpoint projection limit, in edge lengths
};

/// @brief Fits Q to vertices @p p_m with unit normals @p n: PᵀQP = 0 at each vertex (3
/// equations) and ∇Q ⟂ two tangents of each normal (6 equations), for the coefficients of
/// Eq. 3 up to scale (without the chord-normal z² term, see above). Solved in a frame centred
/// on the vertices, aligned with the chord plane and scaled to unit size, so the verdict does
/// not depend on where the facet sits, how it is turned or how large it is.
QuadricFit fitQuadric(const std::array<Vec3, 3>& p_m, const std::array<Vec3, 3>& n,
                      const QuadricFitOptions& options = {});

}  // namespace glint
