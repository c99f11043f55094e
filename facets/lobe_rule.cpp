#include "facets/lobe_rule.h"

#include <algorithm>
#include <boost/math/special_functions/owens_t.hpp>
#include <cmath>
#include <limits>

#include "facets/triangle_rule.h"

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

// The largest |ln(f / Gaussian)| at a sigma point for which the Gaussian still models a piece.
constexpr double kMaxLogRatio = 2.0;

// How far outside the piece (in its (s, t) units) a sigma point may be sampled: the integrand
// continues smoothly there, and truncated Gaussians put a sigma point up to ~0.7 standard
// deviations past the part's edge.
constexpr double kSigmaPointReach = 0.5;

// The skewness along a principal axis of the lobe as restricted to a part above which the
// skewed sigma rule places its points differently from the symmetric one along it (a
// half-normal's is 0.995; below 0.1 the third-order term is a tenth of it).
constexpr double kSkewRuleThreshold = 0.1;

// Beyond this distance from the origin the normal density (e^{-h²/2} < 1e-322) is nothing.
constexpr double kFarTail = 38.5;

// Φ(b) − Φ(a) for a ≤ b, in whichever tail keeps it accurate.
double normalInterval(double a, double b) {
  if (a >= 0.0) return 0.5 * (std::erfc(a / kSqrt2) - std::erfc(b / kSqrt2));
  if (b <= 0.0) return 0.5 * (std::erfc(-b / kSqrt2) - std::erfc(-a / kSqrt2));
  return 1.0 - 0.5 * std::erfc(b / kSqrt2) - 0.5 * std::erfc(-a / kSqrt2);
}

double upperTail(double x) { return 0.5 * std::erfc(x / kSqrt2); }  // Q(x) = 1 − Φ(x)

// The standard normal's mass beyond the line at distance h > 0 from the origin and within the
// wedge from the foot of the perpendicular to the point at s ≥ 0 along the line is Owen's
// T(h, s/h) = Q(h)/2 + V. Only V is returned, so that an edge whose line passes near the
// origin but whose ends lie far along it (both T ≈ Q(h)/2) loses nothing to cancellation:
// for s ≥ h, T(h, a) = Q(h)/2 + Q(ah)/2 − Q(h) Q(ah) − T(ah, 1/a) (Owen 1956), whose last three
// terms are all small where s is large.
// @p terms accumulates the magnitudes of what is summed, for the caller's conditioning.
double wedgeTailExcess(double h, double s, double& terms) {
  if (s <= h) {
    const double t = boost::math::owens_t(h, s / h, OwensPolicy()), q = 0.5 * upperTail(h);
    terms += t + q;
    return t - q;
  }
  if (s > kFarTail) return 0.0;
  const double qs = upperTail(s);
  const double t = boost::math::owens_t(s, h / s, OwensPolicy()), qq = upperTail(h) * qs;
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
  const double straddle = sa < 0.0 && sb >= 0.0 ? upperTail(h) : 0.0;
  terms += straddle;
  return straddle + excess(sb) - excess(sa);
}

// A convex polygon in the piece's (s, t) coordinates, where the piece is the triangle
// (0,0), (1,0), (0,1). Four clips of a triangle leave at most 7 vertices.
struct Polygon {
  std::array<Vec2, 8> v{};
  int n = 0;
};

