#include "facets/beam.h"

#include <algorithm>
#include <cmath>

namespace glint {
namespace {
// ρ/w at which 2P/(πw²)·exp(−2ρ²/w²) has fallen to 1e-15 of its peak: √(ln(1e15)/2).
const double kGaussianReach = std::sqrt(std::log(1e15) / 2.0);
}  // namespace

double Beam::reachFactor() const { return profile == BeamProfile::Gaussian ? kGaussianReach : 1.0; }

double Beam::sweptRadius(const Vec3& centre_m, double radius_m_ball) const {
  if (!swept()) return radius_m_ball;
  // A beam of the sweep is this one turned about its origin by at most α and moved by at most s:
  // seen from it, a point q sits where this beam has a point within s + 2 sin(α/2)|q − origin|
  // ≤ s + α (|center − origin| + r) of q.
  const double lever_m = glm::length(centre_m - origin_m) + radius_m_ball;
  return radius_m_ball + sweep_offset_m + std::min(sweep_angle_rad, kPi) * lever_m;
}

double Beam::radiusAt(double z_m) const {
  const double spread = 0.5 * divergence_rad * std::max(z_m, 0.0);
  return std::hypot(radius_m, spread);
}

double Beam::peakIrradiance() const {
  const double area = kPi * radius_m * radius_m;
  return profile == BeamProfile::Gaussian ? 2.0 * power_w / area : power_w / area;
}

Beam::Sample Beam::at(const Vec3& x_m) const {
  const Vec3 rel = x_m - origin_m;
  const double z = glm::dot(rel, direction);
  if (z < 0.0) return {0.0, -direction};
  const Vec3 radial = rel - z * direction;
  const double rho2 = glm::dot(radial, radial);
  const double r = radiusAt(z);
  const double reach = reachFactor() * r;
  if (rho2 > reach * reach) return {0.0, -direction};

  const double r2 = r * r;
  double e = 0.0;
  if (profile == BeamProfile::Gaussian) {
    e = 2.0 * power_w / (kPi * r2) * std::exp(-2.0 * rho2 / r2);
  } else {
    e = power_w / (kPi * r2);
  }
  e *= transmission(z);
  if (divergence_rad == 0.0) return {e, -direction};
  const double half = 0.5 * divergence_rad;
  const Vec3 ray = direction + radial * (z * half * half / r2);
  return {e, -glm::normalize(ray)};
}

Beam::Footprint Beam::footprint(const Vec3& x_m) const {
  const Vec3 rel = x_m - origin_m;
  const double z = glm::dot(rel, direction);
  const Vec3 radial = rel - z * direction;
  const double rho2 = glm::dot(radial, radial);
  const double r = radiusAt(z);
  const double r2 = r * r;
  Footprint f{0.0, -direction, 1.0, z};
  if (profile == BeamProfile::Gaussian) {
    f.irradiance_w_m2 = 2.0 * power_w / (kPi * r2) * std::exp(-2.0 * rho2 / r2);
  } else {
    f.irradiance_w_m2 = power_w / (kPi * r2);
    f.edge_margin = 1.0 - rho2 / r2;
  }
  f.irradiance_w_m2 *= transmission(z);
  if (divergence_rad > 0.0 && z > 0.0) {
    const double half = 0.5 * divergence_rad;
    f.toward_laser = -glm::normalize(direction + radial * (z * half * half / r2));
  }
  return f;
}

double Beam::maxIrradianceInBall(const Vec3& centre_m, double own_radius_m) const {
  const double radius_m_ball = sweptRadius(centre_m, own_radius_m);
  const Vec3 rel = centre_m - origin_m;
  const double zc = glm::dot(rel, direction);
  if (zc + radius_m_ball < 0.0) return 0.0;
  const double rho_c = glm::length(rel - zc * direction);
  const double rho_min = std::max(rho_c - radius_m_ball, 0.0);
  // The beam is narrowest (brightest) at the near end of the ball and widest at the far end;
  // combining the two extremes bounds every point in between.
  const double r_near = radiusAt(zc - radius_m_ball);
  const double r_far = radiusAt(zc + radius_m_ball);
  if (rho_min > reachFactor() * r_far) return 0.0;
  const double area_near = kPi * r_near * r_near;
  const double t = transmission(zc - radius_m_ball);  // the ball's nearest depth
  if (profile == BeamProfile::Gaussian) {
    return 2.0 * power_w / area_near * std::exp(-2.0 * rho_min * rho_min / (r_far * r_far)) * t;
  }
  return power_w / area_near * t;
}

bool Beam::edgeMayCrossBall(const Vec3& centre_m, double own_radius_m) const {
  const double radius_m_ball = sweptRadius(centre_m, own_radius_m);
  const Vec3 rel = centre_m - origin_m;
  const double zc = glm::dot(rel, direction);
  if (zc - radius_m_ball < 0.0 && zc + radius_m_ball >= 0.0) return true;
  if (profile != BeamProfile::FlatTop) return false;
  const double rho_c = glm::length(rel - zc * direction);
  const double r_near = radiusAt(zc - radius_m_ball);
  const double r_far = radiusAt(zc + radius_m_ball);
  return rho_c - radius_m_ball <= r_far && rho_c + radius_m_ball > r_near;
}

bool Beam::profileMayBendInBall(const Vec3& centre_m, double own_radius_m) const {
  const double radius_m_ball = sweptRadius(centre_m, own_radius_m);
  const double z_near = glm::dot(centre_m - origin_m, direction) - radius_m_ball;
  const double width_m = radiusAt(std::max(z_near, 0.0));
  if (profile == BeamProfile::Gaussian) {
    // Across ±w/2 the Gaussian falls to e^{-1/2} of its top: a quadratic through six nodes
    // follows it to a few per cent, and the change under one split shows the rest. A piece
    // wider than that can hold a spot between its nodes: a 2 cm spot on an 8-segment 20 cm
    // disk read 43 % low at 600 m and 2 400× low at 2.7 km before pieces were held to it.
    return radius_m_ball > 0.5 * width_m;
  }
  // A flat top's edge is a circle, and a rule that clips its pieces at the edge does so along
  // the straight line its corners' margins make: a piece must be small against the circle (its
  // sagitta, R²/2a, at most a/200) for that line to follow it, and a piece wider than the
  // beam can hold the whole spot between corners that all lie outside it. Before this, a
  // 0.5 m beam on a 3 m mirror facet read 2e-8 W/m² where 110 W/m² fall.
  return radius_m_ball > 0.1 * width_m && edgeMayCrossBall(centre_m, own_radius_m);
}

double Beam::directionSpreadInBall(double radius_m_ball) const {
  // Every beam of a sweep turns ωi everywhere by at most the sweep's angle (its rigid motion's
  // rotation).
  const double swept_rad = std::min(sweep_angle_rad, kPi);
  if (divergence_rad == 0.0) return swept_rad;
  const double h = 0.5 * divergence_rad;
  if (swept()) {
    // Where the sweep moves the ball is not known here: any two rays of the beam, whose tilt
    // ρ z h² / r(z)² is at most reach × h (ρ ≤ reach × r, r ≥ z h), differ by at most twice that.
    return swept_rad + 2.0 * reachFactor() * h;
  }
  // The ray is dir + ρ⃗ k(z) with k = z h² / r(z)², h = φ/2. Across the ball ρ⃗ moves by at most
  // its radius (k ≤ h / 2r₀) and k by at most |dk/dz| ≤ h² / r(z)² per metre, times ρ ≤ reach·r(z).
  // The chord between the two unnormalised rays bounds the angle up to a factor π/2.
  const double tilt_rate = h / (2.0 * radius_m) + reachFactor() * h * h / radius_m;
  return 0.5 * kPi * radius_m_ball * tilt_rate;
}

Beam Beam::relativeTo(const Vec3& frame_origin_m) const {
  Beam local = *this;
  local.origin_m = origin_m - frame_origin_m;
  return local;
}

}  // namespace glint
