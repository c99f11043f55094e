#include "facets/detail/diffuse_moments.h"

#include <cmath>
#include <limits>

#include "facets/triangle_rule.h"

namespace glint::detail {
namespace {

// For unit n and e, |∇³K[e, e, e]| ≤ 24 / |y|⁵ for K(y) = n·y / |y|³ = −∇(1/|y|)·n: the
// k-th derivative of 1/|y| along a unit u is k! P_k(ŷ·u) / |y|^(k+1) (the Legendre generating
// function), |P_k| ≤ 1, and a symmetric multilinear form on a Hilbert space is no larger on
// several unit vectors than on one repeated (Banach), so |∇⁴(1/|y|)[n, e, e, e]| ≤ 4! / |y|⁵.
constexpr double kThirdDerivativeBound = 24.0;

// The moments' integrals, summed by one rule over one subdivision of the facet.
struct Sums {
  double total = 0.0;
  std::array<double, 3> first{};
  std::array<std::array<double, 3>, 3> second{};
  Tensor3 third{};
  bool ok = true;
};

// The facet's four quarters (1→4 midpoint split), by their barycentric corners.
const std::array<std::array<Vec3, 3>, 4> kQuarters{{
    {Vec3(1.0, 0.0, 0.0), Vec3(0.5, 0.5, 0.0), Vec3(0.5, 0.0, 0.5)},
    {Vec3(0.5, 0.5, 0.0), Vec3(0.0, 1.0, 0.0), Vec3(0.0, 0.5, 0.5)},
    {Vec3(0.5, 0.0, 0.5), Vec3(0.0, 0.5, 0.5), Vec3(0.0, 0.0, 1.0)},
    {Vec3(0.5, 0.5, 0.0), Vec3(0.0, 0.5, 0.5), Vec3(0.5, 0.0, 0.5)},
}};

// The moments by the points × points conical product rule on each quarter.
Sums integrate(const SurfaceMap& map, const Vec3& centre_m, const Beam& beam, double rho_d,
               int points, std::int64_t& evaluations) {
  const std::span<const TriangleNode> rule = conicalProductRule(points);
  Sums s;
  // Each quarter covers ⅛ of the facet's parameter triangle, of area ½.
  constexpr double area_uv = 0.125;
  for (const std::array<Vec3, 3>& c : kQuarters) {
    for (const TriangleNode& node : rule) {
      const Vec3 bary = node.bary[0] * c[0] + node.bary[1] * c[1] + node.bary[2] * c[2];
      const SurfacePoint p = map.at(bary);
      ++evaluations;
      if (!p.valid) {
        s.ok = false;
        return s;
      }
      const Beam::Footprint b = beam.footprint(p.position_m);
      const double cos_i = glm::dot(p.normal, b.toward_laser);
      // The facet was bounded as lit whole; a node that is not says the bound was wrong.
      if (!(cos_i > 0.0) || !(b.edge_margin > 0.0) || !(b.axial_m > 0.0)) {
        s.ok = false;
        return s;
      }
      const double g =
          rho_d / kPi * b.irradiance_w_m2 * cos_i * p.jacobian_m2 * area_uv * node.weight;
      const Vec3 delta = p.position_m - centre_m;
      s.total += g;
      for (int k = 0; k < 3; ++k) {
        const auto ku = static_cast<std::size_t>(k);
        s.first[ku] += g * p.normal[k];
        for (int l = 0; l < 3; ++l) {
          const auto lu = static_cast<std::size_t>(l);
          s.second[ku][lu] += g * p.normal[k] * delta[l];
          for (int j = 0; j < 3; ++j) {
            s.third[ku][lu][static_cast<std::size_t>(j)] += g * p.normal[k] * delta[l] * delta[j];
          }
        }
      }
    }
  }
  return s;
}

}  // namespace

DiffuseMoments diffuseMoments(const SurfaceMap& map, const PatchGeometry& g, const Beam& beam,
                              const Material& material, std::int64_t& evaluations) {
  DiffuseMoments m;
  m.centre_m = g.centre_m;
  m.radius_m = g.radius_m;
  if (!(material.diffuse_reflectance > 0.0) || beam.swept()) return m;
  // Lit whole: every normal of the facet sees the laser from every point, no edge of the beam
  // (nor the laser's own plane) crosses it, and a Gaussian is no narrower (w ≥ R / 2) than
  // the rules' quarters (each within about R / 2 of its centre), over which 25 nodes follow it
  // and their change from 16 shows what they miss: g is smooth over the facet and the rules
  // converge on it. (profileMayBendInBall(c, ρ) holds the profile to w ≥ 2ρ.)
  if (!(beam.maxIrradianceInBall(g.centre_m, g.radius_m) > 0.0) ||
      beam.edgeMayCrossBall(g.centre_m, g.radius_m) ||
      beam.profileMayBendInBall(g.centre_m, 0.25 * g.radius_m)) {
    return m;
  }
  const double angle_i = angleBetween(g.normal, beam.at(g.centre_m).toward_laser);
  if (!(angle_i + g.cone_rad + beam.directionSpreadInBall(g.radius_m) < 0.5 * kPi)) return m;

  const double rho_d = material.diffuse_reflectance;
  // On the facet's four quarters, a degree-9 rule, its error taken as its change from degree 7.
  const Sums fine = integrate(map, g.centre_m, beam, rho_d, 5, evaluations);
  if (!fine.ok) return m;
  const Sums coarse = integrate(map, g.centre_m, beam, rho_d, 4, evaluations);
  if (!coarse.ok) return m;
  m.total = fine.total;
  m.first = fine.first;
  m.second = fine.second;
  m.third = fine.third;
  m.total_error = std::abs(fine.total - coarse.total);
  double first2 = 0.0, second2 = 0.0, third2 = 0.0;
  for (std::size_t k = 0; k < 3; ++k) {
    const double df = fine.first[k] - coarse.first[k];
    first2 += df * df;
    for (std::size_t l = 0; l < 3; ++l) {
      const double ds = fine.second[k][l] - coarse.second[k][l];
      second2 += ds * ds;
      for (std::size_t j = 0; j < 3; ++j) {
        const double dt = fine.third[k][l][j] - coarse.third[k][l][j];
        third2 += dt * dt;
      }
    }
  }
  m.first_error = std::sqrt(first2);
  m.second_error = std::sqrt(second2);
  m.third_error = std::sqrt(third2);
  m.usable = std::isfinite(m.total) && std::isfinite(m.total_error) &&
             std::isfinite(m.first_error) && std::isfinite(m.second_error) &&
             std::isfinite(m.third_error);
  return m;
}

std::optional<DiffuseEstimate> diffuseFromMoments(const DiffuseMoments& m, const PatchGeometry& g,
                                                  const Vec3& observer_m) {
  if (!m.usable) return std::nullopt;
  const Vec3 r = observer_m - m.centre_m;
  const double d = glm::length(r);
  const double radius = m.radius_m;
  if (!(d > 2.0 * radius)) return std::nullopt;
  // Every normal faces the observer from every point: cos θr > 0 over the whole facet, so no
  // horizon cuts the kernel.
  if (!(angleBetween(g.normal, r) + g.cone_rad + std::asin(radius / d) < 0.5 * kPi)) {
    return std::nullopt;
  }
  // The expansion's terms: first order m·r, rᵀMr, tr M; second order
  // a = ∫ g (n·δ)(r·δ), b = ∫ g (n·r)|δ|², c = ∫ g (n·r)(r·δ)².
  double rm = 0.0, rmr = 0.0, trace = 0.0, a = 0.0, b = 0.0, c = 0.0;
  for (std::size_t k = 0; k < 3; ++k) {
    const double rk = r[static_cast<int>(k)];
    rm += m.first[k] * rk;
    trace += m.second[k][k];
    for (std::size_t l = 0; l < 3; ++l) {
      const double rl = r[static_cast<int>(l)];
      rmr += rk * m.second[k][l] * rl;
      a += m.third[k][k][l] * rl;
      b += rk * m.third[k][l][l];
      for (std::size_t j = 0; j < 3; ++j) c += rk * m.third[k][l][j] * rl * r[static_cast<int>(j)];
    }
  }
  const double d2 = d * d, d3 = d2 * d, d5 = d3 * d2;
  const double value =
      (rm + 3.0 * rmr / d2 - trace) / d3 + 0.5 * (-6.0 * a - 3.0 * b + 15.0 * c / d2) / d5;
  // The Taylor remainder (see the header), and what the moments' own quadrature error moves the
  // value by: |Δm| |r| / |r|³; (3 ‖ΔM‖₂ + |tr ΔM|) / |r|³ ≤ (3 + √3) ‖ΔM‖_F / |r|³; and
  // ½ (6√3 + 3√3 + 15) ‖ΔT‖_F / |r|⁴ for the second order, each contraction of ΔT with unit
  // vectors (or the identity, √3) at most its Frobenius norm times theirs.
  const double gap = d - radius;
  const double remainder = kThirdDerivativeBound / 6.0 * radius * radius * radius *
                           (m.total + m.total_error) / (gap * gap * gap * gap * gap);
  const double quadrature =
      m.first_error / d2 + 5.0 * m.second_error / d3 + 16.0 * m.third_error / (d2 * d2);
  DiffuseEstimate e;
  e.irradiance_w_m2 = std::max(value, 0.0);
  e.error_w_m2 = remainder + quadrature + std::max(-value, 0.0);
  if (!std::isfinite(e.irradiance_w_m2) || !std::isfinite(e.error_w_m2)) return std::nullopt;
  return e;
}

}  // namespace glint::detail