// Keeps the part where the function, linear over the reference triangle with corner values f,
// is positive (Sutherland–Hodgman for one half-plane).
void clipPolygon(Polygon& p, const std::array<double, 3>& f) {
  auto value = [&](const Vec2& x) { return f[0] + (f[1] - f[0]) * x.x + (f[2] - f[0]) * x.y; };
  Polygon out;
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

double cross2(const Vec2& a, const Vec2& b) { return a.x * b.y - a.y * b.x; }

// The quadratic (P2) Lagrange basis on the reference triangle at (s, t), nodes ordered as the
// rule's (corners, then midpoints of 01, 12, 20), with its derivatives.
struct P2 {
  std::array<double, 6> n, ds, dt;
  explicit P2(const Vec2& x) {
    const double l0 = 1.0 - x.x - x.y, l1 = x.x, l2 = x.y;
    n = {l0 * (2 * l0 - 1), l1 * (2 * l1 - 1), l2 * (2 * l2 - 1),
         4 * l0 * l1,       4 * l1 * l2,       4 * l2 * l0};
    ds = {1 - 4 * l0, 4 * l1 - 1, 0.0, 4 * (l0 - l1), 4 * l2, -4 * l2};
    dt = {1 - 4 * l0, 0.0, 4 * l2 - 1, -4 * l1, 4 * l1, 4 * (l0 - l2)};
  }
};

// The nearest point of the reference triangle (0,0), (1,0), (0,1).
Vec2 projectIntoTriangle(const Vec2& x) {
  if (x.x >= 0.0 && x.y >= 0.0 && x.x + x.y <= 1.0) return x;
  auto onSegment = [&](const Vec2& a, const Vec2& b) {
    const Vec2 e = b - a;
    const double w = std::clamp(glm::dot(x - a, e) / glm::dot(e, e), 0.0, 1.0);
    return a + w * e;
  };
  const std::array<Vec2, 3> candidates{onSegment({0.0, 0.0}, {1.0, 0.0}),
                                       onSegment({1.0, 0.0}, {0.0, 1.0}),
                                       onSegment({0.0, 1.0}, {0.0, 0.0})};
  Vec2 best = candidates[0];
  for (const Vec2& c : candidates) {
    if (glm::dot(c - x, c - x) < glm::dot(best - x, best - x)) best = c;
  }
  return best;
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

// The distance from the origin to a convex counter-clockwise polygon (0 inside it).
double distanceToOrigin(std::span<const Vec2> ccw) { return glm::length(nearestToOrigin(ccw)); }

// How much |y|²/2 grows over a polygon from its point @p nearest the origin: (|v|² − |p|²)/2 as
// (v − p)·(v + p)/2, which keeps its precision however far out the polygon lies.
double exponentRange(std::span<const Vec2> ccw, const Vec2& nearest) {
  double range = 0.0;
  for (const Vec2& v : ccw) range = std::max(range, 0.5 * glm::dot(v - nearest, v + nearest));
  return range;
}

// The quadratic interpolant of q over the piece, and its derivatives.
class SlopeModel {
 public:
  struct Local {
    Vec3 q, q_s, q_t;
  };
  explicit SlopeModel(const std::array<const LobeNode*, 6>& nodes) {
    for (int j = 0; j < 6; ++j) slope_[j] = nodes[j]->slope;
  }
  [[nodiscard]] Local at(const Vec2& x) const {
    const P2 b(x);
    Local l{Vec3(0.0), Vec3(0.0), Vec3(0.0)};
    for (int j = 0; j < 6; ++j) {
      l.q += b.n[j] * slope_[j];
      l.q_s += b.ds[j] * slope_[j];
      l.q_t += b.dt[j] * slope_[j];
    }
    return l;
  }

 private:
  std::array<Vec3, 6> slope_{};
};

struct SigmaRule {
  std::array<Vec2, 5> points{};
  std::array<double, 5> weights{};
};

// The lobe with q linearised at c, L(u) = q + J u for u = x − c: the Gaussian
// exp(−(|L|² + κ|u|²)/2σ²) in the piece's coordinates, and its moments over the part.
// κ = 1e-7 σ² changes it by at most 1e-7 over the piece and keeps it integrable where J is
// singular (a cylinder's stripe runs along its null direction).
class GaussianLobe {
 public:
  // False where the linearisation cannot be whitened (not finite).
  // With @p skip_below_log, the moments are not computed (skipped() turns true) where the
  // bound of the integral's logarithm, upperLogIntegral(), is below it.
  bool linearise(const SlopeModel::Local& l, const Vec2& c, double sigma, const Polygon& part,
                 double skip_below_log = -std::numeric_limits<double>::infinity()) {
    l_ = l;
    c_ = c;
    s2_ = sigma * sigma;
    kappa_ = 1e-7 * s2_;
    const double a11 = glm::dot(l.q_s, l.q_s) + kappa_, a12 = glm::dot(l.q_s, l.q_t),
                 a22 = glm::dot(l.q_t, l.q_t) + kappa_;
    const double b1 = glm::dot(l.q_s, l.q), b2 = glm::dot(l.q_t, l.q);
    const double det = a11 * a22 - a12 * a12;
    if (!(det > 0.0) || !std::isfinite(det)) return false;
    const Vec2 u_star(-(a22 * b1 - a12 * b2) / det, -(a11 * b2 - a12 * b1) / det);
    least_ = std::max(0.0, glm::dot(l.q, l.q) + b1 * u_star.x + b2 * u_star.y);
    // Whiten: y = Λ^{1/2} Vᵀ (x − centre) with S = A/σ² = V Λ Vᵀ, V a rotation (so the
    // polygon stays counter-clockwise).
    const double theta = 0.5 * std::atan2(2.0 * a12, a11 - a22);
    cs_ = std::cos(theta);
    sn_ = std::sin(theta);
    const double floor_l = kappa_ / s2_;
    l1_ = std::max((a11 * cs_ * cs_ + 2.0 * a12 * sn_ * cs_ + a22 * sn_ * sn_) / s2_, floor_l);
    l2_ = std::max((a11 * sn_ * sn_ - 2.0 * a12 * sn_ * cs_ + a22 * cs_ * cs_) / s2_, floor_l);
    r1_ = std::sqrt(l1_);
    r2_ = std::sqrt(l2_);
    centre_ = c + u_star;
    std::array<Vec2, 8>& y = whitened_;
    whitened_n_ = part.n;
    for (int i = 0; i < part.n; ++i) y[i] = whiten(part.v[i]);
    // A convex part at distance d from the Gaussian's centre lies in a half plane that far
    // out: its mass is at most Q(d), which needs no Owen's T.
    const double d = distanceToOrigin(std::span<const Vec2>(y.data(), part.n));
    upper_log_ =
        -least_ / (2.0 * s2_) + std::log(2.0 * kPi * upperTail(d)) - 0.5 * std::log(l1_ * l2_);
    skipped_ = upper_log_ < skip_below_log;
    mom_ = skipped_ ? NormalMoments{}
                    : standardNormalOverPolygon(std::span<const Vec2>(y.data(), part.n));
    return std::isfinite(mom_.mass);
  }

  [[nodiscard]] bool skipped() const { return skipped_; }
  // A bound of ln ∫ over the part of the Gaussian (−∞ where the part is beyond its tail).
  [[nodiscard]] double upperLogIntegral() const { return upper_log_; }

  [[nodiscard]] double mass() const { return mom_.mass; }
  // ln ∫ over the part of the Gaussian (requires mass() > 0).
  [[nodiscard]] double logIntegral() const {
    return -least_ / (2.0 * s2_) + std::log(2.0 * kPi * mom_.mass) - 0.5 * std::log(l1_ * l2_);
  }
  // The centroid of the Gaussian over the part (requires mass() > 0).
  [[nodiscard]] Vec2 mean() const { return unwhiten(mom_.mean); }

  // Five points and weights that average a function over the Gaussian as restricted to the
  // part: its mean (weight 1/3) and two points along each principal axis (1/3 between them),
  // placed so that the rule has the Gaussian's mean and covariance, exact for quadratics.
  // Both rules, from one set of principal axes: the symmetric (±√3 standard deviations, 1/6
  // each), and the skewed, with the third moment along each axis too, exact for cubics along
  // the axes (a truncation skews the Gaussian; the symmetric points then err by the
  // third-order term, which the skewed ones do not).
  struct SigmaRules {
    SigmaRule symmetric, skewed;
  };
  [[nodiscard]] SigmaRules sigmaRules() const {
    const Axes axes = principalAxes();
    return {sigmaRule(axes, false), sigmaRule(axes, true)};
  }

  // How evenly the lobe covers the part (requires mass() > 0): the determinant of the
  // Gaussian's covariance as restricted to the part over that of the part's uniform measure,
  // in [0, 1] (a ratio of determinants, the same in any affine coordinates). Near 1 the lobe
  // is flat over the part; near 0 it sits in a corner of it, or in a spot within it.
  [[nodiscard]] double evenness() const {
    const std::array<Vec2, 8>& y = whitened_;
    double area = 0.0, ixx = 0.0, ixy = 0.0, iyy = 0.0;
    Vec2 first{0.0};
    for (int i = 0; i < whitened_n_; ++i) {
      const Vec2& a = y[i];
      const Vec2& b = y[(i + 1) % whitened_n_];
      const double w = cross2(a, b);
      area += 0.5 * w;
      first += (a + b) * (w / 6.0);
      ixx += (a.x * a.x + a.x * b.x + b.x * b.x) * w / 12.0;
      iyy += (a.y * a.y + a.y * b.y + b.y * b.y) * w / 12.0;
      ixy += (a.x * b.y + 2.0 * a.x * a.y + 2.0 * b.x * b.y + b.x * a.y) * w / 24.0;
    }
    if (!(area > 0.0) || !(mom_.mass > 0.0)) return 0.0;
    const Vec2 cu = first / area;
    const double uxx = ixx / area - cu.x * cu.x, uxy = ixy / area - cu.x * cu.y,
                 uyy = iyy / area - cu.y * cu.y;
    const double ratio =
        (mom_.cov_xx * mom_.cov_yy - mom_.cov_xy * mom_.cov_xy) / (uxx * uyy - uxy * uxy);
    return ratio >= 0.0 ? std::min(1.0, ratio) : 0.0;  // NaN: 0, all hidden
  }
  // ln(f / (h · Gaussian)) at x for the true slope q there: what the linearisation missed.
  [[nodiscard]] double logRatio(const Vec2& x, const Vec3& q) const {
    const Vec2 u = x - c_;
    const Vec3 lin = l_.q + u.x * l_.q_s + u.y * l_.q_t;
    return -(glm::dot(q, q) - glm::dot(lin, lin) - kappa_ * glm::dot(u, u)) / (2.0 * s2_);
  }

 private:
  // The principal axes of the Gaussian as restricted to the part (whitened coordinates):
  // directions, standard deviations and skewness γ = μ₃(e, e, e) / sd³ along each.
  struct Axes {
    std::array<Vec2, 2> dir{};
    std::array<double, 2> sd{}, skewness{};
  };
  [[nodiscard]] Axes principalAxes() const {
    const double cxx = std::max(0.0, mom_.cov_xx);
    const double cyy = std::max(0.0, mom_.cov_yy);
    const double bound = std::sqrt(cxx * cyy);
    const double cxy = std::clamp(mom_.cov_xy, -bound, bound);
    const double phi = 0.5 * std::atan2(2.0 * cxy, cxx - cyy);
    const double pc = std::cos(phi), ps = std::sin(phi);
    Axes a;
    a.dir = {Vec2(pc, ps), Vec2(-ps, pc)};
    const std::array<double, 2> var{
        std::max(0.0, cxx * pc * pc + 2.0 * cxy * ps * pc + cyy * ps * ps),
        std::max(0.0, cxx * ps * ps - 2.0 * cxy * ps * pc + cyy * pc * pc)};
    for (int k = 0; k < 2; ++k) {
      a.sd[k] = std::sqrt(var[k]);
      const Vec2& e = a.dir[k];
      const double mu3 = e.x * e.x * e.x * mom_.skew_xxx + 3.0 * e.x * e.x * e.y * mom_.skew_xxy +
                         3.0 * e.x * e.y * e.y * mom_.skew_xyy + e.y * e.y * e.y * mom_.skew_yyy;
      const double gamma = a.sd[k] > 0.0 ? mu3 / (var[k] * a.sd[k]) : 0.0;
      a.skewness[k] = std::isfinite(gamma) ? gamma : 0.0;
    }
    return a;
  }

  [[nodiscard]] SigmaRule sigmaRule(const Axes& axes, bool skewed) const {
    const Vec2 ym = mom_.mean;
    SigmaRule rule;
    rule.points[0] = unwhiten(ym);
    rule.weights[0] = 1.0 / 3.0;
    for (int k = 0; k < 2; ++k) {
      // Weights W p and W (1 − p) at +a and −b standard deviations (W = 1/3): mean 0 and
      // variance 1 give W p a = W (1 − p) b = m, m² = W p (1 − p); the third moment γ then
      // gives 1 − 2p = g / √(1 + g²) with g = γ √W / 2 (p = 1/2, a = b = √3 for γ = 0).
      constexpr double kW = 1.0 / 3.0;
      const double gamma = axes.skewness[k];
      const double g =
          skewed && std::abs(gamma) > kSkewRuleThreshold ? 0.5 * gamma * std::sqrt(kW) : 0.0;
      const double p = 0.5 * (1.0 - g / std::sqrt(1.0 + g * g));
      const double wa = kW * p, wb = kW * (1.0 - p);
      const double m = std::sqrt(kW * p * (1.0 - p));
      const Vec2 step = axes.sd[k] * axes.dir[k];
      rule.points[1 + 2 * k] = unwhiten(ym + (m / wa) * step);
      rule.points[2 + 2 * k] = unwhiten(ym - (m / wb) * step);
      rule.weights[1 + 2 * k] = wa;
      rule.weights[2 + 2 * k] = wb;
    }
    return rule;
  }

  [[nodiscard]] Vec2 whiten(const Vec2& x) const {
    const Vec2 w = x - centre_;
    return {r1_ * (cs_ * w.x + sn_ * w.y), r2_ * (-sn_ * w.x + cs_ * w.y)};
  }
  [[nodiscard]] Vec2 unwhiten(const Vec2& y) const {
    const Vec2 w(y.x / r1_, y.y / r2_);
    return centre_ + Vec2(cs_ * w.x - sn_ * w.y, sn_ * w.x + cs_ * w.y);
  }

  SlopeModel::Local l_{};
  Vec2 c_{0.0}, centre_{0.0};
  double s2_ = 1.0, kappa_ = 0.0, least_ = 0.0, l1_ = 1.0, l2_ = 1.0, r1_ = 1.0, r2_ = 1.0;
  double cs_ = 1.0, sn_ = 0.0;
  NormalMoments mom_{};
  std::array<Vec2, 8> whitened_{};  // the part's vertices in the whitened coordinates
  int whitened_n_ = 0;
  double upper_log_ = 0.0;
  bool skipped_ = false;
};

}  // namespace

namespace {

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

LobeNode lobeNode(const SurfaceMap& map, const Vec3& bary, const Vec3& observer_m, const Beam& beam,
                  const Material& material) {
  return lobeNode(map.at(bary), observer_m, beam, material);
}

LobeNode lobeNode(const SurfacePoint& p, const Vec3& observer_m, const Beam& beam,
                  const Material& material) {
  LobeNode node;
  if (!p.valid) return node;
  const Beam::Footprint b = beam.footprint(p.position_m);
  const Vec3 to_observer = observer_m - p.position_m;
  const double d2 = glm::dot(to_observer, to_observer);
  if (!(d2 > 0.0)) return node;
  const double d = std::sqrt(d2);
  const Vec3 wo = to_observer / d;
  const double cos_i = glm::dot(p.normal, b.toward_laser);
  const double cos_r = glm::dot(p.normal, wo);
  node.clip = {cos_i, cos_r * d, b.edge_margin, b.axial_m};
  double scale = b.irradiance_w_m2 * p.jacobian_m2 / d2;
  if (beam.return_extinction_per_m > 0.0) scale *= std::exp(-beam.return_extinction_per_m * d);
  node.diffuse = material.diffuse_reflectance / kPi * scale * cos_i * cos_r;
  node.valid = true;
  const Vec3 h = b.toward_laser + wo;
  const double hn = glm::dot(h, p.normal);
  if (!(hn > 0.0)) return node;  // θN ≥ 90°: no lobe, and q is undefined
  node.has_slope = true;
  if (material.specular_reflectance > 0.0) {
    node.slope = h / hn - p.normal;
    const double s = glm::dot(node.slope, node.slope);
    const double sigma = material.lobe.sigma;
    node.specular =
        material.specular_reflectance * scale * (1.0 + s) * (1.0 + s) / (8.0 * kPi * sigma * sigma);
  }
  return node;
}

namespace {

// ∫ value(integrand) ds dt over the part, by @p rule on each triangle of a fan from its first
// vertex, sampled from @p sampler (continued smoothly past the part's clipped edges). Adds to
// @p out and @p evaluations; false where a sample is invalid.
template <class Value>
bool integrateOverPart(const LobeSampler& sampler, const Polygon& part,
                       std::span<const TriangleNode> rule, const Value& value, double& out,
                       int& evaluations) {
  for (int i = 1; i + 1 < part.n; ++i) {
    const Vec2 &a = part.v[0], &b = part.v[i], &c = part.v[i + 1];
    const double area = 0.5 * cross2(b - a, c - a);
    double sum = 0.0;
    for (const TriangleNode& node : rule) {
      const Vec2 x = node.bary[0] * a + node.bary[1] * b + node.bary[2] * c;
      const LobeNode at = sampler.at(x.x, x.y);
      ++evaluations;
      if (!at.valid) return false;
      sum += node.weight * value(at);
    }
    out += area * sum;
  }
  return true;
}

// The specular term over the part: ∫ f ds dt in the piece's coordinates, with its error.
struct SpecularPart {
  double value = 0.0;
  double error = 0.0;
  double hidden_error = 0.0;  // see LobeEstimate::hidden_error_w_m2
  int evaluations = 0;
};

// False where the rule cannot be applied (the map breaks down, or a wide lobe lacks a model).
bool integrateLobe(const LobeSampler& sampler, const std::array<const LobeNode*, 6>& nodes,
                   const Polygon& poly, double sigma, double negligible, SpecularPart& part) {
  // A node past θN = 90° leaves q without a model. The piece's normals spread less than 0.3 rad
  // (the lobe scheme's resolution), so all of it then lies beyond θN = 73°, where for σ < 0.2
  // the lobe is below e^-130 of its peak: nothing.
  if (std::any_of(nodes.begin(), nodes.end(), [](const LobeNode* n) { return !n->has_slope; })) {
    if (sigma < 0.2) return true;
    // A wide lobe there is smooth over the piece and falls to 0 with all its derivatives at
    // θN = 90° (e^{−1/(2σ² cos²θN)} / cos⁴θN): no lobe to model, an ordinary degree-5 rule
    // on the part does, its error shown by the change under splitting. (Splitting until every
    // node had a slope would never end: the pieces along θN = 90° double with each level.)
    static const std::span<const TriangleNode> kRule = conicalProductRule(3);
    const auto whole = [sigma](const LobeNode& at) {
      return at.has_slope
                 ? at.specular * std::exp(-glm::dot(at.slope, at.slope) / (2.0 * sigma * sigma))
                 : 0.0;
    };
    return integrateOverPart(sampler, poly, kRule, whole, part.value, part.evaluations) &&
           std::isfinite(part.value);
  }
  const SlopeModel model(nodes);
  // The specular point: least |q|² over the piece, by projected Gauss–Newton on the
  // interpolant (q is nearly affine, so a few steps settle it).
  Vec2 c(1.0 / 3.0);
  for (int it = 0; it < 8; ++it) {
    const SlopeModel::Local l = model.at(c);
    const double a11 = glm::dot(l.q_s, l.q_s), a12 = glm::dot(l.q_s, l.q_t),
                 a22 = glm::dot(l.q_t, l.q_t);
    const double g1 = glm::dot(l.q_s, l.q), g2 = glm::dot(l.q_t, l.q);
    const double reg = 1e-12 * (a11 + a22) + 1e-300;
    const double det = (a11 + reg) * (a22 + reg) - a12 * a12;
    if (!(det > 0.0)) break;
    const Vec2 step(-((a22 + reg) * g1 - a12 * g2) / det, -((a11 + reg) * g2 - a12 * g1) / det);
    const Vec2 next = projectIntoTriangle(c + step);
    const double moved = glm::length(next - c);
    c = next;
    if (!(moved > 1e-10)) break;
  }
  // What the interpolated factor can reach over the piece (a quadratic through six values
  // overshoots their range by at most an eighth of it on each side).
  double low = nodes[0]->specular, high = low;
  for (const LobeNode* n : nodes) {
    low = std::min(low, n->specular);
    high = std::max(high, n->specular);
  }
  const double factor_bound = high + 0.125 * (high - low);
  const double skip_below = negligible > 0.0 && factor_bound > 0.0
                                ? std::log(negligible / factor_bound) - kMaxLogRatio
                                : -std::numeric_limits<double>::infinity();
  GaussianLobe lobe;
  if (!lobe.linearise(model.at(c), c, sigma, poly, skip_below)) return false;
  if (lobe.skipped()) {  // negligible even at its bound: kept as 0, the bound as its error
    part.error = factor_bound * std::exp(lobe.upperLogIntegral() + kMaxLogRatio);
    part.hidden_error = part.error;
    return true;
  }
  // Where the specular point lies outside the piece (or the part is clipped), the mass sits
  // away from c: linearised again at its centroid, the Gaussian follows q where it matters,
  // and what is left for the sigma points is flatter.
  if (lobe.mass() > 0.0) {
    const Vec2 m = projectIntoTriangle(lobe.mean());
    if (glm::length(m - c) > 1e-3) {
      GaussianLobe again;
      if (again.linearise(model.at(m), m, sigma, poly) && again.mass() > 0.0) lobe = again;
    }
  }
  if (lobe.mass() > 0.0 && negligible > 0.0) {
    // The interpolants' own estimate, at the centroid: where even e² times it is negligible,
    // the piece is not worth the sigma points (it is kept, with all of it as its error).
    const Vec2 m = lobe.mean();
    const P2 b(m);
    double factor = 0.0;
    for (int j = 0; j < 6; ++j) factor += b.n[j] * nodes[j]->specular;
    const double log_value = lobe.logIntegral() + lobe.logRatio(m, model.at(m).q);
    const double value = std::max(0.0, factor) * std::exp(std::min(log_value, 700.0));
    if (std::exp(kMaxLogRatio) * value < negligible) {
      part.value = value;
      part.error = std::exp(kMaxLogRatio) * value;
      part.hidden_error = part.error;
      return true;
    }
  }
  if (lobe.mass() > 0.0) {
    // The rest of the integrand, R = f / Gaussian, is smooth: it is averaged over the Gaussian
    // (as restricted to the part) with the five sigma points of its mean and covariance
    // (weights 1/3 at the mean, 1/6 at ±√3 standard deviations along each principal axis),
    // exact for R quadratic. R is sampled from the integrand itself, continued smoothly past
    // the part's edges where a sigma point falls outside it.
    // Where the part cuts the Gaussian (a glint on a piece's edge), the sigma points also
    // take its skew: the skewed rule is the estimate, its difference from the symmetric one
    // (the symmetric rule's third-order error) part of the error.
    const auto [symmetric, skew] = lobe.sigmaRules();
    // The mean, the symmetric rule's four points, then those of the skewed rule that differ
    // (along an axis whose skew is below kSkewRuleThreshold the two rules agree).
    std::array<Vec2, 9> points{};
    std::array<int, 5> skew_index{0, 1, 2, 3, 4};
    int count = 5;
    for (int i = 0; i < 5; ++i) points[i] = symmetric.points[i];
    for (int i = 1; i < 5; ++i) {
      if (skew.points[i] == symmetric.points[i]) continue;
      skew_index[i] = count;
      points[count++] = skew.points[i];
    }
    std::array<double, 9> log_r{}, factor{};
    double log_max = -std::numeric_limits<double>::infinity();
    bool poor_model = false;
    for (int i = 0; i < count; ++i) {
      // A sigma point far outside the piece (the moments of a part deep in the lobe's tail
      // are not resolved in double precision) is brought back onto it, and the estimate is
      // then only an order of magnitude.
      const Vec2 inside = projectIntoTriangle(points[i]);
      if (glm::length(inside - points[i]) > kSigmaPointReach) {
        points[i] = inside;
        poor_model = true;
      }
      const LobeNode at = sampler.at(points[i].x, points[i].y);
      ++part.evaluations;
      if (!at.valid) return false;
      if (!at.has_slope) {  // no lobe there, where the Gaussian says there is some
        poor_model = true;
        continue;  // factor 0
      }
      log_r[i] = lobe.logRatio(points[i], at.slope);
      if (!std::isfinite(log_r[i])) return false;
      // Where the linearised lobe misses the true one by more than e², the Gaussian is not a
      // model of this piece (a coarse piece of a strongly curved q, far out in a wide lobe's
      // tail): the estimate stands, but as wholly uncertain, so that it is split if it matters.
      if (std::abs(log_r[i]) > kMaxLogRatio) poor_model = true;
      factor[i] = at.specular;
      if (factor[i] > 0.0) log_max = std::max(log_max, log_r[i]);
    }
    // R at point i relative to e^{log_max}.
    const auto r = [&](int i) {
      return factor[i] > 0.0 ? factor[i] * std::exp(log_r[i] - log_max) : 0.0;
    };
    double average_symmetric = 0.0, average = 0.0;
    for (int i = 0; i < 5; ++i) {
      average_symmetric += symmetric.weights[i] * r(i);
      average += skew.weights[i] * r(skew_index[i]);
    }
    if (average > 0.0) {
      const double log_value = lobe.logIntegral() + log_max;
      if (!(log_value < 700.0)) return false;  // not finite
      const double scale = std::exp(log_value);
      part.value = average * scale;
      // The sigma points are exact for R quadratic over the part (and, skewed, cubic along
      // its axes); beyond that, their error is taken to be no larger than the whole
      // second-order term they add to the centre value, nor than the change the skew made.
      const double second_order = std::abs(average - r(0));
      const double third_order = std::abs(average - average_symmetric);
      part.error = poor_model ? part.value : std::max(second_order, third_order) * scale;
      part.hidden_error = poor_model ? part.error : (1.0 - lobe.evenness()) * part.error;
    }
  }
  return true;
}

}  // namespace

LobeEstimate lobeRule(const LobeSampler& sampler, const std::array<const LobeNode*, 6>& nodes,
                      double area_uv, double sigma, double negligible_w_m2, bool embedded) {
  LobeEstimate result;
  for (const LobeNode* node : nodes) {
    if (!node->valid) return result;
  }
  Polygon poly;
  poly.v[0] = {0.0, 0.0};
  poly.v[1] = {1.0, 0.0};
  poly.v[2] = {0.0, 1.0};
  poly.n = 3;
  for (int k = 0; k < 4; ++k) {
    const std::array<double, 3> f{nodes[0]->clip[k], nodes[1]->clip[k], nodes[2]->clip[k]};
    if (f[0] > 0.0 && f[1] > 0.0 && f[2] > 0.0) continue;
    clipPolygon(poly, f);
    if (poly.n < 3) {
      result.ok = true;  // nothing of the piece is lit, in the beam and in view
      return result;
    }
  }

  // The diffuse term is smooth over the clipped part: a degree-5 rule (3 × 3 conical product)
  // on each triangle of a fan, sampled from the integrand itself (continued smoothly, signed,
  // where the part's straight edges overshoot the true terminator or horizon).
  double diffuse = 0.0, diffuse_low = 0.0;
  const bool has_diffuse =
      std::any_of(nodes.begin(), nodes.end(), [](const LobeNode* n) { return n->diffuse != 0.0; });
  // The embedded estimate needs the whole piece smooth: every node lit, in view, in the beam.
  const bool unclipped = std::all_of(nodes.begin(), nodes.end(), [](const LobeNode* n) {
    return std::all_of(n->clip.begin(), n->clip.end(), [](double f) { return f > 0.0; });
  });
  auto integrate = [&](std::span<const TriangleNode> rule, double& out) {
    return integrateOverPart(
        sampler, poly, rule, [](const LobeNode& at) { return at.diffuse; }, out,
        result.evaluations);
  };
  if (has_diffuse) {
    static const std::span<const TriangleNode> kRule = conicalProductRule(3);
    if (!integrate(kRule, diffuse)) return result;
    if (embedded && unclipped) {
      static const std::span<const TriangleNode> kLowRule = conicalProductRule(2);
      if (!integrate(kLowRule, diffuse_low)) return result;
    }
  }

  SpecularPart specular;
  if (std::any_of(nodes.begin(), nodes.end(),
                  [](const LobeNode* n) { return n->specular != 0.0; })) {
    const double negligible = area_uv > 0.0 ? negligible_w_m2 / (2.0 * area_uv) : 0.0;
    if (!integrateLobe(sampler, nodes, poly, sigma, negligible, specular)) return result;
    result.evaluations += specular.evaluations;
  }
  const double value = 2.0 * area_uv * (specular.value + diffuse);
  const double error = 2.0 * area_uv * specular.error;
  if (!std::isfinite(value) || !std::isfinite(error)) return result;
  result.irradiance_w_m2 = value;
  result.rule_error_w_m2 = error;
  // (A NaN share leaves the whole error hidden.)
  result.hidden_error_w_m2 = std::min(error, 2.0 * area_uv * specular.hidden_error);
  if (embedded && unclipped) {
    result.diffuse_error_w_m2 = has_diffuse ? 2.0 * area_uv * std::abs(diffuse - diffuse_low) : 0.0;
  }
  if (!(result.diffuse_error_w_m2 >= 0.0)) {
    result.diffuse_error_w_m2 = std::numeric_limits<double>::infinity();
  }
  result.ok = true;
  return result;
}

}  // namespace glint
