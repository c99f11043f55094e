#pragma once
// References for the tests that do not come from the code under test: closed forms of
// mirror-like shapes and the lobe's normalisation integral by quadrature.

#include <cmath>

#include "facets/beckmann.h"
#include "support/quadrature.h"

namespace glint::test {

// A mirror-like sphere of radius R at the origin under a collimated beam of irradiance e0
// along −z, seen from `observer`. For a narrow lobe the glint pencil diverges from the convex
// mirror's two focal lines, f_t = R cos θi / 2 and f_s = R / (2 cos θi) behind the surface, so
// at a distance L from the glint E = ρs e0 R² / (4 (L + f_t)(L + f_s)).
inline double mirrorSphere(double rho, double e0, double radius, const Vec3& observer) {
  const Vec3 dir = glm::normalize(observer);
  const Vec3 glint = radius * glm::normalize(dir + Vec3(0, 0, 1));
  const double cos_i = glm::dot(glm::normalize(glint), Vec3(0, 0, 1));
  const double len = glm::length(observer - glint);
  return rho * e0 * radius * radius /
         (4.0 * (len + 0.5 * radius * cos_i) * (len + 0.5 * radius / cos_i));
}

// A mirror cylinder (radius R, axis z through the origin) lit along +x with irradiance e0,
// seen from `obs` at a height within its length. Each glint reflects a pencil that diverges
// horizontally from the convex mirror's virtual line focus, R cos θi / 2 behind the surface,
// and stays collimated vertically:  E = ρ e0 R cos θi / (2L + R cos θi).
inline double mirrorCylinder(double rho, double e0, double radius, const Vec3& obs) {
  auto miss = [&](double phi) {  // (O − P) × r in the horizontal plane
    const double px = -radius * std::cos(phi), py = radius * std::sin(phi);
    const double rx = -std::cos(2 * phi), ry = std::sin(2 * phi);
    return (obs.x - px) * ry - (obs.y - py) * rx;
  };
  double lo = -0.2, hi = lo;
  for (double phi = -0.2; phi < 0.5 * kPi; phi += 1e-3) {  // bracket the glint
    if (miss(phi) * miss(phi + 1e-3) <= 0.0) {
      lo = phi;
      hi = phi + 1e-3;
      break;
    }
  }
  for (int k = 0; k < 200; ++k) {
    const double mid = 0.5 * (lo + hi);
    (miss(lo) * miss(mid) <= 0.0 ? hi : lo) = mid;
  }
  const double phi = 0.5 * (lo + hi);
  const double len = std::hypot(obs.x + radius * std::cos(phi), obs.y - radius * std::sin(phi));
  return rho * e0 * radius * std::cos(phi) / (2.0 * len + radius * std::cos(phi));
}

// A Lambertian disk of radius R lit at cos θi by irradiance e0, seen on its axis at height h:
// E = ∫ (ρd/π) e0 cos θi cos θr / d² dA = 2 ρd e0 cos θi (1 − h / √(R² + h²)).
inline double lambertianDiskOnAxis(double rho_d, double e0, double cos_i, double radius, double h) {
  return 2.0 * rho_d * e0 * cos_i * (1.0 - h / std::hypot(radius, h));
}

// ∫ Ξ cos θN dω over the hemisphere of normals, with Ξ evaluated through the vector form the
// integrator uses (normal +z, half vector at θN). It is integrated in s = tan θN / σ, where
// the lobe lives, so the same rule resolves σ = 1e-5 and σ = 1: 20 000 Simpson intervals of a
// Gaussian in s leave an error far below 1e-10.
inline double lobeIntegral(const Beckmann& b) {
  const Vec3 n(0, 0, 1);
  auto ring = [&](double theta) {
    const Vec3 h(std::sin(theta), 0.0, std::cos(theta));
    return b.xi(n, h) * std::cos(theta) * std::sin(theta) * 2.0 * kPi;
  };
  auto in_s = [&](double s) {
    const double t = b.sigma * s;
    return ring(std::atan(t)) * b.sigma / (1.0 + t * t);
  };
  // e^{-s²/2} is below 1e-300 beyond s = 40; the rest of the hemisphere (θ beyond atan 60σ)
  // only matters for broad lobes.
  return simpson(in_s, 0.0, 60.0, 20000) + simpson(ring, std::atan(60.0 * b.sigma), kPi / 2, 20000);
}

}  // namespace glint::test
