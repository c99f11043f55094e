#include "facets/surface_map.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace glint {
namespace {

// D(t) = arc(t) − chord(t), t ∈ [0, 1], of an arc of radius R and angle Δ = 2h ≤ π, and its
// t-derivatives, in the frame of the arc's middle (w radial, τ tangent). With z = 2t − 1:
//   D   = R (cos zh − cos h) w + R (sin zh − z sin h) τ
//   D'  = −2Rh sin(zh) w + 2R (h cos zh − sin h) τ
//   D'' = −4Rh² (cos zh w + sin zh τ)
// The radial part is the sagitta, the tangential part a third-order term; bounding them apart
// keeps the small one small.
struct ArcDeviation {
  double d_w, d_tau, d1_w, d1_tau, d2_w, d2_tau;  // |·| bounds over the interval, metres
};

ArcDeviation arcDeviation(double radius_m, double angle_rad, double t0, double t1) {
  const double h = 0.5 * angle_rad;
  const double z0 = 2.0 * t0 - 1.0, z1 = 2.0 * t1 - 1.0;
  // |z| over [z0, z1]: every term is monotone in |z| for |zh| ≤ h ≤ π/2.
  const double lo = z0 <= 0.0 && z1 >= 0.0 ? 0.0 : std::min(std::abs(z0), std::abs(z1));
  const double hi = std::max(std::abs(z0), std::abs(z1));
  // sin zh − z sin h is odd, vanishes at z = 0 and ±1 and has |second derivative| ≤ h² sin h,
  // so on [0, 1] it is at most ½ |z| (1 − |z|) h² sin h.
  const double q = lo <= 0.5 && hi >= 0.5 ? 0.25 : std::max(lo * (1.0 - lo), hi * (1.0 - hi));
  ArcDeviation d;
  d.d_w = radius_m * (std::cos(lo * h) - std::cos(h));
  d.d_tau = radius_m * 0.5 * q * h * h * std::sin(h);
  d.d1_w = 2.0 * radius_m * h * std::sin(hi * h);
  d.d1_tau = 2.0 * radius_m *
             std::max(std::abs(h * std::cos(lo * h) - std::sin(h)),
                      std::abs(h * std::cos(hi * h) - std::sin(h)));
  d.d2_w = 4.0 * radius_m * h * h * std::cos(lo * h);
  d.d2_tau = 4.0 * radius_m * h * h * std::sin(hi * h);
  return d;
}

}  // namespace

SurfaceMap::SurfaceMap(const Target& target, std::uint32_t facet)
    : model_(target.model[facet]), facet_(facet), corner_m_(target.corners_m[facet]) {
  const Vec3 cross = glm::cross(corner_m_[1] - corner_m_[0], corner_m_[2] - corner_m_[0]);
  if (const auto n = tryNormalize(cross)) chord_normal_ = *n;
  if (model_ == SurfaceModel::Quadric) {
    quadric_ = &target.quadrics[target.model_index[facet]];
    const TargetObject& obj = target.objects[target.object[facet]];
    if (obj.rim && target.rim_edges[facet] != 0) {
      const RimCircle& rim = *obj.rim;
      for (int e = 0; e < 3; ++e) {
        if (!(target.rim_edges[facet] >> e & 1u)) continue;
        const Vec3 a = corner_m_[e] - rim.centre_m, b = corner_m_[(e + 1) % 3] - rim.centre_m;
        const auto e1 = tryNormalize(a - glm::dot(a, rim.normal) * rim.normal);
        if (!e1) continue;
        // e2 turns from a toward b in the rim's plane: the arc is the short one between them.
        Vec3 e2 = glm::cross(rim.normal, *e1);
        if (glm::dot(e2, b) < 0.0) e2 = -e2;
        RimArc& arc = rim_[e];
        arc.present = true;
        arc.centre_m = rim.centre_m;
        arc.e1 = *e1;
        arc.e2 = e2;
        arc.radius_m = rim.radius_m;
        arc.angle_rad = std::atan2(glm::dot(b, e2), glm::dot(b, *e1));
        any_rim_ = true;
      }
    }
  } else if (model_ == SurfaceModel::PN) {
    pn_ = &target.pn_triangles[target.model_index[facet]];
  }
}

