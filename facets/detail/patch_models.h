#pragma once
// The three surface models behind patch.h, as small value types, so that hot loops dispatch on
// the model once (withPatchModel) and then run monomorphic code.

#include <algorithm>
#include <cmath>

#include "facets/patch.h"

namespace glint::detail {

// Centre, area, chord normal and the corners' extent: the part every model shares.
struct Chord {
  Vec3 centre_m;
  Vec3 normal;  // zero for a degenerate triangle
  double area_m2;
  double max_corner_distance_m;
};

inline Chord chordOf(const SubFacet& f) {
  Chord c;
  c.centre_m = (f.corner_m[0] + f.corner_m[1] + f.corner_m[2]) / 3.0;
  const Vec3 cross = glm::cross(f.corner_m[1] - f.corner_m[0], f.corner_m[2] - f.corner_m[0]);
  const double len = glm::length(cross);
  c.area_m2 = 0.5 * len;
  c.normal = len > 0.0 ? cross / len : Vec3(0.0);
  double r2 = 0.0;
  for (const Vec3& p : f.corner_m) {
    const Vec3 d = p - c.centre_m;
    r2 = std::max(r2, glm::dot(d, d));
  }
  c.max_corner_distance_m = std::sqrt(r2);
  return c;
}

// The 1→4 split, given where an edge midpoint lands: mid(f, edge, bary_midpoint).
template <class Midpoint>
std::array<SubFacet, 4> splitWith(const SubFacet& f, Midpoint&& mid) {
  std::array<Vec3, 3> m, mb;
  for (int e = 0; e < 3; ++e) {
    mb[e] = 0.5 * (f.bary[e] + f.bary[(e + 1) % 3]);
    m[e] = mid(f, e, mb[e]);
  }
  const auto& p = f.corner_m;
  const auto& b = f.bary;
  const std::uint8_t d = static_cast<std::uint8_t>(f.depth + 1);
  const std::uint8_t r = f.rim_edges;
  // Child edges that lie on a parent edge inherit its rim bit; inner edges have none.
  return {{
      {{p[0], m[0], m[2]}, {b[0], mb[0], mb[2]}, f.coarse, d, static_cast<std::uint8_t>(r & 0b101)},
      {{m[0], p[1], m[1]}, {mb[0], b[1], mb[1]}, f.coarse, d, static_cast<std::uint8_t>(r & 0b011)},
      {{m[2], m[1], p[2]}, {mb[2], mb[1], b[2]}, f.coarse, d, static_cast<std::uint8_t>(r & 0b110)},
      {{m[0], m[1], m[2]}, {mb[0], mb[1], mb[2]}, f.coarse, d, 0},
  }};
}

// The area of the patch that 1→4 subdivision converges to and the centroid of its area measure,
// from samples at the three edge midpoints (a rule exact for quadratics over the triangle).
// The integrand is sampled on the surface at that centroid (projected back onto the surface):
// the one-point rule is then exact for integrands varying linearly along the surface, and its
// O(h²) term is the classical midpoint one, which cancels between neighbours. Sampling at the
// chord centroid, inside the surface, would add a same-signed O(h²) bias instead.
struct Moments {
  double area_m2;
  Vec3 centroid_m;
};

template <class SampleAt>
Moments edgeMidpointMoments(double parameter_area, SampleAt&& sample_at) {
  double sum = 0.0;
  Vec3 first(0.0);
  for (int e = 0; e < 3; ++e) {
    const auto [jacobian, point] = sample_at(e);
    sum += jacobian;
    first += jacobian * point;
  }
  if (!(sum > 0.0)) return {0.0, Vec3(0.0)};
  return {parameter_area * sum / 3.0, first / sum};
}

// The circular segments between a facet's rim edges and the rim's arcs: their area, missing
// from the triangle but part of the facet, and how far the arcs bulge beyond the chords.
struct RimSegments {
  double area_m2 = 0.0;
  double max_bulge_m = 0.0;
};

inline RimSegments rimSegments(const SubFacet& f, const RimCircle& rim) {
  RimSegments s;
  for (int e = 0; e < 3; ++e) {
    if (!(f.rim_edges >> e & 1u)) continue;
    const double chord = glm::length(f.corner_m[(e + 1) % 3] - f.corner_m[e]);
    const double theta = 2.0 * std::asin(std::min(1.0, 0.5 * chord / rim.radius_m));
    s.area_m2 += 0.5 * rim.radius_m * rim.radius_m * (theta - std::sin(theta));
    s.max_bulge_m = std::max(s.max_bulge_m, rim.radius_m * (1.0 - std::cos(0.5 * theta)));
  }
  return s;
}

// Area bound from the largest tilt between the patch's normals and its chord: a surface that is
// a graph over the chord plane with tilt ≤ β has at most area/cos β.
inline double areaBound(const Chord& c, double tilt_rad, double radius_m) {
  if (tilt_rad < 1.2) return c.area_m2 / std::cos(tilt_rad);
  return 4.0 * kPi * radius_m * radius_m;
}

// The narrowest band (patch.h) that one of the quadric's principal axes e gives the normals
// ∇Q/|∇Q| of every point in the ball (centre_m, radius_m). ∇Q·e = 2((Aᵀe)·x + b·e) is affine in
// x, so over the ball it stays within 2|Aᵀe| r of its value at the centre, and |∇Q| within L r
// of its own; the quotient's interval follows. No band where |∇Q| may vanish in the ball.
inline NormalBand quadricNormalBand(const Quadric& q, const Vec3& centre_m, double radius_m) {
  const Vec3 grad = q.gradient(centre_m);
  const double grad_len = glm::length(grad);
  const double slack = q.gradientLipschitz() * radius_m;
  const double len_lo = grad_len - slack, len_hi = grad_len + slack;
  if (!(len_lo > 0.0) || !std::isfinite(len_hi)) return {};
  NormalBand best;
  double best_width = kPi;
  for (const Vec3& e : q.principalAxes()) {
    // A margin of 1e-12 |∇Q| covers the rounding of the dot products (a cylinder's band along
    // its axis is otherwise exactly 0 wide).
    const double along = glm::dot(grad, e);
    const double swing = 2.0 * glm::length(glm::transpose(q.a()) * e) * radius_m + 1e-12 * len_hi;
    const double p_lo = along - swing, p_hi = along + swing;
    const double sin_lo = std::max(-1.0, p_lo / (p_lo >= 0.0 ? len_hi : len_lo));
    const double sin_hi = std::min(1.0, p_hi / (p_hi >= 0.0 ? len_lo : len_hi));
    const double width = std::asin(sin_hi) - std::asin(sin_lo);
    if (width < best_width) {
      best_width = width;
      best = {e, sin_lo, sin_hi};
    }
  }
  return best;
}

struct FlatPatches {
  [[nodiscard]] std::array<SubFacet, 4> split(const SubFacet& f) const {
    return splitWith(f, [](const SubFacet& s, int e, const Vec3&) {
      return 0.5 * (s.corner_m[e] + s.corner_m[(e + 1) % 3]);
    });
  }
  template <bool kBounds>
  [[nodiscard]] PatchGeometry geometry(const SubFacet& f, NormalModel) const {
    const Chord c = chordOf(f);
    PatchGeometry g{c.centre_m, c.normal, c.area_m2};
    g.corner_m = f.corner_m;
    g.corner_normal = {c.normal, c.normal, c.normal};
    if constexpr (kBounds) {
      g.radius_m = c.max_corner_distance_m;
      g.area_bound_m2 = c.area_m2;
    }
    return g;
  }
};

struct QuadricPatches {
  const Quadric* quadric;
  const RimCircle* rim;  // may be null

