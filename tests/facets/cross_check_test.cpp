// Every integration scheme against an independent brute force (support/brute_force.h: the
// integrand written out again, nested adaptive Gauss–Kronrod in each shape's exact
// parametrisation): random scenes with fixed seeds over the analytic shapes, flat-top beams
// wider and narrower than the target (whose edge then crosses it) and Gaussian beams,
// σ from 0.001 to 0.1, observers from 2 cm off the surface to 50 m away. Wherever a scheme
// says an observer converged, its answer is within the tolerance asked of the reference.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "facets/integrator.h"
#include "facets/tessellate.h"
#include "support/brute_force.h"
#include "support/references.h"
#include "support/scenes.h"

namespace glint {
namespace {

struct CrossCheckCase {
  int shape = 0;  // 0 cylinder, 1 sphere, 2 disk
  Beam beam;
  Material material;
  Vec3 observer_m{0.0};
  std::string label;
};

constexpr double kRadius = 0.5;
constexpr double kLength = 2.0;
// The three targets, each as the scheme and the brute force see it.
const CylinderShape kCylinder{Vec3(0), Vec3(0, 0, 1), kRadius, kLength};
const SphereShape kSphere{Vec3(0), kRadius};
const DiskShape kDisk{Vec3(0), glm::normalize(Vec3(-1, 0.3, 0.2)), kRadius};

// One random scene and observer. The target sits at the origin; the laser, 100 m away, aims
// at a point up to 0.2 m off its centre from within 50° of +x.
CrossCheckCase drawCase(std::mt19937_64& rng, int index) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  auto unit_vector = [&] {
    const double z = 2.0 * unit(rng) - 1.0, phi = 2.0 * kPi * unit(rng);
    const double s = std::sqrt(1.0 - z * z);
    return Vec3(s * std::cos(phi), s * std::sin(phi), z);
  };
  CrossCheckCase c;
  c.shape = index % 3;
  const double sigma = std::pow(10.0, -3.0 + 2.0 * unit(rng));
  const double diffuse = unit(rng) < 0.3 ? 0.05 : 0.0;
  c.material = Material{0.9 - diffuse, diffuse, Beckmann{sigma}};

  const double tilt = 50.0 * kPi / 180.0 * std::sqrt(unit(rng)), turn = 2.0 * kPi * unit(rng);
  c.beam.direction =
      Vec3(std::cos(tilt), std::sin(tilt) * std::cos(turn), std::sin(tilt) * std::sin(turn));
  const Vec3 aim = 0.2 * unit(rng) * unit_vector();
  c.beam.origin_m = aim - 100.0 * c.beam.direction;
  c.beam.power_w = 500.0;
  const int beam_kind = static_cast<int>(3.0 * unit(rng));
  c.beam.profile = beam_kind == 2 ? BeamProfile::Gaussian : BeamProfile::FlatTop;
  c.beam.radius_m = beam_kind == 0 ? 2.0 : beam_kind == 1 ? 0.25 : 0.3;