void SurfaceMap::blended(const Vec3& bary, Vec3& p, Vec3& p_u, Vec3& p_v) const {
  // b = (1 − u − v, u, v): ∂b/∂u = (−1, 1, 0), ∂b/∂v = (−1, 0, 1).
  p = bary[0] * corner_m_[0] + bary[1] * corner_m_[1] + bary[2] * corner_m_[2];
  p_u = corner_m_[1] - corner_m_[0];
  p_v = corner_m_[2] - corner_m_[0];
  if (!any_rim_) return;
  static constexpr double kDbDu[3] = {-1.0, 1.0, 0.0}, kDbDv[3] = {-1.0, 0.0, 1.0};
  for (int e = 0; e < 3; ++e) {
    const RimArc& arc = rim_[e];
    if (!arc.present) continue;
    const int f = (e + 1) % 3;
    const double s = bary[e] + bary[f];
    if (!(s > 0.0)) continue;  // the opposite corner: the blend and its derivative vanish
    const double t = bary[f] / s;
    const Vec3& a = corner_m_[e];
    const Vec3& b = corner_m_[f];
    const double phi = t * arc.angle_rad;
    const Vec3 radial = std::cos(phi) * arc.e1 + std::sin(phi) * arc.e2;
    const Vec3 d = arc.centre_m + arc.radius_m * radial - (a + t * (b - a));
    const Vec3 d_t =
        arc.radius_m * arc.angle_rad * (-std::sin(phi) * arc.e1 + std::cos(phi) * arc.e2) - (b - a);
    p += s * s * d;
    // ∂(s² D(t)) = 2 s D ∂s + s² D'(t) ∂t, with s ∂t = ∂b_f − t ∂s.
    const double s_u = kDbDu[e] + kDbDu[f], s_v = kDbDv[e] + kDbDv[f];
    p_u += 2.0 * s * s_u * d + s * (kDbDu[f] - t * s_u) * d_t;
    p_v += 2.0 * s * s_v * d + s * (kDbDv[f] - t * s_v) * d_t;
  }
}

SurfacePoint SurfaceMap::at(const Vec3& bary) const {
  SurfacePoint out;
  switch (model_) {
    case SurfaceModel::Flat: {
      out.position_m = bary[0] * corner_m_[0] + bary[1] * corner_m_[1] + bary[2] * corner_m_[2];
      out.normal = chord_normal_;
      out.jacobian_m2 =
          glm::length(glm::cross(corner_m_[1] - corner_m_[0], corner_m_[2] - corner_m_[0]));
      out.valid = out.jacobian_m2 > 0.0;
      return out;
    }
    case SurfaceModel::PN: {
      out.position_m = pn_->position(bary);
      const auto n = pn_->normal(bary);
      const Vec3 t_u = pn_->derivative(bary, Vec3(-1.0, 1.0, 0.0));
      const Vec3 t_v = pn_->derivative(bary, Vec3(-1.0, 0.0, 1.0));
      out.jacobian_m2 = glm::length(glm::cross(t_u, t_v));
      out.valid = n.has_value() && std::isfinite(out.jacobian_m2);
      if (n) out.normal = *n;
      return out;
    }
    case SurfaceModel::Quadric: {
      // S = P + t m(P), m = ∇Q(P)/|∇Q(P)|: the projection 1→4 subdivision uses, and a map of
      // the point P alone, so two facets sharing a chord edge map it onto the same curve.
      // Its tangents: S_X = X + t dm[X] + dt[X] m, with dm[X] = (I − m mᵀ) 2A X / |∇Q(P)| and
      // dt[X] from ∇Q(S)·S_X = 0.
      Vec3 p, p_u, p_v;
      blended(bary, p, p_u, p_v);
      const Vec3 g = quadric_->gradient(p);
      const double g_len = glm::length(g);
      if (!(g_len > 0.0) || !std::isfinite(g_len)) return out;
      const Vec3 m = g / g_len;
      const auto t = quadric_->nearestRoot(p, m);
      if (!t) return out;
      out.position_m = p + *t * m;
      const Vec3 grad = quadric_->gradient(out.position_m);
      const double along = glm::dot(grad, m);
      const auto n = tryNormalize(grad);
      // A projection line tangent to the surface (or nearly): the map's derivative is unbounded.
      if (!n || !(along > 1e-3 * glm::length(grad))) return out;
      out.normal = *n;
      auto tangent = [&](const Vec3& x) {
        const Vec3 ax = 2.0 * (quadric_->a() * x);
        const Vec3 w = x + (*t / g_len) * (ax - glm::dot(m, ax) * m);
        return w - (glm::dot(grad, w) / along) * m;
      };
      out.jacobian_m2 = glm::length(glm::cross(tangent(p_u), tangent(p_v)));
      out.valid = std::isfinite(out.jacobian_m2);
      return out;
    }
  }
  return out;
}

