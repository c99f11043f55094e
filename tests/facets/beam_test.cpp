#include "facets/beam.h"

#include <gtest/gtest.h>

#include <glm/gtc/quaternion.hpp>
#include <random>

#include "support/quadrature.h"

namespace glint {
namespace {

// Power through the plane perpendicular to the beam at distance z: ∫ E 2πρ dρ.
double powerAt(const Beam& beam, double z) {
  const double r = beam.radiusAt(z);
  auto ring = [&](double rho) {
    return beam.at(beam.origin_m + z * beam.direction + Vec3(0, rho, 0)).irradiance_w_m2 * 2 * kPi *
           rho;
  };
  if (beam.profile == BeamProfile::FlatTop) return test::simpson(ring, 0.0, r, 2000);
  return test::simpson(ring, 0.0, 4.2 * r, 20000);
}

Beam makeBeam(BeamProfile profile, double divergence) {
  Beam b;
  b.origin_m = Vec3(-10, 0, 0);
  b.direction = Vec3(1, 0, 0);
  b.power_w = 250.0;
  b.profile = profile;
  b.radius_m = 0.3;
  b.divergence_rad = divergence;
  return b;
}

TEST(Beam, FlatTopAndGaussianCarryTheirPower) {
  for (auto profile : {BeamProfile::FlatTop, BeamProfile::Gaussian}) {
    for (double divergence : {0.0, 0.01}) {
      const Beam b = makeBeam(profile, divergence);
      for (double z : {0.0, 5.0, 200.0}) {
        // Simpson on the smooth profiles is exact to ~1e-12; the Gaussian is cut at 1e-15.
        EXPECT_NEAR(powerAt(b, z) / b.power_w, 1.0, 1e-9)
            << "profile " << static_cast<int>(profile) << " divergence " << divergence << " z "
            << z;
      }
    }
  }
}

TEST(Beam, DivergenceFollowsTheNohdLaw) {
  const Beam b = makeBeam(BeamProfile::FlatTop, 0.002);
  // D_L = √(a² + r²φ²) in diameters: radius √(0.3² + (1000 · 0.001)²).
  EXPECT_NEAR(b.radiusAt(1000.0), std::hypot(0.3, 1.0), 1e-15);
  EXPECT_NEAR(b.at(b.origin_m + 1000.0 * b.direction).irradiance_w_m2, 250.0 / (kPi * (0.09 + 1.0)),
              1e-12);
}

TEST(Beam, NothingBehindTheLaserOrOutsideTheBeam) {
  const Beam b = makeBeam(BeamProfile::FlatTop, 0.0);
  EXPECT_EQ(b.at(b.origin_m - 0.001 * b.direction).irradiance_w_m2, 0.0);
  EXPECT_EQ(b.at(b.origin_m + Vec3(1.0, 0.31, 0.0)).irradiance_w_m2, 0.0);
  EXPECT_GT(b.at(b.origin_m + Vec3(1.0, 0.29, 0.0)).irradiance_w_m2, 0.0);
}

TEST(Beam, BallBoundsHoldForEveryPointInside) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (auto profile : {BeamProfile::FlatTop, BeamProfile::Gaussian}) {
    const Beam b = makeBeam(profile, 0.05);
    for (int trial = 0; trial < 300; ++trial) {
      const Vec3 c = b.origin_m + Vec3(10.0 + 10.0 * u(rng), 1.5 * u(rng), 1.5 * u(rng));
      const double r = 0.2 * (1.0 + u(rng));
      const double e_max = b.maxIrradianceInBall(c, r);
      const Vec3 wi_c = b.at(c).toward_laser;
      const double spread = b.directionSpreadInBall(r);
      for (int k = 0; k < 50; ++k) {
        Vec3 d(u(rng), u(rng), u(rng));
        if (glm::length(d) > 1.0) continue;
        const Beam::Sample s = b.at(c + r * d);
        ASSERT_LE(s.irradiance_w_m2, e_max * (1 + 1e-12)) << "trial " << trial;
        if (s.irradiance_w_m2 > 0.0 && b.at(c).irradiance_w_m2 > 0.0) {
          ASSERT_LE(angleBetween(s.toward_laser, wi_c), spread + 1e-12) << "trial " << trial;
        }
      }
    }
  }
}

// A swept beam's ball bound holds for every beam of its sweep: beams turned and moved within
// it, at random points of random balls.
TEST(Beam, ASweptBeamsBallBoundHoldsForEveryBeamOfItsSweep) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (BeamProfile profile : {BeamProfile::Gaussian, BeamProfile::FlatTop}) {
    Beam swept;
    swept.origin_m = Vec3(-100.0, 0.0, 0.0);
    swept.direction = Vec3(1.0, 0.0, 0.0);
    swept.profile = profile;
    swept.radius_m = 0.4;
    swept.divergence_rad = 1e-3;
    swept.power_w = 100.0;
    swept.sweep_offset_m = 0.3;
    swept.sweep_angle_rad = 2e-3;
    for (int trial = 0; trial < 2000; ++trial) {
      const Vec3 centre(u(rng) * 2.0, u(rng) * 1.0, u(rng) * 1.0);
      const double radius = 0.05 + 0.2 * std::abs(u(rng));
      // A beam of the sweep: turned by at most the angle about a random axis, moved by at most
      // the offset.
      Beam b = swept;
      b.sweep_offset_m = b.sweep_angle_rad = 0.0;
      const Vec3 axis = glm::normalize(Vec3(u(rng), u(rng), u(rng)));
      b.direction = glm::angleAxis(swept.sweep_angle_rad * std::abs(u(rng)), axis) * b.direction;
      b.origin_m +=
          swept.sweep_offset_m * std::abs(u(rng)) * glm::normalize(Vec3(u(rng), u(rng), u(rng)));
      const double bound = swept.maxIrradianceInBall(centre, radius);
      const double spread = swept.directionSpreadInBall(radius);
      for (int k = 0; k < 8; ++k) {
        const Vec3 p =
            centre + radius * std::abs(u(rng)) * glm::normalize(Vec3(u(rng), u(rng), u(rng)));
        const Beam::Sample s = b.at(p);
        ASSERT_LE(s.irradiance_w_m2, bound * (1 + 1e-12))
            << "at a point of the ball, trial " << trial;
        if (s.irradiance_w_m2 > 0.0) {
          ASSERT_LE(angleBetween(s.toward_laser, swept.at(centre).toward_laser), spread + 1e-12)
              << "ωi turned beyond the spread, trial " << trial;
        }
      }
    }
  }
}

}  // namespace
}  // namespace glint
