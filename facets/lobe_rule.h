#pragma once
/// @file
/// @brief The lobe rule: one piece of a curved facet integrated with its specular lobe in
/// closed form, the rule of the lobe scheme (integrator.h, IntegrationScheme::Lobe).
///
/// Over a piece of surface the specular integrand is a smooth factor times the lobe
/// exp(−tan²θN / 2σ²), and tan²θN = |q|² for the tangent-plane vector q = H/(H·n) − n, a smooth
/// function of the surface point. Where q is affine the lobe is a Gaussian in the piece's
/// coordinates, whose integral over a polygon is a sum of Owen's T functions (exact for any
/// width and aspect ratio: a point glint, a cylinder's stripe, a lobe wider than the piece;
/// bivariate_normal.h). So the rule interpolates q and the smooth factors quadratically from
/// six nodes, finds where |q| is least (the specular point, or the piece's point nearest it),
/// linearises q there, integrates that Gaussian exactly over the piece's lit, visible, in-beam
/// part, and corrects for the rest (the smooth factor and q's curvature) at the Gaussian's
/// centroid: a second-order product rule, with no sample ever needing to land on the peak.

#include <array>
#include <limits>
#include <span>

#include "facets/beam.h"
#include "facets/material.h"
#include "facets/surface_map.h"
#include "facets/vec3.h"

namespace glint {

/// @brief The integrand's parts at one node of a piece, the lobe kept apart.
struct LobeNode {
  Vec3 slope{0.0};  ///< q = H/(H·n) − n: tangent to the surface, |q| = tan θN
  /// ρs E (1 + tan²θN)² / (8π σ² d²) · dA/du dv: the specular integrand without its lobe
  /// factor exp(−tan²θN / 2σ²), in W/m² per unit parameter area.
  double specular = 0.0;
  /// ρd E cos θi cos θr / (π d²) · dA/du dv, with the cosines continued smoothly (signed) past
  /// the terminator and horizon, where the clip cuts it off.
  double diffuse = 0.0;
  /// cos θi, cos θr · d, the beam's edge margin and axial distance: the piece counts only where
  /// all four are positive (each modelled linearly between the piece's corners).
  std::array<double, 4> clip{};
  bool valid = false;  ///< false where the surface map breaks down
  /// False where H·n ≤ 0: θN ≥ 90°, q is undefined and the lobe is taken as 0 (specular = 0).
  bool has_slope = false;
};

/// @brief The integrand's parts at barycentric coordinates @p bary of @p map's coarse facet,
/// for an observer at @p observer_m (both in the facet's object frame).
LobeNode lobeNode(const SurfaceMap& map, const Vec3& bary, const Vec3& observer_m, const Beam& beam,
                  const Material& material);

/// @brief As above, with the surface there already known (@p surface = map.at(bary)).
LobeNode lobeNode(const SurfacePoint& surface, const Vec3& observer_m, const Beam& beam,
                  const Material& material);

/// @brief Where the rule may sample a piece beyond its nodes: the integrand's parts at (s, t),
/// the piece being the image of the triangle (0,0), (1,0), (0,1).
class LobeSampler {
 public:
  virtual ~LobeSampler() = default;
  [[nodiscard]] virtual LobeNode at(double s, double t) const = 0;
};

/// @brief A piece of a coarse facet for one observer, sampled through the facet's surface map.
class PieceSampler final : public LobeSampler {
 public:
  /// @param bary the piece's corners in the coarse facet; @p observer_m and @p beam in the
  /// facet's object frame. All are referenced, not copied.
  PieceSampler(const SurfaceMap& map, const std::array<Vec3, 3>& bary, const Vec3& observer_m,
               const Beam& beam, const Material& material)
      : map_(map), bary_(bary), observer_m_(observer_m), beam_(beam), material_(material) {}
  [[nodiscard]] LobeNode at(double s, double t) const override {
    return lobeNode(map_, (1.0 - s - t) * bary_[0] + s * bary_[1] + t * bary_[2], observer_m_,
                    beam_, material_);
  }

 private:
  const SurfaceMap& map_;
  const std::array<Vec3, 3>& bary_;
  const Vec3& observer_m_;
  const Beam& beam_;
  const Material& material_;
};

/// @brief The lobe rule's estimate of ∫ E dA over one piece (W/m²).
struct LobeEstimate {
  double irradiance_w_m2 = 0.0;
  /// What the rule itself may miss beyond the Gaussian and R quadratic (see lobeRule());
  /// hidden_error_w_m2 is the share of it that the change under 1→4 splitting cannot show.
  double rule_error_w_m2 = 0.0;
  /// The part of rule_error_w_m2 that comparing this piece's estimate with its parent's cannot
  /// show. Where the lobe sits within the piece (a spot inside it, or its tail at one edge),
  /// parent and child sample it at the same points and agree whatever their error; where the
  /// lobe is flat over the piece, the rule is an ordinary one of degree two whose error falls
  /// with the piece's size, which the change under splitting shows. So the sigma points' term
  /// counts by 1 − (the determinant of the lobe's covariance over the piece / that of the
  /// piece's uniform measure). A lobe skipped as negligible, or modelled poorly, counts whole.
  double hidden_error_w_m2 = 0.0;
  int evaluations = 0;  ///< integrand evaluations beyond the six nodes
  bool ok = false;      ///< false when a node is invalid or the estimate is not finite
  /// With `embedded`: the diffuse part's error estimated within the piece, |degree 5 − degree 3|
  /// on the same part (W/m²); +∞ when the piece is clipped anywhere its six nodes can see, since
  /// the straight edges of the clipped part then err by more than the rules show.
  double diffuse_error_w_m2 = std::numeric_limits<double>::infinity();
};

/// @brief Integrates the piece whose nodes are @p nodes (corners 0, 1, 2, then the midpoints of
/// the edges 01, 12, 20), whose area in the coarse facet's (u, v) parameter plane is
/// @p area_uv, for a lobe of RMS slope @p sigma: the Gaussian of q linearised at the specular
/// point in closed form over the clipped part, times the rest of the integrand averaged over
/// that Gaussian at five sigma points, where @p sampler evaluates it; the diffuse term by a
/// degree-5 rule on the part, also sampled from @p sampler. A specular term whose
/// interpolated estimate (times e²) is below @p negligible_w_m2 is returned as that estimate,
/// wholly uncertain, without the sigma points. With @p embedded, the diffuse term's error is
/// also estimated (see LobeEstimate::diffuse_error_w_m2), at four more evaluations.
/// Never throws.
LobeEstimate lobeRule(const LobeSampler& sampler, const std::array<const LobeNode*, 6>& nodes,
                      double area_uv, double sigma, double negligible_w_m2 = 0.0,
                      bool embedded = false);

}  // namespace glint
