#include "facets/surface_map.h"

#include <cmath>

namespace glint {

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
        const Vec3 a = corner_m_[e] - rim.center_m, b = corner_m_[(e + 1) % 3] - rim.center_m;
        const auto e1 = tryNormalize(a - glm::dot(a, rim.normal) * rim.normal);
        if (!e1) continue;
        // e2 turns from a toward b in the rim's plane: the arc is the short one between them.
        Vec3 e2 = glm::cross(rim.normal, *e1);
        if (glm::dot(e2, b) < 0.0) e2 = -e2;
        RimArc& arc = rim_[e];
        arc.present = true;
        arc.center_m = rim.center_m;
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
    const Vec3 d = arc.center_m + arc.radius_m * radial - (a + t * (b - a));
    const Vec3 d_t = arc.radius_m * arc.angle_rad *
                         (-std::sin(phi) * arc.e1 + std::cos(phi) * arc.e2) -
                     (b - a);
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
      out.jacobian_m2 = glm::length(
          glm::cross(corner_m_[1] - corner_m_[0], corner_m_[2] - corner_m_[0]));
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

std::array<SubFacet, 4> SurfaceMap::split(const SubFacet& f) const {
  std::array<SubFacet, 4> out;
  const std::array<Child, 4> c = children(f);
  for (int k = 0; k < 4; ++k) out[k] = subFacet(c[k].bary, c[k].depth, c[k].rim_edges);
  return out;
}

}  // namespace glint
