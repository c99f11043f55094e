#pragma once
/// @file
/// @brief The reflection kernel (the paper's Eq. 1) and a conservative bound of what a piece of
/// surface can send to an observer, with the tests that let whole facets be skipped.

#include <array>
#include <cmath>

#include "facets/beam.h"
#include "facets/material.h"
#include "facets/patch.h"

namespace glint {

/// @brief The part of a triangle where two functions, linear between their corner values, are
/// both positive: its area as a fraction of the triangle's and its barycentric centroid.
struct ClippedTriangle {
  double fraction = 0.0;
  Vec3 centroid_bary{1.0 / 3.0};
};
ClippedTriangle clipTriangle(const std::array<double, 3>& a, const std::array<double, 3>& b);

/// @brief Eq. (1) for a point sample: Φ_A f_r cos θi cos θr / d² with Φ_A = E_beam · area,
/// attenuated by exp(−μ d) along the reflected path (μ = @p return_extinction_per_m).
inline double pointIrradiance(const Vec3& x_m, const Vec3& normal, double area_m2,
                              const Vec3& observer_m, const Beam::Sample& beam_at,
                              const Material& material, double return_extinction_per_m) {
  const Vec3 to_observer = observer_m - x_m;
  const double cos_r_d = glm::dot(normal, to_observer);  // cos θr · d
  const double cos_i = glm::dot(normal, beam_at.toward_laser);
  if (!(cos_r_d > 0.0) || !(cos_i > 0.0) || beam_at.irradiance_w_m2 == 0.0) return 0.0;
  const double d2 = glm::dot(to_observer, to_observer);
  const double d = std::sqrt(d2);
  const double f = material.cosineWeightedBrdf(normal, beam_at.toward_laser, to_observer / d, cos_i,
                                               cos_r_d / d);
  const double e = beam_at.irradiance_w_m2 * area_m2 * f / d2;
  return return_extinction_per_m > 0.0 ? e * std::exp(-return_extinction_per_m * d) : e;
}

/// @brief E_O of Eq. (1) in W/m² for one (sub)facet: the beam power on it, Φ_A = E_beam(x_C)·A,
/// times f_r cos θi cos θr / |x_C − x_O|². One call is one "reflection calculation" in the
/// paper's count.
///
/// The specular term does not fade at the terminator or the observer's horizon, it stops there
/// (f_r cos θi cos θr = ρs Ξ / 4), so a facet across either line is clipped to its lit,
/// visible part, with cos θi and cos θr modelled linearly between its corners, and sampled at
/// that part's centroid. A centre sample would be wrong by up to the whole facet there, an
/// error that only shrinks as fast as the facets' width.
inline double facetIrradiance(const PatchGeometry& g, const Vec3& observer_m, const Beam& beam,
                              const Material& material) {
  const Beam::Sample beam_at = beam.at(g.centre_m);
  if (beam_at.irradiance_w_m2 == 0.0) return 0.0;
  std::array<double, 3> lit, seen;
  int n_lit = 0, n_seen = 0;
  for (int k = 0; k < 3; ++k) {
    lit[k] = glm::dot(g.corner_normal[k], beam_at.toward_laser);
    seen[k] = glm::dot(g.corner_normal[k], observer_m - g.corner_m[k]);
    n_lit += lit[k] > 0.0 ? 1 : 0;
    n_seen += seen[k] > 0.0 ? 1 : 0;
  }
  if (n_lit == 3 && n_seen == 3) {
    return pointIrradiance(g.centre_m, g.normal, g.area_m2, observer_m, beam_at, material,
                           beam.return_extinction_per_m);
  }
  if (n_lit == 0 || n_seen == 0) return 0.0;
  const ClippedTriangle part = clipTriangle(lit, seen);
  if (part.fraction == 0.0) return 0.0;
  const Vec3& w = part.centroid_bary;
  const Vec3 x = w[0] * g.corner_m[0] + w[1] * g.corner_m[1] + w[2] * g.corner_m[2];
  const auto n = tryNormalize(w[0] * g.corner_normal[0] + w[1] * g.corner_normal[1] +
                              w[2] * g.corner_normal[2]);
  if (!n) return 0.0;
  return pointIrradiance(x, *n, part.fraction * g.area_m2, observer_m, beam.at(x), material,
                         beam.return_extinction_per_m);
}

/// @brief When a facet's sample can stand for the whole facet: the specular lobe may only vary
/// so much over it, and it must be small against its distance to the observer.
struct ResolutionLimits {
  double lobe = 1.0;  ///< normal spread (cone + half-vector spread) ≤ lobe × σ
  /// Where the kernel clips a facet at the terminator or the observer's horizon, the lobe must
  /// also be nearly flat over it: ln(Ξ_max / Ξ_min) ≤ this. A width of σ still lets Ξ change by
  /// e⁴ on a flank at 2σ, and a sample of the part left after clipping then misleads the
  /// one-level error estimate; away from the cut the sample errors cancel and σ is enough.
  double clipped_log_variation = 1.0;
  double near_field = 0.1;  ///< bounding radius ≤ near_field × distance to the observer
  /// The rule clips its pieces at the beam's edges itself: an edge crossing the patch leaves
  /// it resolved.
  bool clips_beam_edges = false;
};

/// @brief An upper bound of what a patch can send to an observer, and of the part of it that
/// its centre sample cannot be trusted with.
struct ContributionBound {
  double upper_w_m2 = 0.0;  ///< all of it; +∞ when the observer is inside the patch's ball
  /// The bound of the terms the sample does not resolve: the specular term when the patch is
  /// wider than the lobe (or, where it is clipped, not flat enough), both terms near a beam
  /// edge or in the near field. 0: resolved.
  double unresolved_w_m2 = 0.0;
  double specular_w_m2 = 0.0;  ///< the specular term's share of upper_w_m2

