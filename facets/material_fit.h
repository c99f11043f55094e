#pragma once
/// @file
/// @brief Closed forms fitted to a measured table: Beckmann lobes, ABg scatter and a Lambertian
/// part, least squares on log f_r (docs/physics.md, "Fitting a table").

#include <string>
#include <vector>

#include "facets/brdf_table.h"
#include "facets/material.h"

namespace glint {

/// @brief Which terms a fit has.
struct MaterialFitModel {
  int lobes = 2;        ///< Beckmann lobes, 0 to 4
  bool abg = true;      ///< ABg scatter
  bool diffuse = true;  ///< a Lambertian part
};

/// @brief A fitted material and how far it is from its table.
struct MaterialFit {
  Material material;
  std::size_t nodes = 0;       ///< the table's nodes the fit saw (below 89.5° of θ)
  double rms_log_error = 0.0;  ///< RMS of ln f_fit − ln f_table over those nodes
  /// Largest |f_fit / f_table − 1| over the nodes where the table is at least 1 % of its peak:
  /// the error where the light is.
  double max_relative_error = 0.0;
  double energy = 0.0;  ///< Σ lobes' ρ + ABg's TIS + ρd: at most 1 for a scene to take it
  /// The model's terms the fit drove to nothing (below 1e-6 of the light), left out of
  /// `material`, in words ("lobe 2 (ρ 3e-12, σ 0.04)").
  std::vector<std::string> dropped;
  /// The fit's free parameters: with fewer nodes than these the table cannot settle them.
  int parameters = 0;
};

/// @brief Fits @p model to @p table by Levenberg–Marquardt on ln(f + floor) at the table's
/// nodes (floor 1e-6 of the table's peak keeps its zeros finite), from a few starting widths,
/// keeping the best. Every parameter is kept by its parametrisation in a range a scene takes
/// (ρ and ρd in [1e-12, 1], σ in [1e-4, 2], ABg's peak A/B ≤ 1e10 /sr, its width ≥ 1e-4 rad, g
/// in (0, 4)); terms driven to nothing are dropped and named.
MaterialFit fitMaterial(const BrdfTable& table, const MaterialFitModel& model);

}  // namespace glint
