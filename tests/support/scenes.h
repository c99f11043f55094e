#pragma once
// Small scenes for the tests, built directly (no scene file).

#include <functional>

#include "facets/integrator.h"
#include "facets/tessellate.h"

namespace glint::test {

// A collimated flat-top beam of irradiance e0_w_m2 and radius radius_m arriving along `dir`,
// its laser 100 m back from `target`.
inline Beam flatTop(const Vec3& target, const Vec3& dir, double e0_w_m2, double radius_m) {
  Beam b;
  b.direction = glm::normalize(dir);
  b.origin_m = target - 100.0 * b.direction;
  b.radius_m = radius_m;
  b.power_w = e0_w_m2 * kPi * radius_m * radius_m;
  b.profile = BeamProfile::FlatTop;
  return b;
}

inline Material mirror(double rho_s, double sigma, double rho_d = 0.0) {
  return Material{rho_s, rho_d, Beckmann{sigma}};
}

inline IntegratorOptions accuracy(double tolerance, double floor_w_m2 = 1e-12) {
  IntegratorOptions o;
  o.tolerance = tolerance;
  o.floor_w_m2 = floor_w_m2;
  return o;
}

// One shape of one material under `beam`; `add` receives the target, material index and the
// direction toward the laser.
inline FacetIntegrator singleObject(const Material& m, const Beam& beam,
                                    const std::function<void(Target&, std::uint32_t, Vec3)>& add,
                                    const IntegratorOptions& options) {
  Target t;
  const std::uint32_t mi = t.addMaterial(m);
  add(t, mi, -beam.direction);
  return FacetIntegrator(std::move(t), beam, options);
}

}  // namespace glint::test
