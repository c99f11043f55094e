#pragma once
/// @file
/// @brief The Beckmann microfacet tilt distribution Ξ(θN) of Torrance & Sparrow (1967), as the
/// paper writes it (Eq. 8).

#include <cmath>
#include <limits>

#include "facets/vec3.h"

namespace glint {

/// @brief Ξ(θN) = exp(−tan²θN / 2σ²) / (2π σ² cos⁴θN), normalised so that ∫ Ξ cos θN dω = 1
/// over the hemisphere of microfacet normals (Beckmann with α = √2 σ).
///
/// Everything is written in s = tan²θN, using 1/cos⁴θN = (1 + s)², so no cosine is ever
/// divided by: Ξ is exactly 0 (not NaN, not Inf) at grazing angles and far outside the lobe.
struct Beckmann {
  double sigma = 0.01;  ///< RMS surface slope per axis (dimensionless), > 0

  /// @brief The lobe's angular width (rad): the tilt of the half vector at which Ξ has fallen to
  /// e^(−1/2) of its peak, σ for a narrow lobe. Directions this far apart resolve the light it
  /// reflects (the far field's lattice), and that light changes by about one part per width
  /// of the half vector's turn (the far radius): what every question about σ is asked through.
  [[nodiscard]] double widthRad() const { return sigma; }

  /// @brief Ξ in 1/sr as a function of s = tan²θN ≥ 0 (+∞ allowed, gives 0).
  [[nodiscard]] double xiFromTan2(double tan2) const {
    const double a = tan2 / (2.0 * sigma * sigma);
    // exp(-a) underflows to 0 near a = 745; stopping at 700 also keeps (1 + s)² finite.
    if (!(a < 700.0)) return 0.0;
    const double one_plus = 1.0 + tan2;
    return std::exp(-a) * one_plus * one_plus / (2.0 * kPi * sigma * sigma);
  }

  /// @brief Ξ for unit surface normal @p n and the unnormalised half vector @p h = ωi + ωo.
  /// tan²θN comes from the tangent-plane component of h, which is exact near θN = 0 where
  /// 1 − cos² would cancel.
  [[nodiscard]] double xi(const Vec3& n, const Vec3& h) const {
    const double hn = glm::dot(h, n);
    if (!(hn > 0.0)) return 0.0;
    const Vec3 ht = h - hn * n;
    return xiFromTan2(glm::dot(ht, ht) / (hn * hn));
  }

  /// @brief ln Ξ(s_lo) − ln Ξ(s_hi) for 0 ≤ s_lo ≤ s_hi (s = tan²θN): how much the lobe can change
  /// between two angles, in e-folds; +∞ once Ξ(s_hi) underflows.
  [[nodiscard]] double logRatio(double tan2_lo, double tan2_hi) const {
    if (!std::isfinite(tan2_hi)) return std::numeric_limits<double>::infinity();
    return (tan2_hi - tan2_lo) / (2.0 * sigma * sigma) +
           2.0 * (std::log1p(tan2_lo) - std::log1p(tan2_hi));
  }

  /// @brief The largest Ξ over all θN with tan²θN ≥ @p tan2_min, for conservative bounds.
  /// ln Ξ = −s/2σ² + 2 ln(1 + s) + const is concave in s with its peak at s* = 4σ² − 1, so
  /// for σ < 1/2 Ξ falls monotonically and for wider lobes it first rises to s*.
  /// A NaN @p tan2_min (an angle that could not be computed) gives the lobe's overall maximum,
  /// never 0: a bound must not prove "nothing" from a failed computation.
  [[nodiscard]] double maxXiBeyond(double tan2_min) const {
    const double s_peak = 4.0 * sigma * sigma - 1.0;
    const double s = tan2_min >= 0.0 ? tan2_min : 0.0;
    return xiFromTan2(s_peak > s ? s_peak : s);
  }
};

}  // namespace glint
