#pragma once
/// @file
/// @brief A reflecting material: Beckmann specular lobes plus a Lambertian part (docs/physics.md).

#include <optional>
#include <span>
#include <utility>
#include <vector>

#include "facets/beckmann.h"
#include "facets/vec3.h"

namespace glint {

/// @brief A further specular lobe of a material: its share of the light and its width.
struct SpecularLobe {
  double reflectance = 0.0;  ///< ρ of this lobe in [0, 1]
  Beckmann shape;            ///< σ
};

/// @brief f_r = Σ_k ρk Ξk(θN) / (4 cos θi cos θr) + ρd / π: the first lobe (ρs, σ) and any
/// further ones (a painted or weathered finish: a narrow specular lobe and a wider haze).
///
/// The integrator only ever needs f_r cos θi cos θr, in which the specular cosines cancel;
/// working with that product keeps the specular term finite at grazing incidence.
///
/// The light reflected is linear in f_r, so FacetIntegrator integrates a material of several
/// lobes term by term (terms()): each term is a material of one lobe, which is what the lobe
/// rule (lobe_rule.h) integrates in closed form. The bounds (contributionBound()) take every
/// lobe.
struct Material {
  Material() = default;
  /// @brief ρs and σ of the first lobe, ρd, and any further lobes.
  Material(double rho_s, double rho_d, const Beckmann& first, std::vector<SpecularLobe> more = {})
      : specular_reflectance(rho_s),
        diffuse_reflectance(rho_d),
        lobe(first),
        more_lobes(std::move(more)) {}

  double specular_reflectance = 0.0;     ///< ρs of the first lobe in [0, 1]
  double diffuse_reflectance = 0.0;      ///< ρd in [0, 1], ρd + ρs + Σ ρk ≤ 1
  Beckmann lobe;                         ///< the first specular lobe (σ)
  std::vector<SpecularLobe> more_lobes;  ///< further lobes, each with its own ρk and σk

  /// @brief f_r cos θi cos θr in 1/sr for unit normal @p n, unit directions toward the laser
  /// @p wi and toward the observer @p wo, with their cosines already computed and positive.
  [[nodiscard]] double cosineWeightedBrdf(const Vec3& n, const Vec3& wi, const Vec3& wo,
                                          double cos_i, double cos_r) const {
    double f = diffuse_reflectance * cos_i * cos_r / kPi;
    const Vec3 h = wi + wo;
    if (specular_reflectance > 0.0) f += 0.25 * specular_reflectance * lobe.xi(n, h);
    for (const SpecularLobe& l : more_lobes) {
      if (l.reflectance > 0.0) f += 0.25 * l.reflectance * l.shape.xi(n, h);
    }
    return f;
  }

  /// @brief The sum of the specular lobes' reflectances.
  [[nodiscard]] double totalSpecularReflectance() const {
    double sum = specular_reflectance;
    for (const SpecularLobe& l : more_lobes) sum += l.reflectance;
    return sum;
  }

  /// @brief The terms the integrator integrates one at a time: the first lobe with the
  /// Lambertian part, then each further lobe alone. A material of one lobe is its own one term.
  [[nodiscard]] std::vector<Material> terms() const {
    std::vector<Material> out;
    out.emplace_back(specular_reflectance, diffuse_reflectance, lobe);
    for (const SpecularLobe& l : more_lobes) out.emplace_back(l.reflectance, 0.0, l.shape);
    return out;
  }
};

/// @brief The narrowest specular lobe of @p materials (smallest σ among the lobes with a
/// reflectance, further lobes included): what sets how finely their light must be sampled by
/// direction and how far away it settles into a point source's. Nothing when none reflects
/// specularly.
inline std::optional<Beckmann> narrowestLobe(std::span<const Material> materials) {
  std::optional<Beckmann> narrowest;
  const auto consider = [&](double reflectance, const Beckmann& shape) {
    if (reflectance > 0.0 && (!narrowest || shape.sigma < narrowest->sigma)) narrowest = shape;
  };
  for (const Material& m : materials) {
    consider(m.specular_reflectance, m.lobe);
    for (const SpecularLobe& l : m.more_lobes) consider(l.reflectance, l.shape);
  }
  return narrowest;
}

}  // namespace glint
