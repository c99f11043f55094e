// ABg scatter (abg_scatter.h) and measured tables (brdf_table.h): each normalised as its closed
// form or its own quadrature says, each bound above what it reflects, and the integrator's
// irradiance against a quadrature of the same integral that shares none of its code.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <random>
#include <vector>

#include "facets/abg_scatter.h"
#include "facets/brdf_table.h"
#include "facets/integrator.h"
#include "facets/material.h"
#include "facets/patch.h"
#include "facets/reflection.h"
#include "facets/tessellate.h"
#include "support/brdf_quadrature.h"
#include "support/quadrature.h"
#include "support/scenes.h"

namespace glint {
namespace {

using test::accuracy;
using test::flatTop;

constexpr double kDeg = kPi / 180.0;

Material abgOnly(const AbgScatter& abg) {
  Material m;
  m.abg = abg;
  return m;
}

Material tableOnly(std::shared_ptr<const BrdfTable> table) {
  Material m;
  m.table = std::move(table);
  return m;
}

double hemisphericalReflectance(const Material& m, const Vec3& wi) {
  return test::hemisphericalReflectance(m, wi, 8000);
}

// ∫ A / (B + |β − β₀|²) d²β over the unit disc of projected directions (g = 2), in polar
// coordinates about β₀ = sin θi: the radial integral in closed form, ½ ln(1 + R²/B), and the
// periodic azimuth by the trapezoid rule. No half vector, no outgoing direction.
double discIntegralG2(const AbgScatter& abg, double theta_i) {
  const double b0 = std::sin(theta_i);
  const int n = 4096;
  double sum = 0.0;
  for (int k = 0; k < n; ++k) {
    const double psi = 2.0 * kPi * k / n;
    const double along = b0 * std::cos(psi);  // β₀ · u, u the unit direction at ψ
    const double radius = -along + std::sqrt(along * along + 1.0 - b0 * b0);
    sum += 0.5 * std::log1p(radius * radius / abg.b);
  }
  return abg.a_per_sr * sum * 2.0 * kPi / n;
}

TEST(AbgScatter, TotalIntegratedScatterIsItsClosedForm) {
  // g = 2: 2πA ∫ ρ / (B + ρ²) dρ = πA ln(1 + 1/B); g = 1: 2πA (1 − B ln(1 + 1/B)).
  for (double b : {1e-6, 1e-3, 0.1}) {
    const AbgScatter two{0.01, b, 2.0};
    const double expected2 = kPi * 0.01 * std::log1p(1.0 / b);
    EXPECT_NEAR(two.totalIntegratedScatter() / expected2, 1.0, 1e-10) << "B " << b;
    const AbgScatter one{0.01, b, 1.0};
    const double expected1 = 2.0 * kPi * 0.01 * (1.0 - b * std::log1p(1.0 / b));
    EXPECT_NEAR(one.totalIntegratedScatter() / expected1, 1.0, 1e-10) << "B " << b;
  }
}

// Each incidence's hemispherical reflectance by brute force over the outgoing directions
// (through the half vector, as the integrator sees ABg) equals the disc integral in β; at
// normal incidence it is the TIS, and oblique incidence, which moves β₀ off the disc's centre,
// only lowers it.
TEST(AbgScatter, HemisphericalReflectanceIsTheDiscIntegralAtEveryIncidence) {
  const AbgScatter abg{0.004, 1e-3, 2.0};
  const Material m = abgOnly(abg);
  const double tis = abg.totalIntegratedScatter();
  for (double deg : {0.0, 30.0, 60.0}) {
    const Vec3 wi(std::sin(deg * kDeg), 0.0, std::cos(deg * kDeg));
    const double brute = hemisphericalReflectance(m, wi);
    const double disc = discIntegralG2(abg, deg * kDeg);
    // Simpson's steps (4e-4 rad) are a tenth of the peak's width √B / 2 ≈ 0.016; the cut at
    // the horizon (the integrand ≈ A there) costs Simpson about a step's worth, ~A h ≈ 2e-6.
    EXPECT_NEAR(brute, disc, 2e-5 * tis) << deg << " deg";
    EXPECT_LE(disc, tis * (1.0 + 1e-9)) << deg << " deg";
    if (deg == 0.0) {
      EXPECT_NEAR(disc / tis, 1.0, 1e-9);
    }
    std::printf("[ abg ] albedo at %g deg: brute force %.9f, disc integral %.9f, TIS %.9f\n", deg,
                brute, disc, tis);
  }
}

// A random pair of directions above a normal, and its half vector's tan²θN.
struct Pair {
  Vec3 n, wi, wo;
  double cos_i, cos_r, tan2;
};
Pair randomPair(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const auto up = [&] {
    const double z = u(rng), phi = 2.0 * kPi * u(rng), s = std::sqrt(1.0 - z * z);
    return Vec3(s * std::cos(phi), s * std::sin(phi), z);
  };
  Pair p{Vec3(0, 0, 1), up(), up(), 0, 0, 0};
  p.cos_i = p.wi.z;
  p.cos_r = p.wo.z;
  const Vec3 h = p.wi + p.wo;
  p.tan2 = (h.x * h.x + h.y * h.y) / (h.z * h.z);
  return p;
}

TEST(AbgScatter, ItsBoundHoldsEveryPairOfDirections) {
  std::mt19937_64 rng(7);
  for (double g : {0.5, 1.0, 2.0, 3.0, 4.0}) {
    const AbgScatter abg{0.01, 1e-4, g};
    for (int k = 0; k < 200000; ++k) {
      const Pair p = randomPair(rng);
      if (!(p.cos_i > 0.0 && p.cos_r > 0.0)) continue;
      const double value = abg.cosineWeighted(p.n, p.wi, p.wo, p.cos_i, p.cos_r);
      // The bound beyond this pair's own tilt, and beyond any smaller one.
      ASSERT_LE(value, abg.maxBeyond(p.tan2) * (1.0 + 1e-12)) << "g " << g << " tan² " << p.tan2;
      ASSERT_LE(abg.maxBeyond(p.tan2), abg.maxBeyond(0.25 * p.tan2)) << "g " << g;
      // And with the pair's own cosines as the largest: near grazing they decide.
      ASSERT_LE(value, abg.maxBeyond(p.tan2, p.cos_i, p.cos_r) * (1.0 + 1e-12))
          << "g " << g << " tan² " << p.tan2 << " cos " << p.cos_i << " " << p.cos_r;
    }
    // Seen edge-on the term vanishes, and so does its bound: (A/B) cos θi cos θr.
    EXPECT_NEAR(abg.maxBeyond(0.0, 1.0, 1e-9), abg.a_per_sr / abg.b * 1e-9,
                1e-12 * abg.a_per_sr / abg.b * 1e-9)
        << "g " << g;
    EXPECT_EQ(abg.maxBeyond(std::nan("")), abg.maxBeyond(0.0)) << "a NaN tilt bounds by the peak";
    EXPECT_NEAR(abg.maxBeyond(0.0), abg.a_per_sr / abg.b, 1e-12 * abg.a_per_sr / abg.b);
  }
}

// The paper's cylinder (radius 0.5 m, 2 m long) under a flat-top beam that covers it whole.
FacetIntegrator cylinder(const Material& m, const IntegratorOptions& o) {
  const Beam beam = flatTop(Vec3(0), Vec3(1, 0, 0), 100.0, 2.0);
  return test::singleObject(
      m, beam,
      [](Target& t, std::uint32_t mi, Vec3 toward_laser) {
        addCylinder(t, {Vec3(0), Vec3(0, 0, 1), 0.5, 2.0}, mi, 16, toward_laser);
      },
      o);
}

// The same cylinder's irradiance at @p obs by quadrature over its exact surface, the BRDF given
// as @p brdf(wi, wo, n) (1/sr): Simpson on the angle around the axis (over the lit half, where
// the integrand is continuous and vanishes at the terminator and the horizon) and along it.
template <class Brdf>
double cylinderQuadrature(const Vec3& obs, Brdf&& brdf, int around, int along) {
  const Vec3 wi(-1, 0, 0);
  const double e_beam = 100.0, radius = 0.5;
  const auto at = [&](double phi, double z) {
    const Vec3 n(std::cos(phi), std::sin(phi), 0.0);
    const Vec3 x = radius * n + Vec3(0, 0, z);
    const Vec3 v = obs - x;
    const double d = glm::length(v);
    const Vec3 wo = v / d;
    const double cos_i = glm::dot(n, wi), cos_r = glm::dot(n, wo);
    if (!(cos_i > 0.0 && cos_r > 0.0)) return 0.0;
    return e_beam * brdf(wi, wo, n) * cos_i * cos_r / (d * d) * radius;
  };
  return test::simpson(
      [&](double phi) {
        return test::simpson([&](double z) { return at(phi, z); }, -1.0, 1.0, along);
      },
      0.5 * kPi, 1.5 * kPi, around);
}

// Observers near and far: in the glint's stripe, beside it in the wings, and well off it.
std::vector<Vec3> observers() {
  std::vector<Vec3> out;
  for (double dist : {1.5, 40.0}) {
    for (double deg : {0.0, 10.0, 60.0}) {
      out.emplace_back(-dist * std::cos(deg * kDeg), dist * std::sin(deg * kDeg), 0.2);
    }
  }
  return out;
}

// ABg integrated by glint (the cubature rule on its own term, bounded as every term is) against
// a quadrature of the same integral written from the formula in β.
TEST(AbgScatter, ACylindersIrradianceIsTheQuadratureOfItsFormula) {
  const AbgScatter abg{0.003, 1e-3, 2.0};
  const double tolerance = 1e-4;
  const FacetIntegrator fi = cylinder(abgOnly(abg), accuracy(tolerance));
  IntegratorWorkspace ws;
  const auto formula = [&](const Vec3& wi, const Vec3& wo, const Vec3& n) {
    // β and β₀: the tangent-plane parts of ωo and of the mirror direction 2(n·ωi)n − ωi.
    const Vec3 mirror = 2.0 * glm::dot(n, wi) * n - wi;
    const Vec3 beta = wo - glm::dot(wo, n) * n, beta0 = mirror - glm::dot(mirror, n) * n;
    const double x = glm::length(beta - beta0);
    return abg.a_per_sr / (abg.b + x * x);
  };
  double worst = 0.0;
  for (const Vec3& obs : observers()) {
    const ObserverResult r = fi.adaptive(obs, ws);
    ASSERT_TRUE(r.converged) << obs.x << "," << obs.y;
    // 4000 × 1600 Simpson intervals: steps of 4e-4 rad and 1.3 mm against a peak √B / 2 ≈ 0.016
    // rad of tilt wide (a band of ~0.03 rad around the axis, ≥ 2 cm along it at 1.5 m): the
    // fourth-order error is ~(h / w)⁴ ≈ 1e-5; the kinks at the terminator and the horizon,
    // where the integrand vanishes with a jump in slope, ~h² ≈ 1e-7.
    const double reference = cylinderQuadrature(obs, formula, 4000, 1600);
    ASSERT_GT(reference, 0.0);
    EXPECT_NEAR(r.irradiance_w_m2 / reference, 1.0, 1e-3) << obs.x << "," << obs.y;
    worst = std::max(worst, std::abs(r.irradiance_w_m2 / reference - 1.0));
    std::printf(
        "[ abg ] observer (%.2f, %.2f, %.2f): glint %.6e, quadrature %.6e W/m², %lld "
        "evaluations\n",
        obs.x, obs.y, obs.z, r.irradiance_w_m2, reference, static_cast<long long>(r.evaluations));
  }
  std::printf("[ abg ] worst relative difference %.2e\n", worst);
}

// A Beckmann lobe (ρ, σ) as a table on the given steps, its values up to θ = 80° as a
// goniometer's would stop (the lobe's f_r grows as 1 / cos θi cos θr toward grazing; beyond,
// the table holds its edge).
std::shared_ptr<const BrdfTable> beckmannTable(double rho, double sigma, double theta_step_deg,
                                               double phi_step_deg) {
  const Beckmann lobe{sigma};
  std::vector<double> theta, phi, values;
  for (double t = 0.0; t <= 80.0 + 1e-9; t += theta_step_deg) theta.push_back(t * kDeg);
  for (double p = 0.0; p <= 180.0 + 1e-9; p += phi_step_deg) phi.push_back(p * kDeg);
  for (double ti : theta) {
    for (double to : theta) {
      for (double p : phi) {
        const Vec3 n(0, 0, 1), wi(std::sin(ti), 0.0, std::cos(ti));
        const Vec3 wo(std::sin(to) * std::cos(p), std::sin(to) * std::sin(p), std::cos(to));
        values.push_back(rho * lobe.xi(n, wi + wo) / (4.0 * wi.z * wo.z));
      }
    }
  }
  return std::make_shared<const BrdfTable>(theta, theta, phi, values);
}

TEST(BrdfTable, InterpolatesBetweenItsNodesAndHoldsItsEdges) {
  // g = f cos θi cos θo = 1 + θi + 2 θo + 3 Δφ (radians) on equal steps: the monotone cubic
  // reproduces a linear g (its slopes are the secants) in a cell whose neighbours are given.
  const std::vector<double> theta{0.0, 20 * kDeg, 40 * kDeg, 60 * kDeg},
      phi{0.0, 60 * kDeg, 120 * kDeg, kPi};
  const auto linear = [](double ti, double to, double p) { return 1.0 + ti + 2.0 * to + 3.0 * p; };
  std::vector<double> values;
  for (double ti : theta)
    for (double to : theta)
      for (double p : phi) values.push_back(linear(ti, to, p) / (std::cos(ti) * std::cos(to)));
  const BrdfTable table(theta, theta, phi, values);
  EXPECT_NEAR(table.cosineWeightedAt(30 * kDeg, 30 * kDeg, 90 * kDeg),
              linear(30 * kDeg, 30 * kDeg, 90 * kDeg), 1e-12);
  // Beyond θ = 60° the table holds f_r at 60°, on nodes 1° apart out to 90°.
  EXPECT_NEAR(table.brdf(20 * kDeg, 85 * kDeg, 60 * kDeg), values[(1 * 4 + 3) * 4 + 1], 1e-12)
      << "beyond its nodes the table holds its edge values";
  EXPECT_EQ(table.cosineWeightedAt(20 * kDeg, 90 * kDeg, 60 * kDeg), 0.0) << "nothing at grazing";
  EXPECT_EQ(table.brdf(30 * kDeg, 30 * kDeg, -45 * kDeg),
            table.brdf(30 * kDeg, 30 * kDeg, 45 * kDeg))
      << "even in Δφ";
  // A peak at one node: between nodes the cubic stays between its cell's corners (no overshoot,
  // no negative value beside the peak).
  std::vector<double> spike(theta.size() * theta.size() * phi.size(), 0.0);
  const std::size_t at = (1 * theta.size() + 1) * phi.size() + 2;
  spike[at] = 5.0;
  const BrdfTable peaked(theta, theta, phi, spike);
  const double peak_g = 5.0 * std::cos(20 * kDeg) * std::cos(20 * kDeg);
  for (double ti = 0.0; ti <= 90.0; ti += 0.5) {
    for (double to = 0.0; to <= 90.0; to += 2.5) {
      for (double p = 0.0; p <= 180.0; p += 7.5) {
        const double g = peaked.cosineWeightedAt(ti * kDeg, to * kDeg, p * kDeg);
        ASSERT_GE(g, 0.0) << ti << " " << to << " " << p;
        ASSERT_LE(g, peak_g * (1.0 + 1e-12)) << ti << " " << to << " " << p;
      }
    }
  }
  EXPECT_THROW(BrdfTable({0.0, 0.0}, {0.0}, {0.0}, {1.0, 1.0}), std::invalid_argument);
  EXPECT_THROW(BrdfTable({0.0}, {0.0}, {0.0}, {-1.0}), std::invalid_argument);
}

// The table's own hemispherical reflectance (its cell quadrature) against brute force over the
// outgoing directions through the material, at its nodes and between them.
TEST(BrdfTable, HemisphericalReflectanceIsTheBruteForceIntegralOfItsInterpolant) {
  const auto table = beckmannTable(0.7, 0.2, 5.0, 10.0);
  const Material m = tableOnly(table);
  double largest = 0.0;
  for (double deg : {0.0, 20.0, 32.5, 45.0}) {
    const double theta_i = deg * kDeg;
    const Vec3 wi(std::sin(theta_i), 0.0, std::cos(theta_i));
    const double brute = hemisphericalReflectance(m, wi);
    const double cells = table->hemisphericalReflectance(theta_i);
    // The interpolant's second derivative jumps at every node, which Simpson crosses at steps
    // of 4e-4 rad: far below 1e-5 of the albedo.
    EXPECT_NEAR(brute, cells, 1e-5) << deg << " deg";
    largest = std::max(largest, cells);
    std::printf("[ table ] albedo at %g deg: brute force %.7f, the table's cells %.7f\n", deg,
                brute, cells);
  }
  const BrdfTable::Reflectance most = table->maxHemisphericalReflectance();
  EXPECT_GE(most.value, largest) << "the check meets every node and the points between";
  EXPECT_LE(most.value, 0.7 * 1.01) << "a σ = 0.2 lobe of ρ 0.7: no more than its ρ, but for "
                                       "the interpolation";
  std::printf("[ table ] largest albedo %.6f at %.4g deg\n", most.value, most.theta_i_rad / kDeg);
}

// A coarse table (15° steps) of a narrow lobe: its bound beyond each pair's own tilt holds the
// interpolant the integrator samples, over random pairs of directions.
TEST(BrdfTable, ACoarseTablesBoundIsNeverBelowWhatItReflects) {
  const auto table = beckmannTable(0.8, 0.05, 15.0, 30.0);
  std::mt19937_64 rng(11);
  int checked = 0;
  for (int k = 0; k < 400000; ++k) {
    const Pair p = randomPair(rng);
    if (!(p.cos_i > 0.0 && p.cos_r > 0.0)) continue;
    const double value = table->cosineWeighted(p.n, p.wi, p.wo, p.cos_i, p.cos_r);
    ASSERT_LE(value, table->maxBeyond(p.tan2) * (1.0 + 1e-12)) << "tan² " << p.tan2;
    // And with the pair's own angles as the largest: the coarse envelope over all three.
    const double theta_i = std::acos(p.cos_i) * (1.0 + 1e-9),
                 theta_o = std::acos(p.cos_r) * (1.0 + 1e-9);
    ASSERT_LE(value, table->maxBeyond(p.tan2, theta_i, theta_o) * (1.0 + 1e-12))
        << "tan² " << p.tan2 << " θi " << theta_i << " θo " << theta_o;
    // And with the pair's own angles as the least: the factor that takes g to 0 at grazing.
    const double least_i = std::acos(p.cos_i) * (1.0 - 1e-9),
                 least_o = std::acos(p.cos_r) * (1.0 - 1e-9);
    ASSERT_LE(value,
              table->maxBeyond(p.tan2) * table->grazingFactor(least_i, least_o) * (1.0 + 1e-12))
        << "tan² " << p.tan2 << " θi " << least_i << " θo " << least_o;
    ++checked;
  }
  EXPECT_GT(checked, 100000);
  // The table is given to 80° and completed on 1° steps, so its last cell of θo is 89° to
  // 90°: there the factor falls linearly to 0 at grazing, 1.25 × (90° − θo) / 1°.
  EXPECT_DOUBLE_EQ(table->grazingFactor(0.0, 0.5 * kPi), 0.0);
  EXPECT_NEAR(table->grazingFactor(0.0, 89.9 * kDeg), 0.125, 1e-9);
  EXPECT_DOUBLE_EQ(table->grazingFactor(0.0, 80.0 * kDeg), 1.0);
  EXPECT_DOUBLE_EQ(table->grazingFactor(std::nan(""), std::nan("")), 1.0) << "a NaN proves nothing";
}

// Grazing pairs, where the bound must vanish with the term: θo within 0.5° of the horizon.
TEST(BrdfTable, ItsBoundVanishesAtGrazingAndHoldsThere) {
  const auto table = beckmannTable(0.8, 0.3, 15.0, 30.0);
  std::mt19937_64 rng(12);
  std::uniform_real_distribution<double> grazing(89.5 * kDeg, 0.5 * kPi), any(0.0, 0.5 * kPi),
      azimuth(0.0, kPi);
  double largest_ratio = 0.0;
  for (int k = 0; k < 100000; ++k) {
    const double ti = any(rng), to = grazing(rng), dp = azimuth(rng);
    const double value = table->cosineWeightedAt(ti, to, dp);
    const Vec3 wi(std::sin(ti), 0.0, std::cos(ti));
    const Vec3 wo(std::sin(to) * std::cos(dp), std::sin(to) * std::sin(dp), std::cos(to));
    const Vec3 h = wi + wo;
    const double tan2 = (h.x * h.x + h.y * h.y) / (h.z * h.z);
    const double bound = table->maxBeyond(tan2 * (1.0 - 1e-9)) *
                         table->grazingFactor(ti * (1.0 - 1e-9), to * (1.0 - 1e-9));
    ASSERT_LE(value, bound * (1.0 + 1e-12) + 1e-300) << "θi " << ti << " θo " << to;
    if (bound > 0.0) largest_ratio = std::max(largest_ratio, value / bound);
  }
  // At most 0.5° from grazing the factor is ≤ 0.625: the bound is the envelope's at most that.
  EXPECT_LE(table->grazingFactor(0.0, 89.5 * kDeg), 0.625 + 1e-9);
  std::printf("[ table ] grazing: the term reaches %.3f of its bound\n", largest_ratio);
}

// A table of a Beckmann lobe, fine enough for its width, gives the lobe's own run within the
// table's interpolation error: measured here at the cells' centres, where linear interpolation
// errs most.
TEST(BrdfTable, ATableOfABeckmannLobeGivesTheLobesIrradiance) {
  const double rho = 0.8, sigma = 0.1, tolerance = 1e-4;
  const auto table = beckmannTable(rho, sigma, 1.0, 2.0);
  // The interpolation's relative error over the lobe (half vector within 3σ), at cell centres.
  double interpolation = 0.0;
  const Beckmann lobe{sigma};
  for (double ti = 0.5; ti < 70.0; ti += 1.0) {
    for (double to = 0.5; to < 70.0; to += 1.0) {
      for (double p = 1.0; p < 180.0; p += 2.0) {
        const Vec3 n(0, 0, 1), wi(std::sin(ti * kDeg), 0.0, std::cos(ti * kDeg));
        const Vec3 wo(std::sin(to * kDeg) * std::cos(p * kDeg),
                      std::sin(to * kDeg) * std::sin(p * kDeg), std::cos(to * kDeg));
        const Vec3 h = wi + wo;
        if ((h.x * h.x + h.y * h.y) / (h.z * h.z) > 9.0 * sigma * sigma) continue;
        const double exact = rho * lobe.xi(n, h) / (4.0 * wi.z * wo.z);
        interpolation = std::max(
            interpolation, std::abs(table->brdf(ti * kDeg, to * kDeg, p * kDeg) / exact - 1.0));
      }
    }
  }
  const FacetIntegrator of_table = cylinder(tableOnly(table), accuracy(tolerance));
  const FacetIntegrator of_lobe = cylinder(test::mirror(rho, sigma), accuracy(tolerance));
  IntegratorWorkspace ws;
  double worst = 0.0;
  for (const Vec3& obs : observers()) {
    const ObserverResult t = of_table.adaptive(obs, ws);
    const ObserverResult b = of_lobe.adaptive(obs, ws);
    ASSERT_TRUE(t.converged && b.converged)
        << obs.x << "," << obs.y << ": " << t.converged << " " << t.evaluations << " "
        << t.depth_limited << " " << t.irradiance_w_m2 << " " << t.error_estimate_w_m2 << " / "
        << b.converged << " " << b.irradiance_w_m2;
    // Both to their tolerance; the table's BRDF within `interpolation` of the lobe's wherever
    // the lobe is more than e^-4.5 of its peak (beyond, the light is a hundredth of the total).
    EXPECT_NEAR(t.irradiance_w_m2 / b.irradiance_w_m2, 1.0,
                interpolation + 2.0 * tolerance + 0.01 * std::exp(-4.5))
        << obs.x << "," << obs.y;
    worst = std::max(worst, std::abs(t.irradiance_w_m2 / b.irradiance_w_m2 - 1.0));
    std::printf(
        "[ table ] observer (%.2f, %.2f): table %.6e, lobe %.6e W/m²; %lld against %lld "
        "evaluations\n",
        obs.x, obs.y, t.irradiance_w_m2, b.irradiance_w_m2, static_cast<long long>(t.evaluations),
        static_cast<long long>(b.evaluations));
  }
  // The bound 6σ off the peak: what the table holds beyond 80° (f_r at 80°, toward grazing
  // forward scatter, where θN is ill-conditioned) keeps it high; hence the table's cost.
  std::printf(
      "[ table ] interpolation error over the lobe %.2e; worst irradiance difference "
      "%.2e; bound at 0 and 6σ: %.3g and %.3g 1/sr\n",
      interpolation, worst, table->maxBeyond(0.0),
      table->maxBeyond(std::pow(std::tan(6.0 * sigma), 2)));
}

// The pieces' bounds take ABg and the table as they take a lobe: never below a piece's sample.
TEST(MaterialScatter, EachPiecesBoundHoldsAbgAndTheTable) {
  Material m{0.2, 0.1, Beckmann{0.02}};
  m.abg = AbgScatter{0.002, 1e-3, 2.0};
  m.table = beckmannTable(0.2, 0.1, 5.0, 10.0);
  const FacetIntegrator fi = cylinder(m, accuracy(1e-4));
  const Target& t = fi.target();
  std::vector<SubFacet> pieces;
  for (std::uint32_t f = 0; f < t.facetCount(); ++f) subFacetsAtDepth(t, f, 3, pieces);
  int lit = 0;
  for (const Vec3& obs : observers()) {
    for (const SubFacet& piece : pieces) {
      const PatchGeometry g = patchGeometry(t, piece, NormalModel::Surface);
      for (const Material& part : {abgOnly(*m.abg), tableOnly(m.table), m}) {
        const double sample = facetIrradiance(g, obs, fi.beam(), part);
        if (sample == 0.0) continue;
        ++lit;
        const ContributionBound b = contributionBound(g, obs, fi.beam(), part, ResolutionLimits{});
        ASSERT_GE(b.upper_w_m2, sample) << obs.x << "," << obs.y << "," << obs.z;
      }
    }
  }
  EXPECT_GT(lit, 500) << "the pieces must be lit and seen";
  const std::vector<Material> terms = m.terms();
  ASSERT_EQ(terms.size(), 3u) << "the lobe with the floor, ABg, the table";
  EXPECT_TRUE(terms[1].abg && !terms[1].table && terms[1].specular_reflectance == 0.0);
  EXPECT_TRUE(terms[2].table && !terms[2].abg);
  EXPECT_EQ(*m.narrowestWidthRad(), std::min({0.02, m.abg->widthRad(), m.table->widthRad()}));
}

}  // namespace
}  // namespace glint
