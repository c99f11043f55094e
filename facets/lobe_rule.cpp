#include "facets/lobe_rule.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>

#include "facets/bivariate_normal.h"
#include "facets/triangle_rule.h"

namespace glint {
namespace {

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
  bool linearise(const SlopeModel::Local& l, const Vec2& c, double sigma, const ConvexPolygon& part,
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
    upper_log_ = -least_ / (2.0 * s2_) + std::log(2.0 * kPi * normalUpperTail(d)) -
                 0.5 * std::log(l1_ * l2_);
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

LobeNode lobeNode(const SurfaceMap& map, const Vec3& bary, const Vec3& observer_m, const Beam& beam,
                  const Material& material) {
  return lobeNode(map.at(bary), observer_m, beam, material);
}

LobeNode lobeNode(const SurfacePoint& p, const Vec3& observer_m, const Beam& beam,
                  const Material& material) {
  assert(material.more_lobes.empty() && "the lobe rule takes one term (Material::terms())");
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
bool integrateOverPart(const LobeSampler& sampler, const ConvexPolygon& part,
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
bool integrateSpecularPart(const LobeSampler& sampler, const std::array<const LobeNode*, 6>& nodes,
                           const ConvexPolygon& poly, double sigma, double negligible,
                           SpecularPart& part) {
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
  ConvexPolygon poly;
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
    if (!integrateSpecularPart(sampler, nodes, poly, sigma, negligible, specular)) return result;
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
