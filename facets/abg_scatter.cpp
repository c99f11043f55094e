#include "facets/abg_scatter.h"

#include <array>

namespace glint {

double AbgScatter::totalIntegratedScatter() const {
  // ∫₀¹ ρ / (B + ρᵍ) dρ = ∫ ρ² / (B + ρᵍ) d(ln ρ): in ln ρ the integrand is a smooth step
  // (ρ² below the shoulder ρ ≈ B^(1/g), ρ^(2−g) above it), which composite 4-point
  // Gauss–Legendre panels of width 0.1 resolve to ~1e-12. Below ρ = e⁻⁴⁰ what is left is
  // at most ∫ ρ / B dρ = e⁻⁸⁰ / 2B, nothing for any B ≥ 1e-20.
  constexpr std::array<double, 4> kNode{-0.8611363115940526, -0.3399810435848563,
                                        0.3399810435848563, 0.8611363115940526};
  constexpr std::array<double, 4> kWeight{0.3478548451374538, 0.6521451548625461,
                                          0.6521451548625461, 0.3478548451374538};
  constexpr double kLow = -40.0;
  constexpr int kPanels = 400;
  constexpr double kHalf = 0.5 * (0.0 - kLow) / kPanels;
  double sum = 0.0;
  for (int p = 0; p < kPanels; ++p) {
    const double mid = kLow + (2 * p + 1) * kHalf;
    for (int k = 0; k < 4; ++k) {
      const double rho = std::exp(mid + kHalf * kNode[k]);
      sum += kWeight[k] * kHalf * rho * rho / (b + std::pow(rho, g));
    }
  }
  return 2.0 * kPi * a_per_sr * sum;
}

}  // namespace glint