SubFacet SurfaceMap::subFacet(const std::array<Vec3, 3>& bary, std::uint8_t depth,
                              std::uint8_t rim_edges) const {
  return subFacet(bary, depth, rim_edges, {at(bary[0]), at(bary[1]), at(bary[2])});
}

SubFacet SurfaceMap::subFacet(const std::array<Vec3, 3>& bary, std::uint8_t depth,
                              std::uint8_t rim_edges,
                              const std::array<SurfacePoint, 3>& corners) const {
  SubFacet f;
  f.bary = bary;
  f.coarse = facet_;
  f.depth = depth;
  f.rim_edges = rim_edges;
  for (int k = 0; k < 3; ++k) {
    // An invalid corner keeps its chord position: the piece's bounds then describe the chord,
    // and the integrand there (invalid samples) is refined as unresolved.
    f.corner_m[k] = corners[k].valid ? corners[k].position_m
                                     : bary[k][0] * corner_m_[0] + bary[k][1] * corner_m_[1] +
                                           bary[k][2] * corner_m_[2];
  }
  return f;
}

std::array<SurfaceMap::Child, 4> SurfaceMap::children(const SubFacet& f) {
  std::array<Vec3, 3> m;
  for (int e = 0; e < 3; ++e) m[e] = 0.5 * (f.bary[e] + f.bary[(e + 1) % 3]);
  const auto& b = f.bary;
  const auto d = static_cast<std::uint8_t>(f.depth + 1);
  const std::uint8_t r = f.rim_edges;
  // The same children, in the same order and with the same rim bits, as detail::splitWith.
  return {Child{{b[0], m[0], m[2]}, d, static_cast<std::uint8_t>(r & 0b101)},
          Child{{m[0], b[1], m[1]}, d, static_cast<std::uint8_t>(r & 0b011)},
          Child{{m[2], m[1], b[2]}, d, static_cast<std::uint8_t>(r & 0b110)},
          Child{{m[0], m[1], m[2]}, d, 0}};
}

