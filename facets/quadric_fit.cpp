#include "facets/quadric_fit.h"

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>

namespace glint {

const char* toString(QuadricFitStatus status) {
  switch (status) {
    case QuadricFitStatus::Ok:
      return "ok";
    case QuadricFitStatus::Singular:
      return "singular";
    case QuadricFitStatus::IllConditioned:
      return "ill-conditioned";
    case QuadricFitStatus::Inconsistent:
      return "inconsistent normals";
    case QuadricFitStatus::Unstable:
      return "unstable subdivision";
    case QuadricFitStatus::Unbounded:
      return "normals unbounded over the facet";
  }
  return "unknown";
}

namespace {

// Orients @p quadric by the vertex normals @p n at @p p and checks it is a surface for the
// facet: Ok, or why not.
QuadricFitStatus orientAndCheck(Quadric& quadric, const std::array<Vec3, 3>& p,
                                const std::array<Vec3, 3>& n, const QuadricFitOptions& options) {
  // Orient by the vertex normals; a gradient that vanishes or disagrees in sign is no surface
  // for this facet.
  int agree = 0;
  for (int i = 0; i < 3; ++i) {
    const Vec3 g = quadric.gradient(p[i]);
    const double gn = glm::dot(g, n[i]);
    if (!(std::abs(gn) > 1e-9 * glm::length(g)) || glm::length(g) == 0.0) {
      return QuadricFitStatus::Inconsistent;
    }
    agree += gn > 0.0 ? 1 : -1;
  }
  if (std::abs(agree) != 3) {
    return QuadricFitStatus::Inconsistent;
  }
  if (agree < 0) quadric = quadric.flipped();

  // The surface must also carry subdivision: edge midpoints project nearby.
  for (int i = 0; i < 3; ++i) {
    const Vec3 mid = 0.5 * (p[i] + p[(i + 1) % 3]);
    const auto on = quadric.project(mid);
    const double edge = glm::length(p[(i + 1) % 3] - p[i]);
    if (!on || glm::length(*on - mid) > options.max_midpoint_shift * edge) {
      return QuadricFitStatus::Unstable;
    }
  }
  // The bounds that let observers skip a facet (patch_models.h) need its gradient clear of
  // zero over its ball, 2 L r < |∇Q| at the centroid (L the gradient's Lipschitz constant, r the
  // ball's radius): a fit that fails it leaves its pieces' normal cones open until they are
  // small, and on a car body with computed normals (944 of 1 125 fits) every observer ran to the
  // depth limit without an evaluation and read 0 W/m². PN bounds such a facet.
  const Vec3 centroid = (p[0] + p[1] + p[2]) / 3.0;
  double r0 = 0.0;
  for (const Vec3& v : p) r0 = std::max(r0, glm::length(v - centroid));
  if (!(2.0 * quadric.gradientLipschitz() * r0 < glm::length(quadric.gradient(centroid)))) {
    return QuadricFitStatus::Unbounded;
  }
  return QuadricFitStatus::Ok;
}

}  // namespace

QuadricFit fitQuadric(const std::array<Vec3, 3>& p, const std::array<Vec3, 3>& n,
                      const QuadricFitOptions& options) {
  QuadricFit fit;
  // Local frame: origin at the centroid, unit size, z along the chord plane's normal.
  const Vec3 origin = (p[0] + p[1] + p[2]) / 3.0;
  double scale = 0.0;
  for (const Vec3& v : p) scale = std::max(scale, glm::length(v - origin));
  const auto ez = tryNormalize(glm::cross(p[1] - p[0], p[2] - p[0]));
  if (!(scale > 0.0) || !std::isfinite(scale) || !ez) return fit;
  const Vec3 ex = anyPerpendicular(*ez);
  const Vec3 ey = glm::cross(*ez, ex);
  auto toLocal = [&](const Vec3& v) {
    return Vec3(glm::dot(v, ex), glm::dot(v, ey), glm::dot(v, *ez));
  };

  // The nine constraints can never fix all ten coefficients: with P the chord plane, P² vanishes
  // at the vertices with zero gradient, so Q + βP² fits the same data for every β. In this frame
  // P² = z², and dropping the z² coefficient picks the member that is a graph over the facet
  // (a z² term only bends the surface at second order in its height over the chord). Unknowns:
  // (qxx, qyy, qxy, qxz, qyz, qx, qy, qz, q0) of Eq. 3 with qzz = 0.
  Eigen::Matrix<double, 9, 9> m;
  for (int i = 0; i < 3; ++i) {
    const Vec3 x = toLocal(p[i] - origin) / scale;
    m.row(i) << x.x * x.x, x.y * x.y, 2 * x.x * x.y, 2 * x.x * x.z, 2 * x.y * x.z, 2 * x.x, 2 * x.y,
        2 * x.z, 1.0;
    const Vec3 nl = toLocal(n[i]);
    const Vec3 t1 = anyPerpendicular(nl);
    const Vec3 t2 = glm::cross(nl, t1);
    const Vec3 tangents[2] = {t1, t2};
    for (int k = 0; k < 2; ++k) {
      // t · ∇Q / 2 = t · (A x + b), written out per coefficient.
      const Vec3& t = tangents[k];
      m.row(3 + 2 * i + k) << t.x * x.x, t.y * x.y, t.x * x.y + t.y * x.x, t.x * x.z + t.z * x.x,
          t.y * x.z + t.z * x.y, t.x, t.y, t.z, 0.0;
    }
  }
  if (!m.allFinite()) return fit;

  // The data always admit a solution (the system is singular by construction); it is unique
  // when the second-smallest singular value stays clear of zero.
  const Eigen::JacobiSVD<Eigen::Matrix<double, 9, 9>> svd(m, Eigen::ComputeFullV);
  const auto& s = svd.singularValues();
  fit.rank_gap = s(0) > 0.0 ? s(7) / s(0) : 0.0;
  if (fit.rank_gap < options.singular_below) {
    fit.status = QuadricFitStatus::Singular;
    return fit;
  }
  if (fit.rank_gap < options.ill_conditioned_below) {
    fit.status = QuadricFitStatus::IllConditioned;
    return fit;
  }

  // The null vector, mapped back to world coordinates: x_local = R (x − o) / s, so
  // s² Q_local = (x − o)ᵀ Rᵀ A R (x − o) + 2 s (R b)·(x − o) + s² c.
  const Eigen::Matrix<double, 9, 1> q = svd.matrixV().col(8);
  const glm::dmat3 a_local(q(0), q(2), q(3), q(2), q(1), q(4), q(3), q(4), 0.0);
  const Vec3 b_local(q(5), q(6), q(7));
  const glm::dmat3 rot_t(ex, ey, *ez);  // columns: local axes in world coordinates
  const glm::dmat3 a = rot_t * a_local * glm::transpose(rot_t);
  const Vec3 b_rot = scale * (rot_t * b_local);
  const Vec3 b = -(a * origin) + b_rot;
  const double c =
      glm::dot(origin, a * origin) - 2.0 * glm::dot(b_rot, origin) + scale * scale * q(8);
  Quadric quadric(a, b, c);

  fit.status = orientAndCheck(quadric, p, n, options);
  if (fit.status != QuadricFitStatus::Ok) return fit;
  fit.quadric = quadric;
  return fit;
}

}  // namespace glint
