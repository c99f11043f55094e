// glint fit's core (material_fit.h): a table made from known closed forms gives them back, and
// the fit's reported errors are the errors it has.

#include "facets/material_fit.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <vector>

#include "facets/brdf_table.h"

namespace glint {
namespace {

constexpr double kDeg = kPi / 180.0;

// @p m's f_r on steps of 5° in θ (to 85°) and 10° in Δφ.
std::shared_ptr<const BrdfTable> tableOf(const Material& m) {
  std::vector<double> theta, phi, values;
  for (int t = 0; t <= 85; t += 5) theta.push_back(t * kDeg);
  for (int p = 0; p <= 180; p += 10) phi.push_back(p * kDeg);
  const Vec3 n(0, 0, 1);
  for (double ti : theta) {
    for (double to : theta) {
      for (double p : phi) {
        const Vec3 wi(std::sin(ti), 0.0, std::cos(ti));
        const Vec3 wo(std::sin(to) * std::cos(p), std::sin(to) * std::sin(p), std::cos(to));
        values.push_back(m.cosineWeightedBrdf(n, wi, wo, wi.z, wo.z) / (wi.z * wo.z));
      }
    }
  }
  return std::make_shared<const BrdfTable>(theta, theta, phi, values);
}

// A weathered paint: a specular lobe, a haze, ABg wings and a Lambertian floor. The table holds
// the lobes on 5° steps (the narrow lobe, σ 0.08, spans about two of them), enough for the fit
// to find every term again.
TEST(MaterialFit, ATableOfKnownClosedFormsGivesThemBack) {
  Material truth{0.2, 0.3, Beckmann{0.08}, {{0.15, Beckmann{0.25}}}};
  truth.abg = AbgScatter{0.004, 0.02, 1.5};
  const MaterialFit fit = fitMaterial(*tableOf(truth), MaterialFitModel{});
  const Material& m = fit.material;
  ASSERT_EQ(m.more_lobes.size(), 1u);
  ASSERT_TRUE(m.abg.has_value());
  // The two lobes may come back in either order.
  const bool swapped = m.lobe.sigma > m.more_lobes[0].shape.sigma;
  const double s1 = swapped ? m.more_lobes[0].shape.sigma : m.lobe.sigma;
  const double s2 = swapped ? m.lobe.sigma : m.more_lobes[0].shape.sigma;
  const double r1 = swapped ? m.more_lobes[0].reflectance : m.specular_reflectance;
  EXPECT_NEAR(s1, 0.08, 1e-3 * 0.08);
  EXPECT_NEAR(s2, 0.25, 1e-3 * 0.25);
  EXPECT_NEAR(r1, 0.2, 1e-3 * 0.2);
  EXPECT_NEAR(m.diffuse_reflectance, 0.3, 1e-3 * 0.3);
  EXPECT_NEAR(m.abg->g, 1.5, 1e-2);
  // The table is the model: what the fit leaves is its own convergence.
  EXPECT_LT(fit.rms_log_error, 1e-4);
  EXPECT_LT(fit.max_relative_error, 1e-3);
  const double energy = 0.2 + 0.15 + 0.3 + truth.abg->totalIntegratedScatter();
  EXPECT_NEAR(fit.energy, energy, 1e-3 * energy);
  std::printf(
      "[ fit ] σ %.5f and %.5f, ρd %.5f, ABg g %.4f; rms log error %.2e, largest "
      "relative %.2e\n",
      s1, s2, m.diffuse_reflectance, m.abg->g, fit.rms_log_error, fit.max_relative_error);
}

// A fit that lacks a term says so in its errors: the same table without ABg in the model.
TEST(MaterialFit, AModelWithoutATermReportsTheErrorItLeaves) {
  Material truth{0.2, 0.3, Beckmann{0.08}, {{0.15, Beckmann{0.25}}}};
  truth.abg = AbgScatter{0.02, 0.02, 1.5};
  MaterialFitModel model;
  model.abg = false;
  const MaterialFit fit = fitMaterial(*tableOf(truth), model);
  EXPECT_FALSE(fit.material.abg.has_value());
  EXPECT_GT(fit.max_relative_error, 0.01) << "ABg's wings are 1.5 powers, no Gaussian";
  std::printf("[ fit ] without ABg: rms log error %.3g, largest relative %.3g\n", fit.rms_log_error,
              fit.max_relative_error);
}

}  // namespace
}  // namespace glint
