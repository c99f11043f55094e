#include "hazard/exposure_train.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "facets/sum.h"

namespace glint {
namespace {

// The irradiance at @p x on the linear piece from sample k to k + 1.
double irradianceAt(std::span<const double> t, std::span<const double> e, std::size_t k, double x) {
  const double dt = t[k + 1] - t[k];
  if (!(dt > 0.0)) return e[k];
  return e[k] + (e[k + 1] - e[k]) * std::clamp((x - t[k]) / dt, 0.0, 1.0);
}

// The history from @p a to @p b (within its span, a < b): the irradiance at both ends and its
// samples between, 0 outside as the windows take it.
struct Clipped {
  std::vector<double> time_s, irradiance_w_m2;
};

Clipped clip(std::span<const double> t, std::span<const double> e, double a, double b) {
  const std::size_t last_piece = t.size() - 2;
  const auto first_after =
      static_cast<std::size_t>(std::upper_bound(t.begin(), t.end(), a) - t.begin());
  const auto at_or_before_b =
      static_cast<std::size_t>(std::upper_bound(t.begin(), t.end(), b) - t.begin());
  Clipped c;
  c.time_s.push_back(a);
  c.irradiance_w_m2.push_back(irradianceAt(t, e, std::min(first_after - 1, last_piece), a));
  for (std::size_t i = first_after; i < t.size() && t[i] < b; ++i) {
    c.time_s.push_back(t[i]);
    c.irradiance_w_m2.push_back(e[i]);
  }
  c.time_s.push_back(b);
  c.irradiance_w_m2.push_back(irradianceAt(t, e, std::min(at_or_before_b - 1, last_piece), b));
  return c;
}

double trapezoids(const Clipped& c) {
  CompensatedSum sum;
  for (std::size_t i = 1; i < c.time_s.size(); ++i) {
    sum.add(0.5 * (c.irradiance_w_m2[i - 1] + c.irradiance_w_m2[i]) *
            (c.time_s[i] - c.time_s[i - 1]));
  }
  return sum.value();
}

// What the piecewise-linear irradiance @p c delivers while at or above @p level_w_m2 (J/m²).
double exposureAtOrAbove(const Clipped& c, double level_w_m2) {
  CompensatedSum sum;
  for (std::size_t i = 1; i < c.time_s.size(); ++i) {
    const double e0 = c.irradiance_w_m2[i - 1], e1 = c.irradiance_w_m2[i];
    const double dt = c.time_s[i] - c.time_s[i - 1];
    const bool in0 = e0 >= level_w_m2, in1 = e1 >= level_w_m2;
    if (in0 && in1) {
      sum.add(0.5 * (e0 + e1) * dt);
    } else if (in0 != in1) {
      // The piece crosses the level once: the trapezoid on its high side.
      const double cross = (level_w_m2 - e0) / (e1 - e0);
      sum.add(0.5 * (level_w_m2 + (in0 ? e0 : e1)) * (in0 ? cross : 1.0 - cross) * dt);
    }
  }
  return sum.value();
}

// The intervals where the piecewise-linear irradiance is above @p threshold_w_m2.
struct Interval {
  double start_s, end_s;
};

std::vector<Interval> intervalsAbove(std::span<const double> t, std::span<const double> e,
                                     double threshold_w_m2) {
  std::vector<Interval> found;
  bool inside = e[0] > threshold_w_m2;
  double start = t[0];
  auto close = [&](double end) {
    if (end > start) found.push_back({start, end});
    inside = false;
  };
  for (std::size_t k = 0; k + 1 < t.size(); ++k) {
    const double e0 = e[k], e1 = e[k + 1], dt = t[k + 1] - t[k];
    const bool above = e1 > threshold_w_m2;
    if (!inside && above) {
      // e0 ≤ threshold < e1: the piece crosses it once, rising.
      start = t[k] + (threshold_w_m2 - e0) / (e1 - e0) * dt;
      inside = true;
    } else if (inside && !above) {
      close(e0 > e1 ? t[k] + (e0 - threshold_w_m2) / (e0 - e1) * dt : t[k + 1]);
    }
  }
  if (inside) close(t.back());
  return found;
}

// Pulses a whole t_min or a whole counting span apart, which the standards count apart, may
// lie a rounding closer: spans are shortened by this factor.
constexpr double kRounding = 1.0 - 1e-9;

// The table's durations: a pulse's is kept inside them.
double tableDurationS(double duration_s) { return std::clamp(duration_s, 1e-9, 3e4); }

// A pulse as the standards read one: all its energy against the single-pulse MPE for its
// duration at half its peak (a group's: t_min or its span). glint judges every varying exposure
// by its worst window; a pulse is held to both readings, the larger kept: for a smooth crossing
// this one is the larger (a gaussian keeps 76 % of its energy within its half-peak time, and its
// windows reach about 0.79 of this ratio). Only a compact pulse, at least half of whose energy
// comes while it is at or above half its peak, is read so: above a low threshold a glint and
// the faint light about it count as one long "pulse" whose energy is nearly all outside its
// half-peak time, which the standards' reading was never meant for (the glint alone is a pulse
// at a higher threshold). 0 where it does not apply, or for a pulse longer than the exposure.
double halfPeakRatio(const HistoryPulse& p, const HazardSpec& hazard, double longest_s) {
  if (!(p.duration_s > 0.0) || p.duration_s > longest_s) return 0.0;
  if (!(p.half_peak_exposure_j_m2 >= 0.5 * p.exposure_j_m2)) return 0.0;
  return p.exposure_j_m2 / tableMpe(hazard.wavelength_nm, tableDurationS(p.duration_s),
                                    hazard.standard, hazard.tissue)
                               .radiant_exposure_j_m2;
}

// The pulses at one threshold and what rule 3 counts of them.
struct Level {
  double threshold_w_m2 = 0.0;
  std::vector<HistoryPulse> pulses;
  std::int64_t counted = 0;
  bool grouped = false;
};

}  // namespace

std::vector<HistoryPulse> historyPulses(std::span<const double> time_s,
                                        std::span<const double> irradiance_w_m2,
                                        double threshold_w_m2, double grouping_s) {
  std::vector<HistoryPulse> pulses;
  if (time_s.size() < 2) return pulses;
  const std::vector<Interval> above = intervalsAbove(time_s, irradiance_w_m2, threshold_w_m2);
  for (std::size_t i = 0; i < above.size();) {
    // Pulses that start within t_min of the group's first act on the retina as one (a pulse
    // t_min after it, to rounding, starts a group of its own).
    std::size_t j = i + 1;
    while (j < above.size() && above[j].start_s - above[i].start_s < grouping_s * kRounding) ++j;
    HistoryPulse p;
    p.start_s = above[i].start_s;
    p.end_s = above[j - 1].end_s;
    p.members = static_cast<int>(j - i);
    const Clipped c = clip(time_s, irradiance_w_m2, p.start_s, p.end_s);
    p.exposure_j_m2 = trapezoids(c);
    if (p.members > 1) {
      p.duration_s = std::max(grouping_s, p.end_s - p.start_s);
      p.half_peak_exposure_j_m2 = p.exposure_j_m2;
    } else {
      const double peak = *std::max_element(c.irradiance_w_m2.begin(), c.irradiance_w_m2.end());
      p.duration_s = timeAtOrAbove(c.time_s, c.irradiance_w_m2, 0.5 * peak);
      p.half_peak_exposure_j_m2 = exposureAtOrAbove(c, 0.5 * peak);
    }
    pulses.push_back(p);
    i = j;
  }
  return pulses;
}

double weightedPulsesWithin(const std::vector<HistoryPulse>& pulses,
                            const std::vector<double>& weights, double span_s) {
  double most = 0.0, sum = 0.0;
  std::size_t j = 0;
  for (std::size_t i = 0; i < pulses.size(); ++i) {
    if (j < i) j = i, sum = 0.0;
    while (j < pulses.size() && pulses[j].start_s - pulses[i].start_s < span_s * kRounding)
      sum += weights[j++];
    most = std::max(most, sum);
    sum -= weights[i];
  }
  return most;
}

std::int64_t pulsesWithin(const std::vector<HistoryPulse>& pulses, double span_s) {
  // Sums of ones are exact: the count is the weighted one with every weight 1.
  return static_cast<std::int64_t>(
      weightedPulsesWithin(pulses, std::vector<double>(pulses.size(), 1.0), span_s));
}

TrainHazard judgeTrain(std::span<const double> time_s, std::span<const double> irradiance_w_m2,
                       const HazardSpec& hazard, double longest_s, double floor_w_m2,
                       double window_ratio) {
  TrainHazard best;
  best.reduction_name = clauses(hazard.standard).rule_three_factor;
  if (time_s.size() < 2) return best;
  const double peak = *std::max_element(irradiance_w_m2.begin(), irradiance_w_m2.end());
  // A floor of 0 (which the scene never gives) would never end the doublings: a millionth of
  // the peak then stands for it.
  if (!(floor_w_m2 > 0.0)) floor_w_m2 = 1e-6 * peak;
  if (!(peak > floor_w_m2)) return best;
  const double nm = hazard.wavelength_nm;
  const double grouping_s = pulseGroupingS(nm, hazard.tissue);
  const double counting_s = ruleThreeCountingS(hazard.standard, longest_s);
  auto level = [&](double threshold_w_m2) {
    Level l;
    l.threshold_w_m2 = threshold_w_m2;
    l.pulses = historyPulses(time_s, irradiance_w_m2, threshold_w_m2, grouping_s);
    l.counted = pulsesWithin(l.pulses, counting_s);
    l.grouped = std::any_of(l.pulses.begin(), l.pulses.end(),
                            [](const HistoryPulse& p) { return p.members > 1; });
    return l;
  };
  // The floor and every doubling of it below the peak: a glint on light that never falls to
  // the floor separates from its neighbours above it.
  std::vector<Level> levels{level(floor_w_m2)};
  best.pulses = levels.front().counted;
  best.threshold_w_m2 = floor_w_m2;
  best.grouped = levels.front().grouped;
  best.spans = levels.front().pulses;
  // Rule 1 as the standards read a pulse, wherever the limits apply (rule 3 or not).
  const HistoryPulse* loudest = nullptr;
  for (const HistoryPulse& p : levels.front().pulses) {
    const double ratio = halfPeakRatio(p, hazard, longest_s);
    if (ratio > best.ratio) {
      best.ratio = ratio;
      loudest = &p;
    }
  }
  if (loudest != nullptr) {
    best.pulse_ratio = best.ratio;
    best.by_half_peak = true;
    best.effective_pulses = 1.0;
    const Clipped c = clip(time_s, irradiance_w_m2, loudest->start_s, loudest->end_s);
    best.pulse = worstWindow(c.time_s, c.irradiance_w_m2, hazard,
                             std::min(longest_s, loudest->end_s - loudest->start_s));
    best.pulse_duration_s = loudest->duration_s;
    best.pulse_exposure_j_m2 = loudest->exposure_j_m2;
  }
  // Rule 3 is the retina's: nothing beyond 1400 nm or for the skin.
  if (!ruleThreeApplies(nm, hazard.tissue, MpeLimit::Thermal)) return best;
  for (double threshold = 2.0 * floor_w_m2; threshold < peak; threshold *= 2.0)
    levels.push_back(level(threshold));

  // Rule 3's reduction of pulse p when @p counted are counted (1 where it does not apply).
  auto reduction = [&](const HistoryPulse& p, double counted) {
    const double d = tableDurationS(p.duration_s);
    if (!ruleThreeApplies(nm, hazard.tissue, tableMpe(nm, d, hazard.standard, hazard.tissue).limit))
      return 1.0;
    return ruleThreeReduction(hazard.standard, nm, d, counted);
  };
  // Every pulse's worst window is at most the history's (its windows are the history's, less
  // the light outside it, and no longer), and a pulse above a higher threshold lies within one
  // above a lower: where neither threshold groups pulses, its worst window is at most the
  // largest found at the lower. A threshold whose bound cannot beat what holds is skipped.
  double nested_bound = std::numeric_limits<double>::infinity();
  for (std::size_t li = 0; li < levels.size(); ++li) {
    const Level& l = levels[li];
    if (l.pulses.empty()) continue;
    // The half-peak reading is cheap: its part of the bound is exact.
    double smallest_reduction = 1.0, half_peak = 0.0;
    for (const HistoryPulse& p : l.pulses) {
      const double c = reduction(p, static_cast<double>(l.counted));
      smallest_reduction = std::min(smallest_reduction, c);
      half_peak = std::max(half_peak, halfPeakRatio(p, hazard, longest_s) / c);
    }
    const double pulse_bound = l.grouped ? window_ratio : std::min(window_ratio, nested_bound);
    if (li > 0 && std::max(pulse_bound / smallest_reduction, half_peak) <=
                      std::max(best.ratio, window_ratio)) {
      continue;
    }
    // Each pulse against the single-pulse MPE (the larger of its two readings).
    double largest_window = 0.0;
    std::vector<double> ratios(l.pulses.size());
    std::vector<WindowHazard> windows(l.pulses.size());
    std::vector<char> by_half_peak(l.pulses.size(), 0);
    std::size_t strongest = 0;
    for (std::size_t k = 0; k < l.pulses.size(); ++k) {
      const HistoryPulse& p = l.pulses[k];
      // The single pulse's own windows: up to its duration, a group's t_min (its energy against
      // the MPE for t_min), never beyond the exposure.
      const double longest =
          std::min(longest_s,
                   p.members > 1 ? std::max(grouping_s, p.end_s - p.start_s) : p.end_s - p.start_s);
      const Clipped clipped = clip(time_s, irradiance_w_m2, p.start_s, p.end_s);
      windows[k] = worstWindow(clipped.time_s, clipped.irradiance_w_m2, hazard, longest);
      largest_window = std::max(largest_window, windows[k].ratio);
      const double half_peak_ratio = halfPeakRatio(p, hazard, longest_s);
      ratios[k] = std::max(windows[k].ratio, half_peak_ratio);
      by_half_peak[k] = half_peak_ratio > windows[k].ratio ? 1 : 0;
      if (ratios[k] > ratios[strongest]) strongest = k;
    }
    if (!l.grouped) nested_bound = std::min(nested_bound, largest_window);
    // The train as so many pulses as strong as its strongest, each weighed by its share of it
    // to the fourth power: the weighing under which rule 3's N^-1/4 is exact.
    const double r_max = ratios[strongest];
    if (!(r_max > 0.0)) continue;
    std::vector<double> weights(l.pulses.size());
    for (std::size_t k = 0; k < l.pulses.size(); ++k) weights[k] = std::pow(ratios[k] / r_max, 4);
    const double effective = weightedPulsesWithin(l.pulses, weights, counting_s);
    const double c = reduction(l.pulses[strongest], effective);
    const double ratio = r_max / c;
    if (ratio > best.ratio) {
      const HistoryPulse& p = l.pulses[strongest];
      best.ratio = ratio;
      best.pulse_ratio = r_max;
      best.by_half_peak = by_half_peak[strongest] != 0;
      best.pulses = l.counted;
      best.effective_pulses = effective;
      best.reduction = c;
      best.threshold_w_m2 = l.threshold_w_m2;
      best.grouped = l.grouped;
      best.pulse = windows[strongest];
      best.pulse_duration_s = p.duration_s;
      best.pulse_exposure_j_m2 = p.exposure_j_m2;
      best.spans = l.pulses;
    }
  }
  return best;
}

ExposureVerdict judgeExposure(std::span<const double> time_s,
                              std::span<const double> irradiance_w_m2, double peak_w_m2,
                              const HazardSpec& hazard, double longest_s, double floor_w_m2) {
  ExposureVerdict v;
  v.worst_window = worstWindow(time_s, irradiance_w_m2, hazard, longest_s);
  v.train =
      judgeTrain(time_s, irradiance_w_m2, hazard, longest_s, floor_w_m2, v.worst_window.ratio);
  if (v.train.ratio > v.worst_window.ratio) {
    // A pulse read at its half-peak duration alone (reduction 1) is rule 1's.
    v.ratio = v.train.ratio;
    // A train whose others weigh next to nothing against its strongest pulse (a faint glimmer
    // beside a glint) is that pulse's rule 1.
    v.rule = v.train.reduction < 1.0 - 1e-6 ? DecidingRule::Train : DecidingRule::SinglePulse;
  } else if (v.worst_window.ratio > 0.0) {
    v.ratio = v.worst_window.ratio;
    // Rule 1 where the worst window holds the light of one pulse (or one unbroken exposure)
    // above the floor, rule 2 where it gathers several.
    const double grouping_s = pulseGroupingS(hazard.wavelength_nm, hazard.tissue);
    const double s = v.worst_window.start_s, e = s + v.worst_window.duration_s;
    int overlapped = 0;
    for (const HistoryPulse& p : historyPulses(time_s, irradiance_w_m2, floor_w_m2, grouping_s))
      overlapped += p.start_s < e && p.end_s > s ? 1 : 0;
    v.rule = overlapped > 1 ? DecidingRule::Average : DecidingRule::SinglePulse;
  }
  v.aided_ratio = v.ratio * hazard.aidGain();
  v.time_above_mpe_s = timeAtOrAbove(time_s, irradiance_w_m2, hazard.mpe_w_m2);
  for (const ExposureLevel& l : hazard.levels)
    v.time_above_level_s.push_back(timeAtOrAbove(time_s, irradiance_w_m2, l.thresholdW_m2()));
  v.stare_ratio = hazard.ratio(peak_w_m2);
  return v;
}

const char* toString(DecidingRule rule) {
  switch (rule) {
    case DecidingRule::SinglePulse:
      return "rule 1";
    case DecidingRule::Average:
      return "rule 2";
    case DecidingRule::Train:
      return "rule 3";
    case DecidingRule::None:
      break;
  }
  return "none";
}

}  // namespace glint
