#pragma once
/// @file
/// @brief The laser beam: where it is, how much irradiance it puts on a surface point, and
/// bounds of both over a ball (for culling and the contribution bound).

#include <algorithm>
#include <cmath>

#include "facets/vec3.h"

namespace glint {

/// @brief Transverse irradiance profile of the beam.
enum class BeamProfile {
  FlatTop,   ///< uniform P / (π a²) inside radius a, 0 outside
  Gaussian,  ///< 2P / (π w²) · exp(−2ρ² / w²), w the 1/e² radius
};

/// @brief A beam along the ray from @c origin_m in @c direction (docs/physics.md, "The beam").
///
/// The radius grows with the distance z along the axis as r(z) = √(r₀² + (z φ/2)²) with φ the
/// full divergence angle: the beam-diameter law ANSI Z136.1 uses for the nominal hazard zone
/// (D_L = √(a² + r²φ²)). Power is conserved, so irradiance falls as 1/r(z)². Rays of a
/// diverging beam tilt away from the axis in proportion to their offset, the tilt of that
/// law's wavefront: dr/dz · ρ / r.
///
/// A Gaussian beam is truncated where it falls below 1e-15 of its on-axis value, so that
/// "outside the beam" means exactly zero both for evaluation and for culling.
struct Beam {
  Vec3 origin_m{0.0};             ///< laser position (m)
  Vec3 direction{1.0, 0.0, 0.0};  ///< unit propagation direction
  double power_w = 1.0;           ///< total beam power (W), > 0
  BeamProfile profile = BeamProfile::FlatTop;
  double radius_m = 1.0;        ///< a (flat top) or w (Gaussian) at the laser, > 0
  double divergence_rad = 0.0;  ///< full-angle divergence φ, ≥ 0; 0 is collimated
  /// Extinction of the air (1/m, ≥ 0) along the beam: irradiance falls as exp(−μ z), z the
  /// distance along the axis (never more than a ray's path, so an upper bound when divergent).
  double extinction_per_m = 0.0;
  /// Extinction (1/m, ≥ 0) along each reflected path to the observer, applied by the kernel as
  /// exp(−μ d). 0 where intensity is wanted rather than irradiance at a distance (far field).
  double return_extinction_per_m = 0.0;
  /// A beam that moves over a time interval (an engagement, observers/motion.h) stands for
  /// every beam a rigid motion of this one reaches with its origin at most sweep_offset_m away
  /// and its direction turned at most sweep_angle_rad: the bounds (maxIrradianceInBall(),
  /// directionSpreadInBall(), edgeMayCrossBall(), profileMayBendInBall()) then hold for all of
  /// them, while at() and footprint() evaluate this one. Both 0: the beam itself.
  double sweep_offset_m = 0.0;
  double sweep_angle_rad = 0.0;

  /// @brief Whether the beam stands for a set of beams (see sweep_offset_m).
  [[nodiscard]] bool swept() const { return sweep_offset_m > 0.0 || sweep_angle_rad > 0.0; }

  /// @brief Irradiance on a plane perpendicular to the beam (W/m²), and the unit vector from
  /// the point toward the laser along the local ray (ωi).
  struct Sample {
    double irradiance_w_m2;
    Vec3 toward_laser;
  };

  /// @brief The beam at point @p x_m, attenuated along its path. Points behind the laser
  /// (z < 0) get 0.
  [[nodiscard]] Sample at(const Vec3& x_m) const;

  /// @brief The beam at a point, continued smoothly across its edges, with how far inside
  /// them the point lies: what a rule that clips its pieces at the edges needs.
  struct Footprint {
    /// Irradiance as if the point were inside (flat top: P / π r(z)²; Gaussian: untruncated).
    double irradiance_w_m2;
    Vec3 toward_laser;
    double edge_margin;  ///< flat top: 1 − ρ² / r(z)², > 0 inside the edge; Gaussian: 1
    double axial_m;      ///< z along the axis: points with z < 0 are behind the laser
  };

  /// @brief The beam's smooth continuation at @p x_m (see Footprint). Where the margin and z are
  /// positive it agrees with at().
  [[nodiscard]] Footprint footprint(const Vec3& x_m) const;

  /// @brief Beam radius parameter (a or w) at distance @p z_m ≥ 0 along the axis.
  [[nodiscard]] double radiusAt(double z_m) const;

  /// @brief Irradiance on the axis at the laser: P / (π a²) or 2P / (π w²), the most anywhere.
  [[nodiscard]] double peakIrradiance() const;

  /// @brief An upper bound of the irradiance over the ball (@p centre_m, @p radius_m),
  /// attenuation included; 0 when no point of the ball is lit.
  [[nodiscard]] double maxIrradianceInBall(const Vec3& centre_m, double radius_m) const;

  /// @brief True when a discontinuity of the beam (a flat-top edge, or the laser's own plane)
  /// may pass through the ball, so that samples inside it cannot be trusted to be smooth.
  [[nodiscard]] bool edgeMayCrossBall(const Vec3& centre_m, double radius_m) const;

  /// @brief True when the profile may bend across the ball faster than a rule's few nodes
  /// can follow: a Gaussian whose width w(z) at the ball's near end is under twice the ball's
  /// radius; a flat top whose edge may cross a ball wider than a tenth of its radius a(z) (a
  /// rule that clips at the edge draws it straight between its nodes).
  [[nodiscard]] bool profileMayBendInBall(const Vec3& centre_m, double radius_m) const;

  /// @brief An upper bound, in radians, of the angle between ωi at the centre of a ball of
  /// radius @p radius_m and ωi anywhere in it (0 for a collimated beam).
  [[nodiscard]] double directionSpreadInBall(double radius_m) const;

  /// @brief This beam seen from a frame whose origin sits at @p frame_origin_m.
  [[nodiscard]] Beam relativeTo(const Vec3& frame_origin_m) const;

 private:
  [[nodiscard]] double reachFactor() const;
  /// The radius of a ball about @p centre_m that holds, for every beam of the sweep, the point
  /// of this beam's frame where a point of the ball (@p centre_m, @p radius_m) lies in its own.
  [[nodiscard]] double sweptRadius(const Vec3& centre_m, double radius_m) const;
  /// exp(−μ z) for z ≥ 0 along the axis, exactly 1 in vacuum.
  [[nodiscard]] double transmission(double z_m) const {
    return extinction_per_m > 0.0 ? std::exp(-extinction_per_m * std::max(z_m, 0.0)) : 1.0;
  }
};

}  // namespace glint
