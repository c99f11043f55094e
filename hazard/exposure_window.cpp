#include "hazard/exposure_window.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "facets/sum.h"

namespace glint {
namespace {

// The piecewise-linear irradiance through the samples and its running integral.
class History {
 public:
  History(std::span<const double> t, std::span<const double> e) : t_(t), e_(e), f_(t.size(), 0.0) {
    CompensatedSum sum;
    for (std::size_t i = 1; i < t.size(); ++i) {
      sum.add(0.5 * (e[i - 1] + e[i]) * (t[i] - t[i - 1]));
      f_[i] = sum.value();
    }
  }
  [[nodiscard]] double irradiance(double x) const {
    const std::size_t k = segment(x);
    return e_[k] + (e_[k + 1] - e_[k]) * fraction(k, x);
  }
  // ∫ from the first sample to x (exact for the linear pieces).
  [[nodiscard]] double integral(double x) const {
    const std::size_t k = segment(x);
    return f_[k] + 0.5 * (e_[k] + irradiance(x)) * (x - t_[k]);
  }
  [[nodiscard]] double total() const { return f_.back(); }

 private:
  [[nodiscard]] std::size_t segment(double x) const {
    const auto after = std::upper_bound(t_.begin(), t_.end(), x);
    const auto k = static_cast<std::size_t>(after - t_.begin());
    return std::min(k == 0 ? 0 : k - 1, t_.size() - 2);
  }
  [[nodiscard]] double fraction(std::size_t k, double x) const {
    const double dt = t_[k + 1] - t_[k];
    return dt > 0.0 ? std::clamp((x - t_[k]) / dt, 0.0, 1.0) : 0.0;
  }
  std::span<const double> t_, e_;
  std::vector<double> f_;
};

// The shortest duration the MPE tables cover (tableMpe()).
constexpr double kShortestS = 1e-9;

}  // namespace

WindowExposure largestWindowExposure(std::span<const double> time_s,
                                     std::span<const double> irradiance_w_m2, double duration_s) {
  const std::size_t n = time_s.size();
  if (n < 2) return {0.0, n == 1 ? time_s[0] : 0.0};
  const History h(time_s, irradiance_w_m2);
  const double first = time_s.front(), last = time_s.back();
  // The irradiance is 0 outside the span, so a window at least as long holds all of it, and a
  // shorter one collects most inside it.
  if (duration_s >= last - first) return {h.total(), first};
  const double latest = last - duration_s;
  // G(s) = F(s + t) − F(s) is quadratic between the places where s or s + t meets a sample,
  // its slope E(s + t) − E(s) linear there: its largest value is at one of those places or
  // where that slope falls through 0.
  std::vector<double> starts;
  starts.reserve(2 * n);
  for (double t : time_s) {
    if (t <= latest) starts.push_back(t);
    if (t - duration_s >= first) starts.push_back(t - duration_s);
  }
  std::sort(starts.begin(), starts.end());
  auto window = [&](double s) { return h.integral(s + duration_s) - h.integral(s); };
  auto slope = [&](double s) { return h.irradiance(s + duration_s) - h.irradiance(s); };
  WindowExposure best{window(starts.front()), starts.front()};
  auto consider = [&](double s) {
    const double g = window(s);
    if (g > best.exposure_j_m2) best = {g, s};
  };
  for (std::size_t i = 0; i < starts.size(); ++i) {
    consider(starts[i]);
    if (i + 1 == starts.size() || !(starts[i + 1] > starts[i])) continue;
    // Inside (a, b) both ends of the window stay on one linear piece each.
    const double a = starts[i], b = starts[i + 1];
    const double eps = 1e-12 * (b - a);
    const double da = slope(a + eps), db = slope(b - eps);
    if (da > 0.0 && db < 0.0) consider(a + (b - a) * da / (da - db));
  }
  return best;
}

WindowHazard worstWindow(std::span<const double> time_s, std::span<const double> irradiance_w_m2,
                         const HazardSpec& hazard, double longest_s) {
  struct Point {
    double duration_s, exposure_j_m2, mpe_j_m2, start_s;
  };
  auto at = [&](double duration) {
    const WindowExposure w = largestWindowExposure(time_s, irradiance_w_m2, duration);
    const Mpe mpe = tableMpe(hazard.wavelength_nm, duration, hazard.standard, hazard.tissue);
    return Point{duration, w.exposure_j_m2, mpe.radiant_exposure_j_m2, w.start_s};
  };
  const double lo = kShortestS, hi = std::max(longest_s, kShortestS);
  // A first look four times a decade and at every edge of the table's rows, then every
  // bracket that could still hold a larger ratio is split. Both H_max(t) and, within a row, the
  // MPE as radiant exposure grow with t (mpeRowEdgesS()), so over a bracket [a, b] that no edge
  // divides the ratio is at most H_max(b) / MPE(a): a bound, however the power laws run between.
  const int first_points = std::max(2, static_cast<int>(std::ceil(4.0 * std::log10(hi / lo))) + 1);
  std::vector<double> durations;
  for (int i = 0; i < first_points; ++i) {
    const double f = static_cast<double>(i) / (first_points - 1);
    durations.push_back(i + 1 == first_points ? hi : lo * std::pow(hi / lo, f));
  }
  for (double edge : mpeRowEdgesS()) {
    if (edge > lo && edge < hi) durations.push_back(edge);
  }
  std::sort(durations.begin(), durations.end());
  std::vector<Point> points;
  for (double d : durations) points.push_back(at(d));
  WindowHazard worst;
  auto found = [&](const Point& p) {
    const double r = p.exposure_j_m2 / p.mpe_j_m2;
    if (r > worst.ratio || worst.duration_s == 0.0) {
      worst = {r, p.duration_s, p.start_s, p.exposure_j_m2, p.mpe_j_m2};
    }
  };
  for (const Point& p : points) found(p);
  std::vector<std::pair<Point, Point>> brackets;
  for (std::size_t i = 0; i + 1 < points.size(); ++i)
    brackets.emplace_back(points[i], points[i + 1]);
  double bound = 0.0;
  constexpr double kResolution = 1e-3;
  while (!brackets.empty()) {
    const auto [a, b] = brackets.back();
    brackets.pop_back();
    const double upper = b.exposure_j_m2 / a.mpe_j_m2;
    if (upper <= worst.ratio * (1.0 + kResolution) || b.duration_s <= a.duration_s * (1.0 + 1e-9)) {
      bound = std::max(bound, upper);
      continue;
    }
    const Point m = at(std::sqrt(a.duration_s * b.duration_s));
    found(m);
    brackets.emplace_back(a, m);
    brackets.emplace_back(m, b);
  }
  // The bound of every bracket closed against the largest ratio then known: the largest at
  // most kResolution above the largest found since.
  worst.ratio = std::max(worst.ratio, std::min(bound, worst.ratio * (1.0 + kResolution)));
  return worst;
}

double timeAtOrAbove(std::span<const double> time_s, std::span<const double> irradiance_w_m2,
                     double threshold_w_m2) {
  CompensatedSum above;
  for (std::size_t i = 1; i < time_s.size(); ++i) {
    const double e0 = irradiance_w_m2[i - 1], e1 = irradiance_w_m2[i];
    const double dt = time_s[i] - time_s[i - 1];
    const bool in0 = e0 >= threshold_w_m2, in1 = e1 >= threshold_w_m2;
    if (in0 && in1) {
      above.add(dt);
    } else if (in0 != in1) {
      // The linear piece crosses the threshold once: the part on its high side.
      const double cross = (threshold_w_m2 - e0) / (e1 - e0);
      above.add(in0 ? cross * dt : (1.0 - cross) * dt);
    }
  }
  return above.value();
}

}  // namespace glint