  [[nodiscard]] std::array<SubFacet, 4> split(const SubFacet& f) const {
    return splitWith(f, [this](const SubFacet& s, int e, const Vec3&) {
      const Vec3 m = 0.5 * (s.corner_m[e] + s.corner_m[(e + 1) % 3]);
      if (rim != nullptr && (s.rim_edges >> e & 1u)) return rim->project(m);
      const auto on = quadric->project(m);
      return on ? *on : m;
    });
  }

  template <bool kBounds>
  [[nodiscard]] PatchGeometry geometry(const SubFacet& f, NormalModel normals) const {
    const Chord c = chordOf(f);
    const Vec3 grad = quadric->gradient(c.centre_m);
    const double grad_len = glm::length(grad);
    const Vec3 surface_normal = grad_len > 0.0 ? grad / grad_len : c.normal;
    PatchGeometry g{c.centre_m, c.normal, c.area_m2};
    if (normals == NormalModel::Surface && c.area_m2 > 0.0) {
      // Normal projection onto a surface at height h over the chord has the area element
      // J = 1 − |∇h|²/2 − h Δh to second order, with Δh = −div(∇Q/|∇Q|).
      const glm::dmat3& a = quadric->a();
      const double trace = a[0][0] + a[1][1] + a[2][2];
      const Moments mo = edgeMidpointMoments(c.area_m2, [&](int e) {
        const Vec3 mid = 0.5 * (f.corner_m[e] + f.corner_m[(e + 1) % 3]);
        const Vec3 grad_mid = quadric->gradient(mid);
        const double len = glm::length(grad_mid);
        if (!(len > 0.0)) return std::pair{1.0, mid};
        const Vec3 unit = grad_mid / len;
        const double cos_tilt = std::abs(glm::dot(unit, c.normal));
        const double tan2 = cos_tilt > 0.0 ? 1.0 / (cos_tilt * cos_tilt) - 1.0 : 0.0;
        const double height = quadric->nearestRoot(mid, unit).value_or(0.0);
        const double div = 2.0 * (trace - glm::dot(unit, a * unit)) / len;
        return std::pair{std::max(1.0 - 0.5 * tan2 + height * div, 0.0), mid + height * unit};
      });
      if (mo.area_m2 > 0.0) {
        g.area_m2 = mo.area_m2;
        const Vec3 grad_c = quadric->gradient(mo.centroid_m);
        const double grad_c_len = glm::length(grad_c);
        const auto t = grad_c_len > 0.0 ? quadric->nearestRoot(mo.centroid_m, grad_c / grad_c_len)
                                        : std::nullopt;
        g.centre_m = t ? mo.centroid_m + *t * (grad_c / grad_c_len) : mo.centroid_m;
      }
      const Vec3 grad_at = quadric->gradient(g.centre_m);
      const double grad_at_len = glm::length(grad_at);
      g.normal = grad_at_len > 0.0 ? grad_at / grad_at_len : surface_normal;
      if (rim != nullptr && f.rim_edges != 0) g.area_m2 += rimSegments(f, *rim).area_m2;
    }
    g.corner_m = f.corner_m;
    for (int k = 0; k < 3; ++k) {
      const Vec3 grad_k = quadric->gradient(f.corner_m[k]);
      const double len = glm::length(grad_k);
      g.corner_normal[k] = normals == NormalModel::Surface && len > 0.0 ? grad_k / len : g.normal;
    }
    if constexpr (kBounds) {
      // ∇Q is L-Lipschitz, so over a ball of radius r the gradient stays within L·r of ∇Q(c):
      // an exact normal cone. The patch's height over its chord is at most κ r²/2 with the
      // normal curvature κ ≤ L / |∇Q|, which needs |∇Q| bounded away from 0 on the patch.
      const double lip = quadric->gradientLipschitz();
      const double r0 = c.max_corner_distance_m;
      double cone = kPi;
      double radius = 2.0 * r0;
      if (lip == 0.0) {
        cone = 0.0;
        radius = r0;
      } else if (const double grad_low = grad_len - 2.0 * lip * r0; grad_low > 0.0) {
        const double sag = lip * r0 * r0 / (2.0 * grad_low);
        if (sag <= r0) {
          radius = r0 + sag;
          if (lip * radius < grad_len) cone = std::asin(lip * radius / grad_len);
          // The same ball holds the patch: every normal it shows is also in this band, which
          // is about a fixed axis and needs no widening for the sample's normal.
          if (normals == NormalModel::Surface) {
            g.band = quadricNormalBand(*quadric, c.centre_m, radius);
          }
        }
      }
      const double chord_tilt = c.area_m2 > 0.0 ? angleBetween(c.normal, surface_normal) : 0.0;
      // The cone is about the normal at the chord centroid; the sample's own normal is inside
      // it, so widening by their angle keeps every patch normal within the cone of g.normal.
      cone = std::min(kPi, cone + angleBetween(surface_normal, g.normal));
      if (normals == NormalModel::Flat) cone = std::min(kPi, cone + chord_tilt);
      // The ball was centred on the chord centroid; re-centring on the sample widens it, and so
      // do rim arcs bulging past their chords (whose segments add to the area).
      const RimSegments segments = rim != nullptr ? rimSegments(f, *rim) : RimSegments{};
      g.radius_m = radius + segments.max_bulge_m + glm::length(g.centre_m - c.centre_m);
      g.cone_rad = cone;
      g.area_bound_m2 = areaBound(c, cone + chord_tilt, g.radius_m) + segments.area_m2;
    }
    return g;
  }
};

struct PNPatches {
  const PNTriangle* pn;

