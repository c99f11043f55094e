#include "facets/beckmann.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "facets/material.h"
#include "support/quadrature.h"
#include "support/references.h"

namespace glint {
namespace {

TEST(Beckmann, NormalizedOverHemisphere) {
  for (double sigma : {0.001, 0.003, 0.01, 0.03, 0.1, 0.3, 0.5}) {
    EXPECT_NEAR(test::lobeIntegral(Beckmann{sigma}), 1.0, 1e-9) << "sigma = " << sigma;
  }
}

TEST(Beckmann, ZeroNotNanAtGrazing) {
  const Vec3 n(0, 0, 1);
  for (double sigma : {1e-5, 0.001, 0.003, 0.03, 0.5, 1.0}) {
    const Beckmann b{sigma};
    for (double deg : {89.9999, 90.0, 90.0001, 135.0, 180.0}) {
      const double t = deg * kPi / 180.0;
      const double xi = b.xi(n, Vec3(std::sin(t), 0.0, std::cos(t)));
      EXPECT_FALSE(std::isnan(xi)) << "sigma " << sigma << " at " << deg << " deg";
      EXPECT_EQ(xi, 0.0) << "sigma " << sigma << " at " << deg << " deg";
    }
    EXPECT_EQ(b.xi(n, Vec3(0.0)), 0.0) << "zero half vector, sigma " << sigma;
    EXPECT_EQ(b.xiFromTan2(std::numeric_limits<double>::infinity()), 0.0) << "sigma " << sigma;
  }
}

TEST(Beckmann, TangentFormMatchesTextbookForm) {
  const Vec3 n(0, 0, 1);
  for (double sigma : {0.003, 0.1, 0.5}) {
    const Beckmann b{sigma};
    for (double t : {0.0, 0.5 * sigma, 2.0 * sigma, 3.0 * sigma}) {
      const double theta = std::atan(t);
      const double c = std::cos(theta);
      const double textbook =
          std::exp(-t * t / (2 * sigma * sigma)) / (2 * kPi * sigma * sigma * c * c * c * c);
      // Unnormalised half vector of length 1.7: only its direction may matter.
      const double xi = b.xi(n, 1.7 * Vec3(std::sin(theta), 0.0, c));
      EXPECT_NEAR(xi / textbook, 1.0, 1e-12) << "sigma " << sigma << " tan " << t;
    }
  }
}

TEST(Beckmann, MaxBeyondBoundsEveryLaterAngle) {
  // For σ > 1/2 the lobe peaks away from θN = 0; the bound must follow.
  for (double sigma : {0.003, 0.3, 0.6, 1.0, 3.0}) {
    const Beckmann b{sigma};
    for (double s_min : {0.0, 0.01, 0.5, 3.0, 35.0}) {
      const double bound = b.maxXiBeyond(s_min);
      for (double s = s_min; s < s_min + 100.0; s += 0.01) {
        ASSERT_LE(b.xiFromTan2(s), bound * (1 + 1e-14)) << "sigma " << sigma << " s " << s;
      }
    }
  }
}

TEST(Material, LambertianAlbedoEqualsDiffuseReflectance) {
  const Material m{0.0, 0.7, Beckmann{0.1}};
  const Vec3 n(0, 0, 1);
  const Vec3 wi = glm::normalize(Vec3(0.3, 0.0, 1.0));
  const double cos_i = glm::dot(n, wi);
  // ∫ f_r cos θr dω over the outgoing hemisphere.
  auto ring = [&](double theta) {
    const Vec3 wo(std::sin(theta), 0.0, std::cos(theta));
    return m.cosineWeightedBrdf(n, wi, wo, cos_i, std::cos(theta)) / cos_i * std::sin(theta) * 2.0 *
           kPi;
  };
  EXPECT_NEAR(test::simpson(ring, 0.0, kPi / 2, 2000), 0.7, 1e-12)
      << "a Lambertian surface reflects ρd of what it receives";
}

}  // namespace
}  // namespace glint
