#pragma once
/// @file
/// @brief A measured isotropic BRDF: a table over (θi, θo, Δφ), interpolated, with a bound of
/// what it can reflect that every cell is proven under (docs/physics.md, "Measured tables").

#include <cstddef>
#include <cstdint>
#include <vector>

#include "facets/vec3.h"

namespace glint {

/// @brief f_r(θi, θo, Δφ) in 1/sr on a rectilinear grid, interpolated as the integrator needs
/// it: g = f_r cos θi cos θr, a monotone cubic in each angle between the nodes. C¹, so that the
/// cubature rule converges on it as on a smooth BRDF, and in each cell between its corners'
/// values, so that they bound it; and g stays finite where a microfacet BRDF's f_r grows as
/// 1 / (cos θi cos θr) toward grazing.
///
/// Δφ is the azimuth of the direction toward the observer from that of the direction toward the
/// laser: 180° holds the mirror direction, 0° the laser itself. An isotropic BRDF is even in
/// Δφ, so the table gives it over [0°, 180°]. Beyond its nodes the table holds f_r at its
/// edges, out to θ = 90° (where g is 0) and over Δφ in [0°, 180°], on nodes 1° apart.
///
/// What the integrator's bounds need is the largest g for half vectors tilted by at least some
/// θN (as for a Beckmann lobe): in each cell g is at most its largest corner, and tan θN at most
/// the largest tangent-plane part of ωi + ωo over its least normal part; the envelope of
/// those cell bounds over θN, and a coarser one over θN, θi and θo together, give maxBeyond().
class BrdfTable {
 public:
  /// @brief A table of @p values_per_sr, θi major then θo then Δφ, on the strictly increasing
  /// nodes @p theta_i_rad and @p theta_o_rad in [0, π/2] and @p delta_phi_rad in [0, π].
  /// @throws std::invalid_argument naming what is wrong (a node out of order or range, a value
  /// negative or not finite, a count that does not match).
  BrdfTable(std::vector<double> theta_i_rad, std::vector<double> theta_o_rad,
            std::vector<double> delta_phi_rad, std::vector<double> values_per_sr);

  /// @brief What the constructor takes in memory at its peak for these nodes, besides the
  /// values handed to it (bytes): the completed grid's values and each cell's bound while the
  /// envelope is built (the nodes are checked by the constructor, not here).
  static std::uint64_t memoryBytes(const std::vector<double>& theta_i_rad,
                                   const std::vector<double>& theta_o_rad,
                                   const std::vector<double>& delta_phi_rad);

  /// @brief f_r at the given angles (clamped to the domain; Δφ taken as |Δφ|); 0 at grazing.
  [[nodiscard]] double brdf(double theta_i_rad, double theta_o_rad, double delta_phi_rad) const;

  /// @brief g = f_r cos θi cos θr (1/sr) at the given angles, as brdf() takes them.
  [[nodiscard]] double cosineWeightedAt(double theta_i_rad, double theta_o_rad,
                                        double delta_phi_rad) const;

  /// @brief g = f_r cos θi cos θr (1/sr) for unit normal @p n, unit directions toward the laser
  /// @p wi and the observer @p wo; their (positive) cosines are the material's common signature
  /// (the angles are taken from the tangent-plane parts, exact near the normal).
  [[nodiscard]] double cosineWeighted(const Vec3& n, const Vec3& wi, const Vec3& wo, double cos_i,
                                      double cos_r) const;

  /// @brief The largest g of the interpolant over every pair of directions whose half vector
  /// is tilted by tan²θN ≥ @p tan2_min, with θi ≤ @p theta_i_max_rad and θo ≤
  /// @p theta_o_max_rad; a NaN tilt gives the largest of all. (Away from grazing, the bright
  /// cells a table holds toward grazing forward scatter, where θN is ill-conditioned, do not
  /// count.)
  [[nodiscard]] double maxBeyond(double tan2_min, double theta_i_max_rad = 0.5 * kPi,
                                 double theta_o_max_rad = 0.5 * kPi) const;

  /// @brief A factor ≤ 1 by which maxBeyond() may be multiplied when every θi is at least
  /// @p theta_i_min_rad and every θo at least @p theta_o_min_rad: g vanishes at grazing, and in
  /// the last cell of an axis, of width h, the monotone cubic from g₀ to 0 stays below
  /// 1.25 g₀ (π/2 − θ) / h (its end slopes are at most 3× the secant). Without it a flat facet
  /// seen edge-on keeps its whole bound however finely it is split.
  [[nodiscard]] double grazingFactor(double theta_i_min_rad, double theta_o_min_rad) const;

  /// @brief Half the finest step of the grid as given (rad): the interpolant changes on no
  /// finer scale of the directions, and the normal turns the reflected direction twice as fast.
  [[nodiscard]] double widthRad() const { return width_rad_; }

  /// @brief ∫ f_r cos θo dω over the outgoing hemisphere for light from @p theta_i_rad.
  [[nodiscard]] double hemisphericalReflectance(double theta_i_rad) const;

  /// @brief The largest hemispherical reflectance found at the nodes of θi below grazing and at
  /// three points between each two, and its θi (rad): the energy check of a table.
  struct Reflectance {
    double value = 0.0;
    double theta_i_rad = 0.0;
  };
  [[nodiscard]] Reflectance maxHemisphericalReflectance() const;

  /// @brief The grid's nodes per axis, as given (before completion): θi, θo, Δφ.
  [[nodiscard]] std::size_t givenNodes(int axis) const { return given_[axis].size(); }
  /// @brief The nodes of axis @p axis as given (rad): θi, θo, Δφ.
  [[nodiscard]] const std::vector<double>& givenAxis(int axis) const { return given_[axis]; }

 private:
  [[nodiscard]] double value(std::size_t i, std::size_t o, std::size_t p) const {
    return values_[(i * theta_o_.size() + o) * delta_phi_.size() + p];
  }
  void buildEnvelope();
  // ∫ @p brdf_at(θo, Δφ) cos θo dω over the outgoing hemisphere.
  template <class Brdf>
  double overOutgoing(Brdf&& brdf_at) const;

  std::vector<double> theta_i_, theta_o_, delta_phi_;
  std::vector<double> values_;
  std::vector<double> given_[3];
  double width_rad_ = 0.0;
  // maxBeyond(): θN_max of the cells, decreasing, and the largest cell bound among them so far.
  std::vector<double> envelope_theta_n_;
  std::vector<double> envelope_max_;
  // The same bound over θN, θi and θo at once, each on kCoarseLevels levels of [0, π/2]: the
  // largest cell bound among the cells reaching each θN level or beyond, and starting at or
  // below each level of θi and θo.
  static constexpr int kCoarseLevels = 48;
  static std::size_t coarseIndex(double theta_n, double theta_i, double theta_o);
  std::vector<double> coarse_;
};

}  // namespace glint
