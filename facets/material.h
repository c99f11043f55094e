#pragma once
/// @file
/// @brief A reflecting material: Beckmann specular lobe plus a Lambertian part (docs/physics.md).

#include <optional>
#include <span>

#include "facets/beckmann.h"
#include "facets/vec3.h"

namespace glint {

/// @brief f_r = ρs Ξ(θN) / (4 cos θi cos θr) + ρd / π.
///
/// The integrator only ever needs f_r cos θi cos θr, in which the specular cosines cancel;
/// working with that product keeps the specular term finite at grazing incidence.
struct Material {
  double specular_reflectance = 0.0;  ///< ρs in [0, 1]
  double diffuse_reflectance = 0.0;   ///< ρd in [0, 1], ρs + ρd ≤ 1
  Beckmann lobe;                      ///< the specular lobe (σ)

  /// @brief f_r cos θi cos θr in 1/sr for unit normal @p n, unit directions toward the laser
  /// @p wi and toward the observer @p wo, with their cosines already computed and positive.
  [[nodiscard]] double cosineWeightedBrdf(const Vec3& n, const Vec3& wi, const Vec3& wo,
                                          double cos_i, double cos_r) const {
    double f = diffuse_reflectance * cos_i * cos_r / kPi;
    if (specular_reflectance > 0.0) f += 0.25 * specular_reflectance * lobe.xi(n, wi + wo);
    return f;
  }
};

/// @brief The narrowest specular lobe of @p materials (smallest σ among those with a specular
/// part): what sets how finely their light must be sampled by direction and how far away it
/// settles into a point source's. Nothing when none reflects specularly.
inline std::optional<Beckmann> narrowestLobe(std::span<const Material> materials) {
  std::optional<Beckmann> narrowest;
  for (const Material& m : materials) {
    if (m.specular_reflectance > 0.0 && (!narrowest || m.lobe.sigma < narrowest->sigma))
      narrowest = m.lobe;
  }
  return narrowest;
}

}  // namespace glint
