#include "facets/bivariate_normal.h"

#include <algorithm>
#include <boost/math/special_functions/owens_t.hpp>
#include <cmath>
#include <glm/geometric.hpp>

#include "facets/triangle_rule.h"
#include "facets/vec3.h"

namespace glint {
namespace {

namespace bmp = boost::math::policies;
// Double precision throughout (the default would promote to long double for no gain here),
// and no exceptions: this is hot code, and every argument it is given is finite and checked.
using OwensPolicy =
    bmp::policy<bmp::promote_double<false>, bmp::domain_error<bmp::ignore_error>,
                bmp::overflow_error<bmp::ignore_error>, bmp::underflow_error<bmp::ignore_error>,
                bmp::evaluation_error<bmp::ignore_error>, bmp::denorm_error<bmp::ignore_error>,
                bmp::rounding_error<bmp::ignore_error>, bmp::pole_error<bmp::ignore_error>>;

constexpr double kSqrt2 = 1.41421356237309504880;
constexpr double kInvSqrt2Pi = 0.39894228040143267794;

// Beyond this distance from the origin the normal density (e^{-h²/2} < 1e-322) is nothing.
constexpr double kFarTail = 38.5;

// Φ(b) − Φ(a) for a ≤ b, in whichever tail keeps it accurate.
double normalInterval(double a, double b) {
  if (a >= 0.0) return 0.5 * (std::erfc(a / kSqrt2) - std::erfc(b / kSqrt2));
  if (b <= 0.0) return 0.5 * (std::erfc(-b / kSqrt2) - std::erfc(-a / kSqrt2));
  return 1.0 - 0.5 * std::erfc(b / kSqrt2) - 0.5 * std::erfc(-a / kSqrt2);
}

// The standard normal's mass beyond the line at distance h > 0 from the origin and within the
// wedge from the foot of the perpendicular to the point at s ≥ 0 along the line is Owen's
// T(h, s/h) = Q(h)/2 + V. Only V is returned, so that an edge whose line passes near the
// origin but whose ends lie far along it (both T ≈ Q(h)/2) loses nothing to cancellation:
// for s ≥ h, T(h, a) = Q(h)/2 + Q(ah)/2 − Q(h) Q(ah) − T(ah, 1/a) (Owen 1956), whose last three
// terms are all small where s is large.
// @p terms accumulates the magnitudes of what is summed, for the caller's conditioning.
double wedgeTailExcess(double h, double s, double& terms) {
  if (s <= h) {
    const double t = boost::math::owens_t(h, s / h, OwensPolicy()), q = 0.5 * normalUpperTail(h);
    terms += t + q;
    return t - q;
  }
  if (s > kFarTail) return 0.0;
  const double qs = normalUpperTail(s);
  const double t = boost::math::owens_t(s, h / s, OwensPolicy()), qq = normalUpperTail(h) * qs;
  terms += 0.5 * qs + qq + t;
  return 0.5 * qs - qq - t;
}

// Σ of that mass between the points sa < sb along an edge at distance h > 0 (signed along s).
double edgeTail(double h, double sa, double sb, double& terms) {
  if (h > kFarTail) return 0.0;
  auto excess = [&](double s) {
    return s < 0.0 ? -wedgeTailExcess(h, -s, terms) : wedgeTailExcess(h, s, terms);
  };
  // The Q(h)/2 parts cancel where sa and sb lie on the same side of the foot (V(0) = −Q(h)/2
  // makes s = 0 either side).
  const double straddle = sa < 0.0 && sb >= 0.0 ? normalUpperTail(h) : 0.0;
  terms += straddle;
  return straddle + excess(sb) - excess(sa);
}

// The point of a convex counter-clockwise polygon nearest the origin (the origin inside it).
Vec2 nearestToOrigin(std::span<const Vec2> ccw) {
  const std::size_t n = ccw.size();
  bool inside = n >= 3;
  Vec2 nearest = n > 0 ? ccw[0] : Vec2(0.0);
  for (std::size_t i = 0; i < n; ++i) {
    const Vec2& a = ccw[i];
    const Vec2& b = ccw[(i + 1) % n];
    const Vec2 e = b - a;
    if (cross2(e, -a) < 0.0) inside = false;  // the origin is right of this edge
    const double len2 = glm::dot(e, e);
    const double w = len2 > 0.0 ? std::clamp(-glm::dot(a, e) / len2, 0.0, 1.0) : 0.0;
    const Vec2 p = a + w * e;
    if (glm::dot(p, p) < glm::dot(nearest, nearest)) nearest = p;
  }
  return inside ? Vec2(0.0) : nearest;
}

// How much |y|²/2 grows over a polygon from its point @p nearest the origin: (|v|² − |p|²)/2 as
// (v − p)·(v + p)/2, which keeps its precision however far out the polygon lies.
double exponentRange(std::span<const Vec2> ccw, const Vec2& nearest) {
  double range = 0.0;
  for (const Vec2& v : ccw) range = std::max(range, 0.5 * glm::dot(v - nearest, v + nearest));
  return range;
}
// Within this range of |y|²/2 over a polygon its moments are taken by quadrature (see
// standardNormalOverPolygon()), beyond it in closed form.
constexpr double kQuadratureRange = 8.0;
// The quadrature's triangles are split until |y|²/2 varies by at most this over each: the
// degree-11 rule then errs by about 1e-9 of their mass (the exponential's Taylor remainder
// about the middle, (range/2)¹² / 12!).
constexpr double kTriangleRange = 2.0;
// (|mean|² + spread) / spread within which the closed form's third moments about the mean
// keep about 1e-5 of their size: its terms err by about 1e-10 of theirs, which the cancellation
// of E[y³] against the mean's cube multiplies by this ratio to the power 3/2.
constexpr double kSkewConditioning = 400.0;

// The third moments about the mean @p mean from those about some origin: the second
// (@p xx, @p xy, @p yy) and third ({xxx, xxy, xyy, yyy}) per unit mass.
void centralThirdMoments(const Vec2& mean, double xx, double xy, double yy,
                         const std::array<double, 4>& third, NormalMoments& m) {
  const double mx = mean.x, my = mean.y;
  m.skew_xxx = third[0] - 3.0 * mx * xx + 2.0 * mx * mx * mx;
  m.skew_xxy = third[1] - my * xx - 2.0 * mx * xy + 2.0 * mx * mx * my;
  m.skew_xyy = third[2] - mx * yy - 2.0 * my * xy + 2.0 * mx * my * my;
  m.skew_yyy = third[3] - 3.0 * my * yy + 2.0 * my * my * my;
}

// The moments by a degree-11 rule, weighted relative to the density at the polygon's point
// @p near_point nearest the origin and taken about the vertices' average, so that nothing
// cancels.
NormalMoments quadratureMoments(std::span<const Vec2> ccw, const Vec2& near_point) {
  NormalMoments m;
  const std::size_t n = ccw.size();
  Vec2 ref{0.0};
  for (const Vec2& v : ccw) ref += v;
  ref /= static_cast<double>(n);
  struct Triangle {
    Vec2 a, b, c;
    int depth;
  };
  // Depth-first, each triangle at most kMaxSplits times: the polygon's range is at most
  // kQuadratureRange, and each split about halves a triangle's, so two or three suffice.
  constexpr int kMaxSplits = 4;
  std::array<Triangle, 16 + 3 * kMaxSplits> stack{};
  std::size_t top = 0;
  for (std::size_t i = 1; i + 1 < n; ++i) stack[top++] = {ccw[0], ccw[i], ccw[i + 1], 0};
  static const std::span<const TriangleNode> kRule = conicalProductRule(6);
  double m0 = 0.0, sxx = 0.0, sxy = 0.0, syy = 0.0, sxxx = 0.0, sxxy = 0.0, sxyy = 0.0, syyy = 0.0;
  Vec2 m1{0.0};
  while (top > 0) {
    const Triangle t = stack[--top];
    const std::array<Vec2, 3> corners{t.a, t.b, t.c};
    if (t.depth < kMaxSplits && exponentRange(corners, nearestToOrigin(corners)) > kTriangleRange) {
      const Vec2 ab = 0.5 * (t.a + t.b), bc = 0.5 * (t.b + t.c), ca = 0.5 * (t.c + t.a);
      const int depth = t.depth + 1;
      stack[top++] = {t.a, ab, ca, depth};
      stack[top++] = {ab, t.b, bc, depth};
      stack[top++] = {ca, bc, t.c, depth};
      stack[top++] = {ab, bc, ca, depth};
      continue;
    }
    const double area = 0.5 * cross2(t.b - t.a, t.c - t.a);
    if (!(area > 0.0)) continue;
    for (const TriangleNode& node : kRule) {
      const Vec2 x = node.bary[0] * t.a + node.bary[1] * t.b + node.bary[2] * t.c;
      const double w =
          node.weight * area * std::exp(-0.5 * glm::dot(x - near_point, x + near_point));
      const Vec2 z = x - ref;
      m0 += w;
      m1 += w * z;
      sxx += w * z.x * z.x;
      sxy += w * z.x * z.y;
      syy += w * z.y * z.y;
      sxxx += w * z.x * z.x * z.x;
      sxxy += w * z.x * z.x * z.y;
      sxyy += w * z.x * z.y * z.y;
      syyy += w * z.y * z.y * z.y;
    }
  }
  m.mass = m0 * std::exp(-0.5 * glm::dot(near_point, near_point)) / (2.0 * kPi);
  if (!(m.mass > 0.0) || !std::isfinite(m.mass)) return NormalMoments{};
  const Vec2 shift = m1 / m0;
  m.mean = ref + shift;
  m.cov_xx = sxx / m0 - shift.x * shift.x;
  m.cov_xy = sxy / m0 - shift.x * shift.y;
  m.cov_yy = syy / m0 - shift.y * shift.y;
  m.first = m.mass * m.mean;
  m.second_xx = m.mass * (m.cov_xx + m.mean.x * m.mean.x);
  m.second_xy = m.mass * (m.cov_xy + m.mean.x * m.mean.y);
  m.second_yy = m.mass * (m.cov_yy + m.mean.y * m.mean.y);
  centralThirdMoments(shift, sxx / m0, sxy / m0, syy / m0,
                      {sxxx / m0, sxxy / m0, sxyy / m0, syyy / m0}, m);
  m.skew_known = true;
  return m;
}

// @p terms receives the sum of the magnitudes the mass is the difference of: its conditioning.
NormalMoments closedFormMoments(std::span<const Vec2> ccw, double& terms) {
  NormalMoments m;
  const std::size_t n = ccw.size();
  double winding = 0.0, tails = 0.0;
  terms = 0.0;
  bool on_boundary = false;  // the origin lies exactly on an edge (a symmetric glint does)
  Vec2 boundary{0.0};
  double sxx = 0.0, sxy = 0.0, syy = 0.0;  // ∮ yⱼ φ₂ nᵢ ds, symmetrised
  Vec2 xx_n{0.0}, yy_n{0.0};               // ∮ x² φ₂ n ds, ∮ y² φ₂ n ds
  for (std::size_t i = 0; i < n; ++i) {
    const Vec2& a = ccw[i];
    const Vec2& b = ccw[(i + 1) % n];
    const Vec2 e = b - a;
    const double len = glm::length(e);
    if (!(len > 0.0)) continue;
    const Vec2 dir = e / len;
    const Vec2 out(dir.y, -dir.x);  // outward for a counter-clockwise polygon
    // The distance from the nearer end, whose rounding is the smaller; and the angle the edge
    // subtends from the same h, sa, sb, so that the winding and the tails agree on which side
    // of the edge the origin lies even when it is within rounding of a vertex.
    const double h = glm::dot(glm::dot(a, a) <= glm::dot(b, b) ? a : b, out);
    const double sa = glm::dot(a, dir), sb = glm::dot(b, dir);
    winding += std::atan2(h * (sb - sa), h * h + sa * sb);
    if (h == 0.0 && sa <= 0.0 && sb >= 0.0) on_boundary = true;
    const double ah = std::abs(h);
    if (ah > kFarTail) continue;
    // Signed mass of the triangle (origin, a, b) is sign(h)·[wedge − tail] between sa and sb;
    // the wedges add up to the winding number, the tails are subtracted here.
    if (ah > 0.0) tails += (h > 0.0 ? 1.0 : -1.0) * edgeTail(ah, sa, sb, terms);
    // ∫ y φ₂ = −∮ φ₂ n ds, and φ₂ along the edge is φ(h) φ(s).
    // Along the edge y = h·out + s·dir and φ₂ = φ(h) φ(s).
    const double phi_h = kInvSqrt2Pi * std::exp(-0.5 * h * h);
    const double along = normalInterval(sa, sb);  // ∫ φ(s) ds
    const double s_along = kInvSqrt2Pi * (std::exp(-0.5 * sa * sa) - std::exp(-0.5 * sb * sb));
    boundary += out * (phi_h * along);
    const Vec2 y_along = phi_h * (h * along * out + s_along * dir);  // ∫ y φ₂ ds
    sxx += out.x * y_along.x;
    sxy += 0.5 * (out.x * y_along.y + out.y * y_along.x);
    syy += out.y * y_along.y;
    // ∫ yⱼ² φ₂ ds, with ∫ s² φ(s) ds = ∫ φ(s) ds + [−s φ(s)] between sa and sb.
    const double s2_along =
        along + kInvSqrt2Pi * (sa * std::exp(-0.5 * sa * sa) - sb * std::exp(-0.5 * sb * sb));
    const auto squared = [&](double o, double d) {
      return phi_h * (h * h * o * o * along + 2.0 * h * o * d * s_along + d * d * s2_along);
    };
    xx_n += out * squared(out.x, dir.x);
    yy_n += out * squared(out.y, dir.y);
  }
  // The winding number is 0 or 1: rounding removes the atan2 noise. On an edge (atan2 of ±0
  // would say ±π for it) the origin has half of its neighbourhood inside, at a corner the
  // corner's share.
  double inside = std::round(winding / (2.0 * kPi));
  if (on_boundary) {
    inside = 0.5;
    for (std::size_t i = 0; i < n; ++i) {
      if (ccw[i] != Vec2(0.0)) continue;
      const Vec2 next = ccw[(i + 1) % n], prev = ccw[(i + n - 1) % n];
      inside = std::atan2(cross2(next, prev), glm::dot(next, prev)) / (2.0 * kPi);
    }
  }
  m.mass = std::max(0.0, inside - tails);
  terms += std::abs(inside);
  m.first = -boundary;
  m.second_xx = m.mass - sxx;
  m.second_xy = -sxy;
  m.second_yy = m.mass - syy;
  if (m.mass > 0.0) {
    m.mean = m.first / m.mass;
    m.cov_xx = m.second_xx / m.mass - m.mean.x * m.mean.x;
    m.cov_xy = m.second_xy / m.mass - m.mean.x * m.mean.y;
    m.cov_yy = m.second_yy / m.mass - m.mean.y * m.mean.y;
    const std::array<double, 4> third{(2.0 * m.first.x - xx_n.x) / m.mass, -xx_n.y / m.mass,
                                      -yy_n.x / m.mass, (2.0 * m.first.y - yy_n.y) / m.mass};
    centralThirdMoments(m.mean, m.second_xx / m.mass, m.second_xy / m.mass, m.second_yy / m.mass,
                        third, m);
  }
  return m;
}

}  // namespace

NormalMoments standardNormalOverPolygon(std::span<const Vec2> ccw) {
  const std::size_t n = ccw.size();
  if (n < 3 || n > 16) return NormalMoments{};
  double terms = 0.0;
  const NormalMoments closed = closedFormMoments(ccw, terms);
  // The closed form is taken where it is well conditioned: its mass not a small difference of
  // its terms, its covariance not a small difference of second moment and squared mean. (Its
  // terms carry errors up to about 1e-10 of their size, which these ratios multiply; both pass
  // for a polygon that holds much of the lobe or is not small against it.)
  const double spread = closed.cov_xx + closed.cov_yy;
  const double thinnest =
      0.5 * spread - std::hypot(0.5 * (closed.cov_xx - closed.cov_yy), closed.cov_xy);
  const bool conditioned =
      closed.mass > 1e-4 * terms && thinnest > 1e-7 * (glm::dot(closed.mean, closed.mean) + spread);
  // The third moments about the mean cancel as the cube of the mean against the spread's:
  // resolved within kSkewConditioning.
  const bool skew_conditioned =
      glm::dot(closed.mean, closed.mean) + spread <= kSkewConditioning * spread;
  if (conditioned && skew_conditioned) {
    NormalMoments m = closed;
    m.skew_known = true;
    return m;
  }
  // Otherwise the polygon is small against the lobe or far out in its tail, where the density
  // varies little over it: by quadrature, if it varies by at most e⁸. (A NaN vertex fails the
  // test and keeps the closed form's NaN mass.)
  const Vec2 near_point = nearestToOrigin(ccw);
  if (exponentRange(ccw, near_point) <= kQuadratureRange) return quadratureMoments(ccw, near_point);
  NormalMoments m = closed;
  m.skew_xxx = m.skew_xxy = m.skew_xyy = m.skew_yyy = 0.0;  // unresolved: skew_known false
  return m;
}

void clipPolygon(ConvexPolygon& p, const std::array<double, 3>& f) {
  auto value = [&](const Vec2& x) { return f[0] + (f[1] - f[0]) * x.x + (f[2] - f[0]) * x.y; };
  ConvexPolygon out;
  for (int i = 0; i < p.n; ++i) {
    const Vec2& a = p.v[i];
    const Vec2& b = p.v[(i + 1) % p.n];
    const double fa = value(a), fb = value(b);
    if (fa > 0.0) out.v[out.n++] = a;
    if ((fa > 0.0) != (fb > 0.0)) {
      const double w = fa / (fa - fb);
      out.v[out.n++] = a + w * (b - a);
    }
    if (out.n >= 7) break;  // cannot happen for a convex polygon and a line; never overrun
  }
  p = out;
}

double distanceToOrigin(std::span<const Vec2> ccw) { return glm::length(nearestToOrigin(ccw)); }

}  // namespace glint