  // Mostly on the laser's side (where the glints are), some anywhere (grazing and forward).
  Vec3 dir = unit_vector();
  if (unit(rng) < 0.7 && glm::dot(dir, c.beam.direction) > 0.0)
    dir -= 2.0 * glm::dot(dir, c.beam.direction) * c.beam.direction;
  const bool near = unit(rng) < 0.4;
  const double offset_m = near ? 0.02 * std::pow(15.0, unit(rng)) : 2.0 * std::pow(25.0, unit(rng));
  if (c.shape == 0) {  // off the side surface, within its length
    const double height = 0.8 * (unit(rng) - 0.5) * kLength;
    const Vec3 radial = glm::normalize(Vec3(dir.x, dir.y, 0.0) + Vec3(1e-9, 0.0, 0.0));
    c.observer_m =
        near ? (kRadius + offset_m) * radial + Vec3(0, 0, height) : (kRadius + offset_m) * dir;
  } else {
    c.observer_m = (kRadius + offset_m) * dir;
  }
  std::ostringstream label;
  label << "case " << index << ": "
        << (c.shape == 0   ? "cylinder"
            : c.shape == 1 ? "sphere"
                           : "disk")
        << ", sigma " << sigma << ", rho_d " << diffuse << ", "
        << (beam_kind == 0   ? "wide flat top"
            : beam_kind == 1 ? "narrow flat top"
                             : "Gaussian")
        << ", observer (" << c.observer_m.x << ", " << c.observer_m.y << ", " << c.observer_m.z
        << ")";
  c.label = label.str();
  return c;
}

test::brute::Parametrisation parametrisation(const CrossCheckCase& c) {
  if (c.shape == 0) return test::brute::cylinder(kCylinder);
  if (c.shape == 1) {
    // The glint lies in the plane of the laser, the centre and the observer: its normal is the
    // pole, so the glint sits on the equator, far from the parametrisation's singular points.
    Vec3 pole = glm::cross(c.beam.direction, c.observer_m);
    if (glm::length(pole) < 1e-6 * glm::length(c.observer_m))
      pole = glm::cross(c.beam.direction, Vec3(0.3, 0.5, 0.7));
    return test::brute::sphere(kSphere, pole);
  }
  return test::brute::disk(kDisk);
}

FacetIntegrator integrator(const CrossCheckCase& c, const IntegratorOptions& options) {
  return test::singleObject(
      c.material, c.beam,
      [&](Target& t, std::uint32_t m, Vec3 ref) {
        if (c.shape == 0) addCylinder(t, kCylinder, m, 16, ref);
        if (c.shape == 1) addSphere(t, kSphere, m, 16, ref);
        if (c.shape == 2) addDisk(t, kDisk, m, 16, ref);
      },
      options);
}

// The reference itself against closed forms, so that agreeing with it means something.
TEST(BruteForce, MatchesTheLambertianDiskAndTheMirrorSphereClosedForms) {
  const Beam beam = test::flatTop(Vec3(0), Vec3(0, 0, -1), 40.0, 2.0);
  const Material lambert{0.0, 0.8, Beckmann{0.1}};
  const test::brute::Parametrisation disk = test::brute::disk({Vec3(0), Vec3(0, 0, 1), 0.5});
  for (double h : {0.05, 0.5, 5.0}) {
    const test::brute::Estimate e = test::brute::irradiance(disk, beam, lambert, Vec3(0, 0, h));
    EXPECT_NEAR(e.value / test::lambertianDiskOnAxis(0.8, 40.0, 1.0, 0.5, h), 1.0, 1e-8)
        << "h = " << h << " m";
  }
  // σ = 0.001: the lobe's departure from the mirror's focal-line form is O(σ²) and O(R/d).
  const Material mirror{0.9, 0.0, Beckmann{0.001}};
  for (double deg : {30.0, 90.0, 150.0}) {
    const double t = deg * kPi / 180.0;
    const Vec3 obs = 1000.0 * Vec3(std::sin(t), 0.0, std::cos(t));
    const test::brute::Parametrisation sphere = test::brute::sphere({Vec3(0), 0.5}, Vec3(0, 1, 0));
    const test::brute::Estimate e = test::brute::irradiance(sphere, beam, mirror, obs);
    EXPECT_NEAR(e.value / test::mirrorSphere(0.9, 40.0, 0.5, obs), 1.0, 1e-5)
        << deg << " deg from backscatter";
  }
}

class CrossCheck : public ::testing::TestWithParam<IntegrationScheme> {};

TEST_P(CrossCheck, ConvergedObserversAreWithinTheirToleranceOfABruteForceReference) {
  constexpr double kTolerance = 1e-3, kFloor_w_m2 = 1e-6;
  constexpr int kCases = 60;
  std::mt19937_64 rng(20261123);
  // The brute force takes about a second a case: the schemes share its references.
  static std::vector<test::brute::Estimate> references;
  IntegratorOptions options = test::accuracy(kTolerance, kFloor_w_m2);
  options.scheme = GetParam();
  int converged = 0, lit = 0;
  std::vector<std::int64_t> evaluations;
  double worst = 0.0;      // achieved error over what was allowed
  int estimate_below = 0;  // converged observers whose own error estimate is below their error
  for (int k = 0; k < kCases; ++k) {
    const CrossCheckCase c = drawCase(rng, k);
    if (references.size() == static_cast<std::size_t>(k)) {
      references.push_back(
          test::brute::irradiance(parametrisation(c), c.beam, c.material, c.observer_m));
    }
    const test::brute::Estimate& ref = references[static_cast<std::size_t>(k)];
    // The reference must be far more accurate than what it checks.
    ASSERT_LE(ref.error, 0.01 * (kTolerance * ref.value + kFloor_w_m2))
        << "the reference did not converge: " << c.label;
    IntegratorWorkspace ws;
    const ObserverResult r = integrator(c, options).adaptive(c.observer_m, ws);
    evaluations.push_back(r.evaluations);
    if (ref.value > 1e3 * kFloor_w_m2) ++lit;
    if (!r.converged) continue;
    ++converged;
    const double error = std::abs(r.irradiance_w_m2 - ref.value);
    const double allowed = kTolerance * ref.value + kFloor_w_m2 + ref.error;
    worst = std::max(worst, error / allowed);
    if (r.error_estimate_w_m2 < error) ++estimate_below;
    EXPECT_LE(error, allowed) << c.label << ": " << r.irradiance_w_m2 << " W/m² against "
                              << ref.value << " (relative error " << error / ref.value
                              << ", own estimate " << r.error_estimate_w_m2 << ")";
  }
  std::sort(evaluations.begin(), evaluations.end());
  std::cout << "[ cross-check ] " << converged << " of " << kCases << " converged (" << lit
            << " lit); worst achieved error / allowed = " << worst << "; own estimate below "
            << "the achieved error for " << estimate_below << "; evaluations median "
            << evaluations[evaluations.size() / 2] << ", max " << evaluations.back() << "\n";
  EXPECT_GE(converged, kCases * 9 / 10) << "most observers converge at the default tolerance";
  EXPECT_GE(lit, kCases / 3) << "the draw puts most observers in some light";
}

INSTANTIATE_TEST_SUITE_P(Schemes, CrossCheck,
                         ::testing::Values(IntegrationScheme::Paper, IntegrationScheme::Cubature,
                                           IntegrationScheme::Lobe),
                         [](const ::testing::TestParamInfo<IntegrationScheme>& param) {
                           return integrationSchemeNames()[static_cast<std::size_t>(param.param)];
                         });

}  // namespace
}  // namespace glint
