#pragma once
/// @file
/// @brief An exposure that varies in time judged as a train of pulses, and the verdict that
/// joins the repetitive-pulse rules over it. A target that turns or vibrates sends its glint
/// across an eye again and again, and to the eye that is a pulse train (ANSI Z136.1-2014 8.2.3,
/// IEC 60825-1:2014 A.3; docs/hazard.md, "A train of glints"). The separate exposures of an
/// irradiance history are counted and rule 3 of the repetitive-pulse rules applied to them;
/// rules 1 and 2 are the worst window's (hazard/exposure_window.h).
///
/// Each pulse is read two ways against the single-pulse MPE, the larger kept: its worst window,
/// and the standards' reading of a pulse, all its energy against the MPE for its duration at
/// half its peak. The standards write rule 3 for identical pulses; glints are not. glint judges
/// a train as N_eff pulses as strong as its strongest, N_eff = Σ (r_i / r_max)⁴ over its pulses'
/// ratios r_i: the weighing under which rule 3's N^-1/4 law is exact (identical pulses give
/// N_eff = N, the standards' own count), so that a faint glimmer beside a glint adds next to
/// nothing while ten equal glints count as ten.

#include <cstdint>
#include <span>
#include <vector>

#include "hazard/exposure_window.h"

namespace glint {

/// @brief One separate exposure of a history: where the irradiance rises above a threshold
/// and falls back to it, or a group of such pulses closer than t_min (T_i) counted as one.
struct HistoryPulse {
  double start_s = 0.0;        ///< where it rises above the threshold (a group: its first pulse's)
  double end_s = 0.0;          ///< where it falls back (a group: its last pulse's)
  double exposure_j_m2 = 0.0;  ///< ∫E dt from start to end, the light between grouped pulses too
  /// Its duration as the standards define it: the time at or above half its peak; a group's,
  /// t_min or its span if longer.
  double duration_s = 0.0;
  /// What it delivers while at or above half its peak (a group: all of it): how compact it is.
  double half_peak_exposure_j_m2 = 0.0;
  int members = 1;  ///< pulses counted as this one (more than 1: grouped)
};

/// @brief The pulses of the irradiance piecewise linear through (@p time_s,
/// @p irradiance_w_m2): the intervals where it is above @p threshold_w_m2, those starting
/// less than @p grouping_s after a group's first grouped with it (0: none grouped), in time
/// order.
std::vector<HistoryPulse> historyPulses(std::span<const double> time_s,
                                        std::span<const double> irradiance_w_m2,
                                        double threshold_w_m2, double grouping_s);

/// @brief The most pulses whose starts lie in any interval [s, s + @p span_s) (the starts
/// increasing): the n or N rule 3 counts.
std::int64_t pulsesWithin(const std::vector<HistoryPulse>& pulses, double span_s);

/// @brief The largest sum of @p weights (one per pulse) over the pulses whose starts lie in any
/// interval [s, s + @p span_s): pulsesWithin() with each pulse counted by its weight.
double weightedPulsesWithin(const std::vector<HistoryPulse>& pulses,
                            const std::vector<double>& weights, double span_s);

/// @brief Rule 3 of an irradiance history's train of pulses.
struct TrainHazard {
  /// The largest over the pulses of each one's worst window against the single-pulse MPE times
  /// its reduction (ANSI's C_P, IEC's C5), at the threshold where that is largest; 0 where
  /// rule 3 does not apply (the skin, beyond 1400 nm) or nothing is above the floor.
  double ratio = 0.0;
  /// The pulses (or groups) counted: n over the longest window (ANSI), N within T2 (IEC),
  /// at that threshold.
  std::int64_t pulses = 0;
  /// What the reduction counts: the pulses as so many as strong as the strongest, each weighed
  /// by (its ratio / the strongest's)⁴ (pulses for identical pulses).
  double effective_pulses = 0.0;
  double reduction = 1.0;              ///< C_P or C5 of the pulse that sets the ratio
  const char* reduction_name = "C_P";  ///< StandardClauses::rule_three_factor
  double threshold_w_m2 = 0.0;         ///< the irradiance the pulses were counted above
  bool grouped = false;                ///< some pulses closer than t_min were counted as one
  /// The pulse that sets the ratio (its own worst window and its duration, at or above half
  /// its peak).
  WindowHazard pulse;
  /// That pulse against the single-pulse MPE, before the reduction: the larger of its worst
  /// window's ratio and the standards' reading of a pulse, all its energy against the MPE for
  /// its half-peak duration (see by_half_peak).
  double pulse_ratio = 0.0;
  bool by_half_peak = false;  ///< the half-peak reading set pulse_ratio
  double pulse_duration_s = 0.0;
  double pulse_exposure_j_m2 = 0.0;  ///< all it delivers, from where it rises to where it falls
  /// Every pulse (or group) at that threshold, in time order: what the time series marks.
  std::vector<HistoryPulse> spans;
};

/// @brief Rule 3 of the history (@p time_s, @p irradiance_w_m2) under @p hazard's wavelength,
/// standard and tissue, for an exposure of @p longest_s at most. The pulses are counted above
/// the floor @p floor_w_m2 and above every doubling of it below the peak, and the threshold
/// that gives the largest ratio is kept: a glint riding on light that never falls to the floor
/// is still a pulse of its own. Thresholds that cannot exceed @p window_ratio (the worst
/// window's, which already holds) nor the floor's are not evaluated: below @p window_ratio the
/// ratio returned is then a lower bound of rule 3's.
/// @pre times increasing, irradiance ≥ 0, longest_s within the MPE table; floor_w_m2 > 0 (0
/// stands for a millionth of the peak).
TrainHazard judgeTrain(std::span<const double> time_s, std::span<const double> irradiance_w_m2,
                       const HazardSpec& hazard, double longest_s, double floor_w_m2,
                       double window_ratio);

/// @brief Which of the repetitive-pulse rules sets a verdict.
enum class DecidingRule : std::uint8_t {
  None = 0,         ///< nothing above the floor
  SinglePulse = 1,  ///< rule 1: the worst window lies within one pulse (or one exposure)
  Average = 2,      ///< rule 2: the worst window spans several pulses
  Train = 3,        ///< rule 3: a pulse against the single-pulse MPE reduced for the train
};

/// @brief What an engagement's irradiance history at one observer means for the eye.
struct ExposureVerdict {
  /// The verdict, unaided: the larger of the worst window's ratio (rules 1 and 2) and the
  /// train's (rule 3).
  double ratio = 0.0;
  DecidingRule rule = DecidingRule::None;  ///< which rule sets it
  WindowHazard worst_window;               ///< rules 1 and 2: the worst window, unaided
  TrainHazard train;                       ///< rule 3
  /// The verdict through the optical aid: its gain scales every exposure alike, so the ratio is
  /// the gain times the unaided one (the unaided ratio without an aid).
  double aided_ratio = 0.0;
  double time_above_mpe_s = 0.0;  ///< at or above the stare MPE (HazardSpec::mpe_w_m2)
  /// Per level (HazardSpec::levels): how long the irradiance is at or above its threshold.
  std::vector<double> time_above_level_s;
  /// The per-pose verdict: the peak irradiance as if stared at for the whole exposure
  /// (peak / HazardSpec::mpe_w_m2), what judging each pose alone would report.
  double stare_ratio = 0.0;
};

/// @brief The verdict of the history (@p time_s, @p irradiance_w_m2) whose peak is
/// @p peak_w_m2: windows up to @p longest_s, pulses counted above @p floor_w_m2 (judgeTrain()).
ExposureVerdict judgeExposure(std::span<const double> time_s,
                              std::span<const double> irradiance_w_m2, double peak_w_m2,
                              const HazardSpec& hazard, double longest_s, double floor_w_m2);

/// @brief "rule 1", "rule 2", "rule 3" or "none".
const char* toString(DecidingRule rule);

}  // namespace glint