SurfaceMap::Bend SurfaceMap::bend(const std::array<Vec3, 3>& bary,
                                  const std::array<Vec3, 3>& corner_m,
                                  std::uint8_t rim_edges) const {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  Bend out;
  if (!any_rim_) return out;
  // Rims bound disks: the blend stays in their plane, which the projection leaves as it is.
  // On a curved quadric it would move bent points by more than their offset: no bound here.
  if (quadric_ == nullptr || quadric_->gradientLipschitz() != 0.0) return {kInf, kInf};
  for (int k = 0; k < 3; ++k) {
    if (rim_edges >> k & 1u) continue;
    // Along the edge b(λ) = p + λ (q − p), the blend of rim edge e is G(λ) = s² D(t) with
    // s = b_e + b_f linear in λ and s² dt/dλ = c constant, so
    //   G'' = 2 (ds/dλ)² D + 4 (ds/dλ) (c/s) D' + (c/s)² D''.
    const Vec3& p = bary[k];
    const Vec3& q = bary[(k + 1) % 3];
    double curvature_m = 0.0;  // |G''| over λ ∈ [0, 1], summed over the rim edges
    for (int e = 0; e < 3; ++e) {
      const RimArc& arc = rim_[e];
      if (!arc.present) continue;
      const int f = (e + 1) % 3;
      const double s0 = p[e] + p[f], s1 = q[e] + q[f];
      const double ds = s1 - s0;
      const double c = p[e] * (q[f] - p[f]) - p[f] * (q[e] - p[e]);
      // t is monotone along a line, so its range is its ends'; an end at the corner opposite
      // the rim (s = 0) puts the edge on a line of constant t (c = 0) through the other end.
      double t0 = 0.0, t1 = 0.0;
      if (s0 > 0.0 && s1 > 0.0) {
        t0 = p[f] / s0;
        t1 = q[f] / s1;
      } else if (s0 > 0.0 || s1 > 0.0) {
        t0 = t1 = s0 > 0.0 ? p[f] / s0 : q[f] / s1;
      } else {
        continue;  // both ends at the opposite corner: no edge
      }
      const ArcDeviation d =
          arcDeviation(arc.radius_m, arc.angle_rad, std::clamp(std::min(t0, t1), 0.0, 1.0),
                       std::clamp(std::max(t0, t1), 0.0, 1.0));
      double k_w = 2.0 * ds * ds * d.d_w, k_tau = 2.0 * ds * ds * d.d_tau;
      if (c != 0.0) {
        const double s_min = std::min(s0, s1);
        if (!(s_min > 0.0)) return {kInf, kInf};
        const double r = std::abs(c) / s_min;  // |s dt/dλ| at most
        k_w += 4.0 * std::abs(ds) * r * d.d1_w + r * r * d.d2_w;
        k_tau += 4.0 * std::abs(ds) * r * d.d1_tau + r * r * d.d2_tau;
      }
      curvature_m += std::hypot(k_w, k_tau);
    }
    // The bent edge leaves its chord by g(λ), g(0) = g(1) = 0, |g''| ≤ K: |g| ≤ K λ(1 − λ)/2
    // ≤ K/8 and |g'| ≤ K. The area it adds is ∫ g × chord dλ + ½ ∫ g × g' dλ, at most
    // L K/12 + K²/24; the piece, bounded by such edges, lies within K/8 of its chord triangle.
    const double chord_m = glm::length(corner_m[(k + 1) % 3] - corner_m[k]);
    out.offset_m = std::max(out.offset_m, curvature_m / 8.0);
    out.area_m2 += chord_m * curvature_m / 12.0 + curvature_m * curvature_m / 24.0;
  }
  if (!std::isfinite(out.offset_m) || !std::isfinite(out.area_m2)) return {kInf, kInf};
  return out;
}

PatchGeometry SurfaceMap::geometry(const Target& target, const SubFacet& f) const {
  PatchGeometry g = patchGeometry(target, f, NormalModel::Surface);
  if (!any_rim_) return g;
  const Bend b = bend(f.bary, f.corner_m, f.rim_edges);
  g.radius_m += b.offset_m;
  g.area_bound_m2 += b.area_m2;  // on the plane bend() asks for, area is the flat area
  return g;
}

std::array<SubFacet, 4> SurfaceMap::split(const SubFacet& f) const {
  std::array<SubFacet, 4> out;
  const std::array<Child, 4> c = children(f);
  for (int k = 0; k < 4; ++k) out[k] = subFacet(c[k].bary, c[k].depth, c[k].rim_edges);
  return out;
}

}  // namespace glint