  [[nodiscard]] bool resolved() const { return unresolved_w_m2 == 0.0; }
};

/// @brief Bounds the irradiance at @p observer_m from every point of the curved patch @p g:
/// the beam's maximum over the patch's ball, its largest possible lobe value (the smallest θN
/// any normal of the cone and band can make with any half vector the ball allows:
/// minHalfVectorAngle()), its area bound and its nearest distance, for the specular and diffuse
/// terms separately; 0 where no normal of the patch can both face the laser and be seen
/// (lightVerdict(), mayFaceObserver()). Requires the bound fields of @p g.
///
/// With @p observer_radius_m > 0 the bound holds for every observer in the ball of that radius
/// around @p observer_m (a block of the observer field): the half vector may then also turn by
/// what the observer ball subtends. (`unresolved_w_m2` keeps its meaning for a point observer.)
ContributionBound contributionBound(const PatchGeometry& g, const Vec3& observer_m,
                                    const Beam& beam, const Material& material,
                                    const ResolutionLimits& limits, double observer_radius_m = 0.0);

/// @brief A lower bound (rad) of θN, the angle between any normal of patch @p g and the half
/// vector ωi + ωo at any of its points toward any observer within @p observer_radius_m of
/// @p observer_m: the larger of what its normal cone and its normal band allow (0 where
/// neither proves anything, or the observer is inside the ball). contributionBound() takes the
/// lobe's largest value beyond this angle. Requires the bound fields of @p g.
double minHalfVectorAngle(const PatchGeometry& g, const Vec3& observer_m, const Beam& beam,
                          double observer_radius_m = 0.0);

/// @brief False only when no normal of the patch can face any observer within
/// @p observer_radius_m of @p observer_m from any point of it: such a facet costs them nothing.
bool mayFaceObserver(const PatchGeometry& g, const Vec3& observer_m,
                     double observer_radius_m = 0.0);

/// @brief Why a facet cannot be lit, if it cannot.
enum class LightVerdict { MayBeLit, FacesAway, OutsideBeam };

/// @brief Whether any point of the patch can receive the beam on its reflecting side.
LightVerdict lightVerdict(const PatchGeometry& g, const Beam& beam);

}  // namespace glint
