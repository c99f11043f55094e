#include "facets/brdf_table.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

namespace glint {
namespace {

// An axis of the table's nodes, given (strictly increasing in [0, hi]), completed to [0, hi]
// by nodes that hold the value of the nearest given one, no more than kFillStepRad apart: the
// cosines vary across the filled band (the table holds f_r, the interpolant f_r cos θi cos θr),
// and narrow cells there keep the bounds of what the band reflects near grazing tight.
// source[k] is the given node whose values the completed node k takes.
struct Axis {
  std::vector<double> nodes;
  std::vector<std::size_t> source;
};

constexpr double kFillStepRad = kPi / 180.0;

Axis completedAxis(const std::vector<double>& given, double hi, const char* name) {
  if (given.empty()) throw std::invalid_argument(std::string(name) + ": no nodes");
  for (std::size_t k = 0; k < given.size(); ++k) {
    if (!(given[k] >= 0.0 && given[k] <= hi)) {
      throw std::invalid_argument(std::string(name) + ": node " + std::to_string(k) +
                                  " is outside the domain");
    }
    if (k > 0 && !(given[k] > given[k - 1])) {
      throw std::invalid_argument(std::string(name) + ": the nodes must increase strictly");
    }
  }
  Axis a;
  const auto fill = [&a](double from, double to, std::size_t source) {
    const int steps = static_cast<int>(std::ceil((to - from) / kFillStepRad - 1e-9));
    for (int j = 0; j < steps; ++j) {
      a.nodes.push_back(from + (to - from) * j / steps);
      a.source.push_back(source);
    }
  };
  fill(0.0, given.front(), 0);
  for (std::size_t k = 0; k < given.size(); ++k) {
    a.nodes.push_back(given[k]);
    a.source.push_back(k);
  }
  const double last = given.back();
  const int steps = static_cast<int>(std::ceil((hi - last) / kFillStepRad - 1e-9));
  for (int j = 1; j <= steps; ++j) {
    a.nodes.push_back(last + (hi - last) * j / steps);
    a.source.push_back(given.size() - 1);
  }
  return a;
}

// The cell of @p nodes holding @p x (clamped to the axis) and x's weight toward its upper node.
std::pair<std::size_t, double> locate(const std::vector<double>& nodes, double x) {
  if (!(x > nodes.front())) return {0, 0.0};
  if (!(x < nodes.back())) return {nodes.size() - 2, 1.0};
  const std::size_t k =
      static_cast<std::size_t>(std::upper_bound(nodes.begin(), nodes.end(), x) - nodes.begin()) - 1;
  return {k, (x - nodes[k]) / (nodes[k + 1] - nodes[k])};
}

// Half the finest step among the given nodes of an axis (∞ for a single node).
double halfFinestStep(const std::vector<double>& given) {
  double step = std::numeric_limits<double>::infinity();
  for (std::size_t k = 1; k < given.size(); ++k) step = std::min(step, given[k] - given[k - 1]);
  return 0.5 * step;
}

// 4-point Gauss–Legendre on [-1, 1].
constexpr std::array<double, 4> kGaussNode{-0.8611363115940526, -0.3399810435848563,
                                           0.3399810435848563, 0.8611363115940526};
constexpr std::array<double, 4> kGaussWeight{0.3478548451374538, 0.6521451548625461,
                                             0.6521451548625461, 0.3478548451374538};

}  // namespace

std::uint64_t BrdfTable::memoryBytes(const std::vector<double>& theta_i_rad,
                                     const std::vector<double>& theta_o_rad,
                                     const std::vector<double>& delta_phi_rad) {
  // The nodes each completed axis adds: its fill up to the first node and beyond the last.
  const auto completed = [](const std::vector<double>& given, double hi) -> std::uint64_t {
    if (given.empty()) return 0;
    const auto fill = [](double span) {
      return static_cast<std::uint64_t>(std::max(0.0, std::ceil(span / kFillStepRad - 1e-9)));
    };
    return given.size() + fill(given.front()) + fill(hi - given.back());
  };
  const std::uint64_t ni = completed(theta_i_rad, 0.5 * kPi),
                      no = completed(theta_o_rad, 0.5 * kPi), np = completed(delta_phi_rad, kPi);
  const std::uint64_t nodes = ni * no * np;
  const std::uint64_t cells = (ni > 0 ? ni - 1 : 0) * (no > 0 ? no - 1 : 0) * (np > 0 ? np - 1 : 0);
  // values_; the cells' (θN, bound) pairs and the envelope made of them; the coarse envelope;
  // the axes.
  return nodes * sizeof(double) + cells * 4 * sizeof(double) +
         static_cast<std::uint64_t>(kCoarseLevels) * kCoarseLevels * kCoarseLevels *
             sizeof(double) +
         2 * (ni + no + np) * sizeof(double);
}

BrdfTable::BrdfTable(std::vector<double> theta_i_rad, std::vector<double> theta_o_rad,
                     std::vector<double> delta_phi_rad, std::vector<double> values_per_sr) {
  const std::size_t count = theta_i_rad.size() * theta_o_rad.size() * delta_phi_rad.size();
  if (values_per_sr.size() != count) {
    throw std::invalid_argument("the table has " + std::to_string(values_per_sr.size()) +
                                " values for a grid of " + std::to_string(count) + " nodes");
  }
  for (double v : values_per_sr) {
    if (!(v >= 0.0 && std::isfinite(v)))
      throw std::invalid_argument("every BRDF value must be finite and ≥ 0");
  }
  const Axis ai = completedAxis(theta_i_rad, 0.5 * kPi, "theta_i");
  const Axis ao = completedAxis(theta_o_rad, 0.5 * kPi, "theta_o");
  const Axis ap = completedAxis(delta_phi_rad, kPi, "delta_phi");
  given_[0] = theta_i_rad;
  given_[1] = theta_o_rad;
  given_[2] = delta_phi_rad;
  values_.reserve(ai.nodes.size() * ao.nodes.size() * ap.nodes.size());
  for (std::size_t ci = 0; ci < ai.nodes.size(); ++ci) {
    for (std::size_t co = 0; co < ao.nodes.size(); ++co) {
      // cos(π/2) is 6e-17, not 0: the grazing nodes reflect nothing, exactly.
      const double cosines = ai.nodes[ci] >= 0.5 * kPi || ao.nodes[co] >= 0.5 * kPi
                                 ? 0.0
                                 : std::cos(ai.nodes[ci]) * std::cos(ao.nodes[co]);
      for (std::size_t p : ap.source) {
        const std::size_t given =
            (ai.source[ci] * theta_o_rad.size() + ao.source[co]) * delta_phi_rad.size() + p;
        values_.push_back(values_per_sr[given] * cosines);
      }
    }
  }
  width_rad_ = std::min({0.25 * kPi, halfFinestStep(theta_i_rad), halfFinestStep(theta_o_rad),
                         halfFinestStep(delta_phi_rad)});
  theta_i_ = ai.nodes;
  theta_o_ = ao.nodes;
  delta_phi_ = ap.nodes;
  buildEnvelope();
}

namespace {

// Where @p x falls on an axis for the monotone cubic: its cell k (clamped to the axis), the
// local coordinate t in [0, 1], and the Hermite weights of the four nodes k − 1 … k + 2
// once the data's slopes are known (pchip()).
struct Span {
  std::size_t k = 0;
  double t = 0.0;
};

Span span(const std::vector<double>& nodes, double x) {
  const auto [k, t] = locate(nodes, x);
  return {k, t};
}

// The monotone piecewise cubic (Fritsch–Butland slopes) through y[k−1 … k+2] on the nodes x,
// at local coordinate t of cell k. Each node's slope is the weighted harmonic mean of its two
// secants (0 where they differ in sign, one-sided at the axis' ends), at most 3× either
// secant: the cubic stays between y[k] and y[k+1] (de Boor & Swartz), which is what lets a
// cell be bounded by its corners, and is C¹, which is what lets the cubature rule converge.
double pchip(const std::vector<double>& x, std::size_t k, double t, const double* y_at_k_minus_1) {
  const std::size_t n = x.size();
  const double* y = y_at_k_minus_1 + 1;  // y[0] is node k
  const double h = x[k + 1] - x[k];
  const double s = (y[1] - y[0]) / h;
  const auto slope = [](double left_secant, double right_secant, double h_left, double h_right) {
    if (left_secant * right_secant <= 0.0) return 0.0;
    // Brodlie's weighting of the harmonic mean for unequal steps.
    const double w1 = (2.0 * h_right + h_left) / (3.0 * (h_left + h_right));
    const double w2 = (h_right + 2.0 * h_left) / (3.0 * (h_left + h_right));
    return 1.0 / (w1 / left_secant + w2 / right_secant);
  };
  double d0 = s, d1 = s;
  if (k > 0) {
    const double hl = x[k] - x[k - 1];
    d0 = slope((y[0] - y[-1]) / hl, s, hl, h);
  }
  if (k + 2 < n) {
    const double hr = x[k + 2] - x[k + 1];
    d1 = slope(s, (y[2] - y[1]) / hr, h, hr);
  }
  const double t2 = t * t, t3 = t2 * t;
  return (2 * t3 - 3 * t2 + 1) * y[0] + (t3 - 2 * t2 + t) * h * d0 + (-2 * t3 + 3 * t2) * y[1] +
         (t3 - t2) * h * d1;
}

}  // namespace

double BrdfTable::cosineWeightedAt(double theta_i_rad, double theta_o_rad,
                                   double delta_phi_rad) const {
  const Span si = span(theta_i_, theta_i_rad), so = span(theta_o_, theta_o_rad),
             sp = span(delta_phi_, std::abs(delta_phi_rad));
  // Along Δφ, then θo, then θi, each over the four nodes about the cell (clamped at the ends,
  // where pchip() does not read them).
  const auto clampIndex = [](std::size_t k, int offset, std::size_t n) {
    const long j = static_cast<long>(k) + offset;
    return static_cast<std::size_t>(std::clamp<long>(j, 0, static_cast<long>(n) - 1));
  };
  std::array<double, 4> along_i{};
  for (int a = -1; a <= 2; ++a) {
    const std::size_t i = clampIndex(si.k, a, theta_i_.size());
    std::array<double, 4> along_o{};
    for (int b = -1; b <= 2; ++b) {
      const std::size_t o = clampIndex(so.k, b, theta_o_.size());
      std::array<double, 4> along_p{};
      for (int c = -1; c <= 2; ++c)
        along_p[c + 1] = value(i, o, clampIndex(sp.k, c, delta_phi_.size()));
      along_o[b + 1] = pchip(delta_phi_, sp.k, sp.t, along_p.data());
    }
    along_i[a + 1] = pchip(theta_o_, so.k, so.t, along_o.data());
  }
  return std::max(0.0, pchip(theta_i_, si.k, si.t, along_i.data()));
}

double BrdfTable::brdf(double theta_i_rad, double theta_o_rad, double delta_phi_rad) const {
  const double cosines = std::cos(std::clamp(theta_i_rad, 0.0, 0.5 * kPi)) *
                         std::cos(std::clamp(theta_o_rad, 0.0, 0.5 * kPi));
  return cosines > 0.0 ? cosineWeightedAt(theta_i_rad, theta_o_rad, delta_phi_rad) / cosines : 0.0;
}

double BrdfTable::cosineWeighted(const Vec3& n, const Vec3& wi, const Vec3& wo, double cos_i,
                                 double cos_r) const {
  // The angles from the tangent-plane parts, exact near the normal where acos loses them.
  const Vec3 ti = wi - glm::dot(wi, n) * n, to = wo - glm::dot(wo, n) * n;
  const double theta_i = std::atan2(glm::length(ti), cos_i);
  const double theta_o = std::atan2(glm::length(to), cos_r);
  const double delta_phi = std::atan2(glm::length(glm::cross(ti, to)), glm::dot(ti, to));
  (void)cos_i;
  (void)cos_r;
  return cosineWeightedAt(theta_i, theta_o, delta_phi);
}

void BrdfTable::buildEnvelope() {
  // Each cell: its bound of f_r cos θi cos θr and the most its half vector can be tilted; and
  // in the coarse envelope, at the largest θN and the least θi and θo it reaches.
  std::vector<std::pair<double, double>> cells;  // (θN_max, bound)
  cells.reserve((theta_i_.size() - 1) * (theta_o_.size() - 1) * (delta_phi_.size() - 1));
  coarse_.assign(static_cast<std::size_t>(kCoarseLevels * kCoarseLevels * kCoarseLevels), 0.0);
  for (std::size_t i = 0; i + 1 < theta_i_.size(); ++i) {
    for (std::size_t o = 0; o + 1 < theta_o_.size(); ++o) {
      for (std::size_t p = 0; p + 1 < delta_phi_.size(); ++p) {
        double corner = 0.0;
        for (int k = 0; k < 8; ++k)
          corner = std::max(corner, value(i + (k & 1), o + (k >> 1 & 1), p + (k >> 2)));
        if (corner == 0.0) continue;
        const double bound = corner;
        // tan θN = |h_t| / h_z for h = ωi + ωo, h_z = cos θi + cos θo, and
        // |h_t|² = (sin θi − sin θo)² + 2 sin θi sin θo (1 + cos Δφ): two terms ≥ 0, each at
        // its largest over the cell on its own (sin rises and cos Δφ falls on the axes). Taken
        // together, as a cosine of θN, they would lose the terms' correlation, and near
        // θN = 0 acos turns a small slack in cos θN into a large one in θN.
        const double si0 = std::sin(theta_i_[i]), si1 = std::sin(theta_i_[i + 1]);
        const double so0 = std::sin(theta_o_[o]), so1 = std::sin(theta_o_[o + 1]);
        const double apart = std::max(std::abs(si1 - so0), std::abs(si0 - so1));
        const double ht2 = apart * apart + 2.0 * si1 * so1 * (1.0 + std::cos(delta_phi_[p]));
        const double hz = std::cos(theta_i_[i + 1]) + std::cos(theta_o_[o + 1]);
        const double theta_n_max = hz > 0.0 ? std::atan(std::sqrt(ht2) / hz) : 0.5 * kPi;
        cells.emplace_back(theta_n_max, bound);
        double& at = coarse_[coarseIndex(theta_n_max, theta_i_[i], theta_o_[o])];
        at = std::max(at, bound);
      }
    }
  }
  // Each entry becomes the largest over every cell at or beyond its θN level, and at or below
  // its θi and θo levels.
  const auto at = [](int n, int i, int o) {
    return static_cast<std::size_t>((n * kCoarseLevels + i) * kCoarseLevels + o);
  };
  for (int n = kCoarseLevels - 1; n >= 0; --n) {
    for (int i = 0; i < kCoarseLevels; ++i) {
      for (int o = 0; o < kCoarseLevels; ++o) {
        double& m = coarse_[at(n, i, o)];
        if (n + 1 < kCoarseLevels) m = std::max(m, coarse_[at(n + 1, i, o)]);
        if (i > 0) m = std::max(m, coarse_[at(n, i - 1, o)]);
        if (o > 0) m = std::max(m, coarse_[at(n, i, o - 1)]);
      }
    }
  }
  std::sort(cells.begin(), cells.end(),
            [](const auto& a, const auto& b) { return a.first > b.first; });
  // The envelope only needs the cells where the running largest bound grows, each at the θN
  // where it first does: every tilt at or below that θN may meet that cell.
  double largest = 0.0;
  for (const auto& [theta_n, bound] : cells) {
    if (bound > largest) {
      largest = bound;
      envelope_theta_n_.push_back(theta_n);
      envelope_max_.push_back(largest);
    }
  }
}

std::size_t BrdfTable::coarseIndex(double theta_n, double theta_i, double theta_o) {
  const auto level = [](double x, bool nan_high) {
    if (std::isnan(x)) return nan_high ? kCoarseLevels - 1 : 0;
    const double l = x > 0.0 ? std::floor(x / (0.5 * kPi) * kCoarseLevels) : 0.0;
    return static_cast<int>(std::min(l, static_cast<double>(kCoarseLevels - 1)));
  };
  // A NaN takes the level where every cell counts: the least θN, the largest θi and θo.
  return static_cast<std::size_t>((level(theta_n, false) * kCoarseLevels + level(theta_i, true)) *
                                      kCoarseLevels +
                                  level(theta_o, true));
}

double BrdfTable::maxBeyond(double tan2_min, double theta_i_max_rad, double theta_o_max_rad) const {
  if (envelope_max_.empty()) return 0.0;
  if (!(tan2_min >= 0.0)) return envelope_max_.back();
  const double theta_n = std::atan(std::sqrt(tan2_min));
  // The cells that may hold a half vector tilted by θN or more are the first ones.
  const auto end = std::partition_point(envelope_theta_n_.begin(), envelope_theta_n_.end(),
                                        [&](double t) { return t >= theta_n; });
  if (end == envelope_theta_n_.begin()) return 0.0;
  const double by_tilt =
      envelope_max_[static_cast<std::size_t>(end - envelope_theta_n_.begin()) - 1];
  // The coarse envelope rounds each angle down to its level: it takes every cell reaching the
  // tilt and within the angles, and some a level beyond, so it too is an upper bound.
  return std::min(by_tilt, coarse_[coarseIndex(theta_n, theta_i_max_rad, theta_o_max_rad)]);
}

double BrdfTable::grazingFactor(double theta_i_min_rad, double theta_o_min_rad) const {
  // On the last cell [π/2 − h, π/2], with u = (π/2 − θ) / h, the cubic from g₀ to 0 is
  // g₀ u [u (3 − 2u) − α u (1 − u) + (1 − u)²] for the start slope −α g₀ / h, α ∈ [0, 3]:
  // at most g₀ u (1 + u − u²) ≤ 1.25 g₀ u. Along θo it holds at each θi node, and the θi cubic
  // stays between its cell's two nodes; along θi it holds of the θi cubic itself.
  const auto factor = [](double theta_min, const std::vector<double>& axis) {
    if (!(theta_min >= 0.0)) return 1.0;  // a NaN proves nothing
    const double last_step = axis.back() - axis[axis.size() - 2];
    const double u = (0.5 * kPi - theta_min) / last_step;
    return std::clamp(1.25 * u, 0.0, 1.0);
  };
  return factor(theta_i_min_rad, theta_i_) * factor(theta_o_min_rad, theta_o_);
}

template <class Brdf>
double BrdfTable::overOutgoing(Brdf&& brdf_at) const {
  // ∫∫ f cos θo sin θo dθo dΔφ over θo in [0, π/2] and Δφ in [−π, π], twice the half Δφ ≥ 0,
  // cell by cell of the grid: there the interpolant is a cubic in each angle, so 4 × 4
  // Gauss–Legendre (exact to degree 7) leaves the error on its product with sin θo / cos θi,
  // under 1e-9 for cells of 15°.
  double sum = 0.0;
  for (std::size_t o = 0; o + 1 < theta_o_.size(); ++o) {
    const double ho = 0.5 * (theta_o_[o + 1] - theta_o_[o]), mo = theta_o_[o] + ho;
    for (std::size_t p = 0; p + 1 < delta_phi_.size(); ++p) {
      const double hp = 0.5 * (delta_phi_[p + 1] - delta_phi_[p]), mp = delta_phi_[p] + hp;
      for (int a = 0; a < 4; ++a) {
        const double theta_o = mo + ho * kGaussNode[a];
        const double weight_o = kGaussWeight[a] * ho * 0.5 * std::sin(2.0 * theta_o);
        for (int c = 0; c < 4; ++c) {
          sum += weight_o * kGaussWeight[c] * hp * brdf_at(theta_o, mp + hp * kGaussNode[c]);
        }
      }
    }
  }
  return 2.0 * sum;
}

double BrdfTable::hemisphericalReflectance(double theta_i_rad) const {
  // ∫ f cos θo dω = ∫ g sin θo dθo dΔφ / cos θi, g = f cos θi cos θo the interpolant.
  const double cos_i = std::cos(theta_i_rad);
  if (!(cos_i > 0.0) || theta_i_rad >= 0.5 * kPi) return 0.0;
  return overOutgoing([&](double theta_o, double phi) {
    const double cos_o = std::cos(theta_o);
    return cos_o > 0.0 ? cosineWeightedAt(theta_i_rad, theta_o, phi) / (cos_i * cos_o) : 0.0;
  });
}

BrdfTable::Reflectance BrdfTable::maxHemisphericalReflectance() const {
  // At every node of θi below grazing and at three points between each two: the interpolant
  // is a cubic in θi, so the reflectance varies smoothly between nodes.
  Reflectance best;
  for (std::size_t i = 0; i + 1 < theta_i_.size(); ++i) {
    for (int q = 0; q < 4; ++q) {
      const double theta_i = theta_i_[i] + 0.25 * q * (theta_i_[i + 1] - theta_i_[i]);
      const double r = hemisphericalReflectance(theta_i);
      if (r > best.value) best = {r, theta_i};
    }
  }
  return best;
}

}  // namespace glint