  [[nodiscard]] std::array<SubFacet, 4> split(const SubFacet& f) const {
    return splitWith(f,
                     [this](const SubFacet&, int, const Vec3& bary) { return pn->position(bary); });
  }

  template <bool kBounds>
  [[nodiscard]] PatchGeometry geometry(const SubFacet& f, NormalModel normals) const {
    const Chord c = chordOf(f);
    const Vec3 centre_bary = (f.bary[0] + f.bary[1] + f.bary[2]) / 3.0;
    const auto field = pn->normal(centre_bary);
    const Vec3 surface_normal = field ? *field : c.normal;
    PatchGeometry g{c.centre_m, c.normal, c.area_m2};
    if (normals == NormalModel::Surface) {
      // A PN patch is parametric: its area element is |p_s × p_t| over the sub-triangle's
      // parameter domain (area ½). (The PN normal field is not this geometric normal.)
      const Vec3 ds = f.bary[1] - f.bary[0], dt = f.bary[2] - f.bary[0];
      // The moments are taken in parameter space, where the centroid maps straight onto the patch.
      const Moments mo = edgeMidpointMoments(0.5, [&](int e) {
        const Vec3 mid = 0.5 * (f.bary[e] + f.bary[(e + 1) % 3]);
        return std::pair{glm::length(glm::cross(pn->derivative(mid, ds), pn->derivative(mid, dt))),
                         mid};
      });
      if (mo.area_m2 > 0.0) {
        g.area_m2 = mo.area_m2;
        g.centre_m = pn->position(mo.centroid_m);
        if (const auto n = pn->normal(mo.centroid_m)) g.normal = *n;
      } else {
        g.normal = surface_normal;
      }
    }
    g.corner_m = f.corner_m;
    for (int k = 0; k < 3; ++k) {
      const auto n = pn->normal(f.bary[k]);
      g.corner_normal[k] = normals == NormalModel::Surface && n ? *n : g.normal;
    }
    if constexpr (kBounds) {
      const double radius = c.max_corner_distance_m + pn->sagBound(f.depth);
      // The blossom cone is about the normal at the parameter centroid; g.normal was taken at
      // the area centroid, so widen by their angle as for quadrics.
      double cone = std::min(kPi, pn->normalConeHalfAngle(f.bary, surface_normal) +
                                      angleBetween(surface_normal, g.normal));
      const double chord_tilt = c.area_m2 > 0.0 ? angleBetween(c.normal, surface_normal) : 0.0;
      if (normals == NormalModel::Flat) cone = std::min(kPi, cone + chord_tilt);
      g.radius_m = radius + glm::length(g.centre_m - c.centre_m);
      g.cone_rad = cone;
      g.area_bound_m2 = areaBound(c, cone + chord_tilt, g.radius_m);
    }
    return g;
  }
};

// Calls fn with the surface model of coarse facet `facet`: the one switch per dispatch.
template <class Fn>
decltype(auto) withPatchModel(const Target& target, std::uint32_t facet, Fn&& fn) {
  const std::uint32_t index = target.model_index[facet];
  switch (target.model[facet]) {
    case SurfaceModel::Quadric: {
      const TargetObject& obj = target.objects[target.object[facet]];
      return fn(QuadricPatches{&target.quadrics[index], obj.rim ? &*obj.rim : nullptr});
    }
    case SurfaceModel::PN:
      return fn(PNPatches{&target.pn_triangles[index]});
    case SurfaceModel::Flat:
      break;
  }
  return fn(FlatPatches{});
}

}  // namespace glint::detail
