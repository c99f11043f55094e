#pragma once
// An independent reference for the irradiance one analytic shape sends to an observer: the
// integrand of docs/physics.md written out again here (nothing in facets/ is evaluated, only its
// plain data structs are read) and integrated by nested adaptive Gauss–Kronrod over the shape's
// own exact parametrisation, not over facets.
//
// A lobe of σ = 0.001 is a spike in that parametrisation that a fixed rule would step over.
// Each 1-D integral is therefore cut at the spike (the lit, visible, in-beam point of the line
// where tan θN is least, found by a scan refined by golden section) into segments whose
// widths halve toward it, so the spike sits at the end of short segments whatever its width
// down to 1e-6 of the range; edges (beam, terminator, horizon, rim) are resolved by each
// segment's adaptive bisection. Slow (about 10⁶ evaluations per observer) and simple: it is
// only a reference.

#include <algorithm>
#include <boost/math/quadrature/gauss_kronrod.hpp>
#include <cmath>
#include <functional>
#include <limits>
#include <utility>
#include <vector>

#include "facets/beam.h"
#include "facets/material.h"
#include "facets/tessellate.h"

namespace glint::test::brute {

/// A point of the surface, its outward unit normal and dA / (du dv).
struct SurfacePoint {
  Vec3 x_m;
  Vec3 normal;
  double jacobian;
};

/// A shape as (u, v) ↦ point over u ∈ [u0, u1], v ∈ v_range(u); a periodic v is one turn.
struct Parametrisation {
  double u0 = 0.0, u1 = 0.0;
  std::function<std::pair<double, double>(double)> v_range;
  std::function<SurfacePoint(double, double)> at;
  bool v_periodic = false;
};

/// The lit, visible, in-beam part of the integrand, as docs/physics.md states it. `tan2` receives
/// tan²θN where the point contributes, +∞ elsewhere (the spike finder's merit).
inline double integrand(const Beam& beam, const Material& m, const SurfacePoint& p,
                        const Vec3& observer_m, double* tan2 = nullptr) {
  if (tan2 != nullptr) *tan2 = std::numeric_limits<double>::infinity();
  const Vec3 d = glm::normalize(beam.direction);
  const Vec3 rel = p.x_m - beam.origin_m;
  const double z = glm::dot(rel, d);
  if (z <= 0.0) return 0.0;
  const double rho2 = std::max(0.0, glm::dot(rel, rel) - z * z);
  const double r2 = beam.radius_m * beam.radius_m;
  double e_beam = 0.0;
  if (beam.profile == BeamProfile::FlatTop) {
    e_beam = rho2 <= r2 ? beam.power_w / (kPi * r2) : 0.0;
  } else {
    e_beam = 2.0 * beam.power_w / (kPi * r2) * std::exp(-2.0 * rho2 / r2);
  }
  if (e_beam == 0.0) return 0.0;
  const Vec3 wi = -d;
  const double cos_i = glm::dot(p.normal, wi);
  if (cos_i <= 0.0) return 0.0;
  const Vec3 to = observer_m - p.x_m;
  const double dist2 = glm::dot(to, to);
  const Vec3 wo = to / std::sqrt(dist2);
  const double cos_r = glm::dot(p.normal, wo);
  if (cos_r <= 0.0) return 0.0;
  double f = m.diffuse_reflectance / kPi * cos_i * cos_r;
  const Vec3 h = glm::normalize(wi + wo);
  const double c = glm::dot(h, p.normal);
  if (c > 0.0) {
    const Vec3 t = h - c * p.normal;
    const double t2 = glm::dot(t, t) / (c * c);
    if (tan2 != nullptr) *tan2 = t2;
    const double s = m.lobe.sigma;
    f += 0.25 * m.specular_reflectance * std::exp(-t2 / (2.0 * s * s)) /
         (2.0 * kPi * s * s * c * c * c * c);
  }
  return e_beam * f / dist2 * p.jacobian;
}

/// The point of [a, b] where `merit` is least: a scan of n points refined by golden section
/// in the bracket around the best one (+∞ marks points that do not count).
inline double argMin(const std::function<double(double)>& merit, double a, double b, int n = 1024) {
  double best_x = 0.5 * (a + b), best = std::numeric_limits<double>::infinity();
  const double step = (b - a) / n;
  for (int k = 0; k <= n; ++k) {
    const double x = a + k * step, m = merit(x);
    if (m < best) best = m, best_x = x;
  }
  if (!std::isfinite(best)) return best_x;
  double lo = std::max(a, best_x - step), hi = std::min(b, best_x + step);
  const double g = 0.5 * (std::sqrt(5.0) - 1.0);
  double x1 = hi - g * (hi - lo), x2 = lo + g * (hi - lo);
  double f1 = merit(x1), f2 = merit(x2);
  for (int k = 0; k < 60; ++k) {
    if (f1 <= f2) {
      hi = x2, x2 = x1, f2 = f1, x1 = hi - g * (hi - lo), f1 = merit(x1);
    } else {
      lo = x1, x1 = x2, f1 = f2, x2 = lo + g * (hi - lo), f2 = merit(x2);
    }
  }
  const double x = 0.5 * (lo + hi);
  return merit(x) <= best ? x : best_x;
}

/// A value and the sum of its segments' error estimates.
struct Estimate {
  double value = 0.0;
  double error = 0.0;
};

/// ∫ f over [a, b] cut at the spike c into segments that halve toward it (see the header),
/// then globally adaptive (QUADPACK's QAG): the segment with the largest Gauss–Kronrod error
/// is bisected until the errors sum below `relative` × |value|, so effort goes where the
/// total needs it, not to tails that are tiny against it.
inline Estimate gradedIntegral(const std::function<double(double)>& f, double a, double b, double c,
                               double relative) {
  std::vector<double> cuts{a, b, c};
  const double span = std::max(c - a, b - c);
  for (int k = 1; k <= 20; ++k) {
    const double w = span * std::ldexp(1.0, -k);
    cuts.push_back(c - w);
    cuts.push_back(c + w);
  }
  std::erase_if(cuts, [&](double x) { return !(x >= a && x <= b); });
  std::sort(cuts.begin(), cuts.end());
  cuts.erase(std::unique(cuts.begin(), cuts.end()), cuts.end());
  struct Segment {
    double a, b, value, error;
    bool operator<(const Segment& o) const { return error < o.error; }
  };
  auto rule = [&](double lo, double hi) {
    double error = 0.0;
    const double v =
        boost::math::quadrature::gauss_kronrod<double, 21>::integrate(f, lo, hi, 0, 0.0, &error);
    // Boost reports the error of the rule on [−1, 1], before the change of variable.
    return Segment{lo, hi, v, error * 0.5 * (hi - lo)};
  };
  std::vector<Segment> heap;
  for (std::size_t k = 0; k + 1 < cuts.size(); ++k) heap.push_back(rule(cuts[k], cuts[k + 1]));
  std::make_heap(heap.begin(), heap.end());
  auto totals = [&] {
    Estimate e;
    for (const Segment& s : heap) e.value += s.value, e.error += s.error;
    return e;
  };
  Estimate sum = totals();
  for (int split = 0; split < 4000 && sum.error > relative * std::abs(sum.value); ++split) {
    std::pop_heap(heap.begin(), heap.end());
    const Segment worst = heap.back();
    heap.pop_back();
    const double mid = 0.5 * (worst.a + worst.b);
    if (!(mid > worst.a && mid < worst.b)) {  // cannot be split further: keep it as it is
      heap.push_back(worst);
      std::push_heap(heap.begin(), heap.end());
      break;
    }
    for (const Segment& half : {rule(worst.a, mid), rule(mid, worst.b)}) {
      heap.push_back(half);
      std::push_heap(heap.begin(), heap.end());
    }
    sum = totals();
  }
  return sum;
}

/// The irradiance (W/m²) at `observer_m` from the surface `p` under `beam`, with the
/// quadrature's own error estimate. Occlusion is not modelled: use convex shapes and
/// observers outside them.
inline Estimate irradiance(const Parametrisation& p, const Beam& beam, const Material& m,
                           const Vec3& observer_m) {
  auto value = [&](double u, double v, double* tan2) {
    return integrand(beam, m, p.at(u, v), observer_m, tan2);
  };
  auto spike_v = [&](double u) {  // where along the line u the lobe peaks
    const auto [v0, v1] = p.v_range(u);
    return argMin(
        [&](double v) {
          double t2 = 0.0;
          value(u, v, &t2);
          return t2;
        },
        v0, v1);
  };
  auto least_tan2 = [&](double u) {
    double t2 = 0.0;
    value(u, spike_v(u), &t2);
    return t2;
  };
  double inner_error = 0.0;  // the largest relative error of any line (the integrand is ≥ 0)
  auto inner = [&](double u) {
    auto [v0, v1] = p.v_range(u);
    if (!(v1 > v0)) return 0.0;
    const double c = spike_v(u);
    if (p.v_periodic) v0 = c - kPi, v1 = c + kPi;  // the seam opposite the spike
    const Estimate e =
        gradedIntegral([&](double v) { return value(u, v, nullptr); }, v0, v1, c, 1e-9);
    if (e.value > 0.0) inner_error = std::max(inner_error, e.error / e.value);
    return e.value;
  };
  const double c = argMin(least_tan2, p.u0, p.u1, 256);
  // The lines are integrated a hundred times more finely than the outer integral asks, so
  // their noise does not pass for structure there.
  Estimate e = gradedIntegral(inner, p.u0, p.u1, c, 1e-7);
  // Each line is within inner_error of its value, so their integral is within that of its own.
  e.error += inner_error * e.value;
  return e;
}

/// The shapes of tessellate.h in their own coordinates. `pole` picks the sphere's polar axis
/// (keep it away from the glint: the parametrisation is singular there).
inline Parametrisation cone(const ConeShape& s);
inline Parametrisation cylinder(const CylinderShape& s) {
  // A cone of slope 0: the same points, normals and area element, to the bit.
  return cone({s.centre_m, s.axis, s.radius_m, s.radius_m, s.length_m});
}

inline Parametrisation sphere(const SphereShape& s, const Vec3& pole) {
  const Vec3 a = glm::normalize(pole);
  const Vec3 e1 = anyPerpendicular(a), e2 = glm::cross(a, e1);
  Parametrisation p;
  p.u0 = 0.0;
  p.u1 = kPi;
  p.v_range = [](double) { return std::pair{0.0, 2.0 * kPi}; };
  p.v_periodic = true;
  p.at = [=](double theta, double phi) {
    const Vec3 n =
        std::sin(theta) * (std::cos(phi) * e1 + std::sin(phi) * e2) + std::cos(theta) * a;
    return SurfacePoint{s.centre_m + s.radius_m * n, n, s.radius_m * s.radius_m * std::sin(theta)};
  };
  return p;
}

inline Parametrisation cone(const ConeShape& s) {
  const Vec3 a = glm::normalize(s.axis);
  const Vec3 e1 = anyPerpendicular(a), e2 = glm::cross(a, e1);
  const double slope = (s.top_radius_m - s.radius_m) / s.length_m;  // dr/dt
  const double stretch = std::sqrt(1.0 + slope * slope);
  Parametrisation p;
  p.u0 = -0.5 * s.length_m;
  p.u1 = 0.5 * s.length_m;
  p.v_range = [](double) { return std::pair{0.0, 2.0 * kPi}; };
  p.v_periodic = true;
  p.at = [=](double t, double phi) {
    const Vec3 radial = std::cos(phi) * e1 + std::sin(phi) * e2;
    const double r = s.radius_m + slope * (t + 0.5 * s.length_m);
    // ∂x/∂t = a + slope·radial, ∂x/∂φ = r·tangent: the outward normal leans against the slope.
    return SurfacePoint{s.centre_m + t * a + r * radial, (radial - slope * a) / stretch,
                        r * stretch};
  };
  return p;
}

/// A torus about the z axis through the origin: ring radius `major_m`, tube radius `minor_m`,
/// u the angle around the axis, v around the tube (periodic), v = 0 on the outer equator.
inline Parametrisation torus(double major_m, double minor_m) {
  Parametrisation p;
  p.u0 = 0.0;
  p.u1 = 2.0 * kPi;
  p.v_range = [](double) { return std::pair{0.0, 2.0 * kPi}; };
  p.v_periodic = true;
  p.at = [=](double phi, double theta) {
    const Vec3 radial(std::cos(phi), std::sin(phi), 0.0);
    const Vec3 n = std::cos(theta) * radial + Vec3(0.0, 0.0, std::sin(theta));
    return SurfacePoint{major_m * radial + minor_m * n, n,
                        minor_m * (major_m + minor_m * std::cos(theta))};
  };
  return p;
}

inline Parametrisation disk(const DiskShape& s) {
  const Vec3 n = glm::normalize(s.normal);
  const Vec3 e1 = anyPerpendicular(n), e2 = glm::cross(n, e1);
  Parametrisation p;
  p.u0 = -s.radius_m;
  p.u1 = s.radius_m;
  p.v_range = [r = s.radius_m](double x) {
    const double h = std::sqrt(std::max(0.0, r * r - x * x));
    return std::pair{-h, h};
  };
  p.at = [=](double x, double y) { return SurfacePoint{s.centre_m + x * e1 + y * e2, n, 1.0}; };
  return p;
}

}  // namespace glint::test::brute
