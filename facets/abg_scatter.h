#pragma once
/// @file
/// @brief ABg scatter (Harvey–Shack): the wings of a painted or weathered finish, as optical
/// design and stray-light tools fit them (docs/physics.md, "ABg scatter").

#include <cmath>

#include "facets/vec3.h"

namespace glint {

/// @brief f_r = A / (B + |β − β₀|^g) in 1/sr, where β and β₀ are the projections on the surface's
/// tangent plane of the direction toward the observer and of the mirror direction.
///
/// The mirror direction's projection is −(the laser direction's), so β − β₀ is the tangent-plane
/// part of the unnormalised half vector ωi + ωo, and |β − β₀| = (cos θi + cos θr) tan θN: ABg is
/// a function of the half vector's tilt θN, as a Beckmann lobe is, which is what lets every
/// bound of the integrator treat it alike.
struct AbgScatter {
  double a_per_sr = 0.0;  ///< A ≥ 0 (1/sr)
  double b = 1e-3;        ///< B > 0: the peak is A/B, its width about B^(1/g)
  double g = 2.0;         ///< the wings' slope, |β − β₀|^(−g), in (0, 4]

  /// @brief f_r at a distance @p x = |β − β₀| from the mirror direction.
  [[nodiscard]] double brdfAt(double x) const { return a_per_sr / (b + std::pow(x, g)); }

  /// @brief f_r cos θi cos θr (1/sr) for unit normal @p n, unit directions toward the laser
  /// @p wi and the observer @p wo, and their (positive) cosines.
  [[nodiscard]] double cosineWeighted(const Vec3& n, const Vec3& wi, const Vec3& wo, double cos_i,
                                      double cos_r) const {
    const Vec3 h = wi + wo;
    const Vec3 ht = h - glm::dot(h, n) * n;
    return brdfAt(glm::length(ht)) * cos_i * cos_r;
  }

  /// @brief The largest f_r cos θi cos θr over every pair of directions whose half vector is
  /// tilted by tan²θN ≥ @p tan2_min, with cos θi ≤ @p cos_i_max and cos θr ≤ @p cos_r_max; a
  /// NaN tilt gives the peak over those cosines (a bound never proves "nothing" from a failed
  /// computation, nor does a NaN cosine).
  ///
  /// With c = cos θi + cos θr ∈ (0, 2] and t = tan θN, cos θi cos θr ≤ c²/4 and
  /// |β − β₀| = c t, so the product is at most A c² / (4 (B + cᵍ tᵍ)): increasing in c for
  /// g ≤ 2, and for g > 2 largest at cᵍ tᵍ = 2B / (g − 2) if that c is below the largest.
  /// Near grazing the cosines themselves decide: f_r ≤ A/B, so the product is at most
  /// (A/B) cos θi cos θr, which vanishes at the horizon and the terminator as the term does.
  [[nodiscard]] double maxBeyond(double tan2_min, double cos_i_max = 1.0,
                                 double cos_r_max = 1.0) const {
    const auto in_range = [](double cos_max) {
      return std::isnan(cos_max) ? 1.0 : std::fmin(1.0, std::fmax(0.0, cos_max));
    };
    const double ci = in_range(cos_i_max), cr = in_range(cos_r_max);
    const double by_cosines = a_per_sr / b * ci * cr;
    const double tg = tan2_min > 0.0 ? std::pow(tan2_min, 0.5 * g) : 0.0;
    if (std::isinf(tg)) return 0.0;
    const double c_max = ci + cr;
    double c = c_max;
    if (g > 2.0 && tg > 0.0) c = std::fmin(c_max, std::pow(2.0 * b / ((g - 2.0) * tg), 1.0 / g));
    return std::fmin(by_cosines, a_per_sr * c * c / (4.0 * (b + std::pow(c, g) * tg)));
  }

  /// @brief The tilt of the half vector over which the peak changes by about an e-fold (rad):
  /// for g ≥ 1, |d ln f / dx| peaks at (g − 1)^((g − 1)/g) / B^(1/g) ≤ g / B^(1/g), and
  /// |dx / dθN| ≤ 2. (For g < 1 the peak is a cusp; B^(1/g) still sets where it stands out.)
  [[nodiscard]] double widthRad() const { return 0.5 * std::pow(b, 1.0 / g) / std::fmax(1.0, g); }

  /// @brief The same width for half vectors tilted by at least @p theta_n_min_rad: away from the
  /// peak f falls as a power of sin θN, so it changes by an e-fold over at least θN / g.
  [[nodiscard]] double widthBeyondRad(double theta_n_min_rad) const {
    return std::fmax(widthRad(), theta_n_min_rad / std::fmax(1.0, g));
  }

  /// @brief The total integrated scatter at normal incidence, 2π A ∫₀¹ ρ / (B + ρᵍ) dρ: the
  /// hemispherical reflectance of the ABg term at its largest, since a disc of directions
  /// centred on the peak of a radially falling f holds more of it than any shifted disc
  /// (oblique incidence shifts β₀ off the unit disc's centre).
  [[nodiscard]] double totalIntegratedScatter() const;
};

}  // namespace glint
