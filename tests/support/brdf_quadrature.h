#pragma once
// A material's hemispherical reflectance by brute force, for the tests of its normalisation.

#include "facets/material.h"
#include "support/quadrature.h"

namespace glint::test {

// ∫ f_r cos θr dω over the outgoing hemisphere for light from @p wi (normal +z), brute force:
// Simpson on the angle α from the mirror direction (where every model here peaks), in
// @p alpha_steps steps over [0, π], and on its azimuth in 256.
inline double hemisphericalReflectance(const Material& m, const Vec3& wi, int alpha_steps) {
  const Vec3 n(0, 0, 1);
  const double cos_i = glm::dot(n, wi);
  const Vec3 r = 2.0 * cos_i * n - wi;
  const Vec3 e1 = glm::normalize(glm::cross(r, Vec3(0, 1, 0)));
  const Vec3 e2 = glm::cross(r, e1);
  const auto ring = [&](double alpha) {
    return simpson(
        [&](double beta) {
          const Vec3 wo =
              std::cos(alpha) * r + std::sin(alpha) * (std::cos(beta) * e1 + std::sin(beta) * e2);
          const double cos_r = glm::dot(n, wo);
          if (!(cos_r > 0.0)) return 0.0;
          return m.cosineWeightedBrdf(n, wi, wo, cos_i, cos_r) / cos_i;
        },
        0.0, 2.0 * kPi, 256);
  };
  return simpson([&](double a) { return ring(a) * std::sin(a); }, 0.0, kPi, alpha_steps);
}

}  // namespace glint::test
