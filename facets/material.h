#pragma once
/// @file
/// @brief A reflecting material: Beckmann specular lobes, ABg scatter, a measured table and a
/// Lambertian part (docs/physics.md).

#include <memory>
#include <optional>
#include <span>
#include <utility>
#include <vector>

#include "facets/abg_scatter.h"
#include "facets/beckmann.h"
#include "facets/brdf_table.h"
#include "facets/vec3.h"

namespace glint {

/// @brief A further specular lobe of a material: its share of the light and its width.
struct SpecularLobe {
  double reflectance = 0.0;  ///< ρ of this lobe in [0, 1]
  Beckmann shape;            ///< σ
};

/// @brief f_r = Σ_k ρk Ξk(θN) / (4 cos θi cos θr) + f_ABg + f_table + ρd / π: the first lobe
/// (ρs, σ), any further ones (a painted or weathered finish: a narrow specular lobe and a wider
/// haze), ABg scatter wings (abg_scatter.h) and a measured table (brdf_table.h), each optional.
///
/// The integrator only ever needs f_r cos θi cos θr, in which the specular cosines cancel;
/// working with that product keeps the specular term finite at grazing incidence.
///
/// The light reflected is linear in f_r, so FacetIntegrator integrates a material of several
/// lobes term by term (terms()): each term is a material of one lobe, which is what the lobe
/// rule (lobe_rule.h) integrates in closed form; ABg and the table have none, and their terms
/// are sampled (sampledOnly()). The bounds (contributionBound()) take every term.
struct Material {
  Material() = default;
  /// @brief ρs and σ of the first lobe, ρd, and any further lobes.
  Material(double rho_s, double rho_d, const Beckmann& first, std::vector<SpecularLobe> more = {})
      : specular_reflectance(rho_s),
        diffuse_reflectance(rho_d),
        lobe(first),
        more_lobes(std::move(more)) {}

  double specular_reflectance = 0.0;       ///< ρs of the first lobe in [0, 1]
  double diffuse_reflectance = 0.0;        ///< ρd in [0, 1], ρd + ρs + Σ ρk ≤ 1
  Beckmann lobe;                           ///< the first specular lobe (σ)
  std::vector<SpecularLobe> more_lobes;    ///< further lobes, each with its own ρk and σk
  std::optional<AbgScatter> abg;           ///< ABg scatter wings, if any
  std::shared_ptr<const BrdfTable> table;  ///< a measured BRDF, if any (shared: it may be large)

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
    if (abg) f += abg->cosineWeighted(n, wi, wo, cos_i, cos_r);
    if (table) f += table->cosineWeighted(n, wi, wo, cos_i, cos_r);
    return f;
  }

  /// @brief The sum of the specular lobes' reflectances.
  [[nodiscard]] double totalSpecularReflectance() const {
    double sum = specular_reflectance;
    for (const SpecularLobe& l : more_lobes) sum += l.reflectance;
    return sum;
  }

  /// @brief Whether the material has a part with no closed form in the lobe rule (ABg, a
  /// table): a term of it is integrated by sampling (the cubature rule).
  [[nodiscard]] bool sampledOnly() const { return abg.has_value() || table != nullptr; }

  /// @brief The terms the integrator integrates one at a time: the first lobe with the
  /// Lambertian part, then each further lobe alone, then the ABg scatter, then the table. A
  /// material of one lobe is its own one term; a first term that reflects nothing is left out
  /// when there are others.
  [[nodiscard]] std::vector<Material> terms() const {
    std::vector<Material> out;
    if (specular_reflectance > 0.0 || diffuse_reflectance > 0.0 ||
        (more_lobes.empty() && !sampledOnly())) {
      out.emplace_back(specular_reflectance, diffuse_reflectance, lobe);
    }
    for (const SpecularLobe& l : more_lobes) out.emplace_back(l.reflectance, 0.0, l.shape);
    if (abg) {
      Material& m = out.emplace_back(0.0, 0.0, lobe);
      m.abg = abg;
    }
    if (table) {
      Material& m = out.emplace_back(0.0, 0.0, lobe);
      m.table = table;
    }
    return out;
  }

  /// @brief The narrowest angular width (rad) of the material's directional terms (a lobe's
  /// σ, ABg's peak, a table's step): how finely its light must be sampled by direction, and how
  /// far away it settles into a point source's. Nothing when it reflects only diffusely.
  ///
  /// Given @p theta_n_min_rad, the least tilt of the half vector over the directions in
  /// question, ABg's width is that of its wings there (AbgScatter::widthBeyondRad()): they
  /// carry most of its light and are broad, which is what keeps an observer field from taking
  /// them for a narrow glint. A lobe's bound already falls to nothing away from its peak.
  [[nodiscard]] std::optional<double> narrowestWidthRad(double theta_n_min_rad = 0.0) const {
    std::optional<double> narrowest;
    const auto consider = [&](double width) {
      if (!narrowest || width < *narrowest) narrowest = width;
    };
    if (specular_reflectance > 0.0) consider(lobe.widthRad());
    for (const SpecularLobe& l : more_lobes) {
      if (l.reflectance > 0.0) consider(l.shape.widthRad());
    }
    if (abg && abg->a_per_sr > 0.0) consider(abg->widthBeyondRad(theta_n_min_rad));
    if (table) consider(table->widthRad());
    return narrowest;
  }
};

/// @brief The narrowest width of @p materials' directional terms (Material::narrowestWidthRad());
/// nothing when none reflects but diffusely.
inline std::optional<double> narrowestWidthRad(std::span<const Material> materials) {
  std::optional<double> narrowest;
  for (const Material& m : materials) {
    const std::optional<double> w = m.narrowestWidthRad();
    if (w && (!narrowest || *w < *narrowest)) narrowest = w;
  }
  return narrowest;
}

}  // namespace glint
