#include "pipeline/report/engagement_report.h"

#include <algorithm>
#include <array>
#include <charconv>
#include <chrono>
#include <cmath>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>

#include "export/atomic_file.h"
#include "pipeline/base/memory_budget.h"
#include "pipeline/base/number_format.h"
#include "pipeline/base/output_names.h"
#include "pipeline/base/progress.h"
#include "pipeline/report/hazard_report.h"

namespace glint {
namespace {

// The row of @p results with the largest verdict (0 when empty).
std::size_t worstRow(const EngagementResults& results) {
  std::size_t worst = 0;
  for (std::size_t i = 0; i < results.verdicts.size(); ++i) {
    if (results.verdicts[i].ratio > results.verdicts[worst].ratio) worst = i;
  }
  return worst;
}

// How the strongest pulse of @p t was read: "0.417 (its 0.0304 J/m² over its half-peak
// 5.1e-05 s)" or "0.329 (its worst window, 7.69e-05 s)".
std::string strongestPulse(const TrainHazard& t) {
  return formatNumber("%.3g", t.pulse_ratio) +
         (t.by_half_peak
              ? " (its " + formatNumber("%.3g", t.pulse_exposure_j_m2) +
                    " J/m² over its half-peak " + formatNumber("%.3g", t.pulse_duration_s) + " s)"
              : " (its worst window, " + formatNumber("%.3g", t.pulse.duration_s) + " s)");
}

// What sets the verdict @p v, in words: "rule 3, a train of 101 pulses, 99.67 as strong as its
// strongest: C_P 0.316, its strongest 0.418 (…)", or "rule 1 (its worst window, within one
// pulse)".
std::string decidedBy(const ExposureVerdict& v) {
  if (v.rule == DecidingRule::Train) {
    return std::string("rule 3, a train of ") + std::to_string(v.train.pulses) +
           (v.train.grouped ? " pulses (or groups within t_min), " : " pulses, ") +
           formatNumber("%.4g", v.train.effective_pulses) +
           " as strong as its strongest: " + v.train.reduction_name + " " +
           formatNumber("%.3g", v.train.reduction) + ", its strongest " + strongestPulse(v.train);
  }
  switch (v.rule) {
    case DecidingRule::SinglePulse:
      if (v.ratio > v.worst_window.ratio) {
        return "rule 1 (one pulse: " + strongestPulse(v.train) + ")";
      }
      return "rule 1 (its worst window, within one pulse)";
    case DecidingRule::Average:
      return "rule 2 (its worst window, over several pulses)";
    default:
      return toString(v.rule);
  }
}

}  // namespace

std::vector<CsvColumn> engagementColumns(const EngagementResults& results,
                                         const HazardSpec& hazard) {
  std::vector<CsvColumn> columns;
  auto add = [&](const std::string& name, auto value, bool integer = false) {
    CsvColumn c{name, {}, integer};
    for (std::size_t i = 0; i < results.histories.size(); ++i) {
      c.values.push_back(value(results.histories[i], results.verdicts[i]));
    }
    columns.push_back(std::move(c));
  };
  using H = const ExposureHistory&;
  using V = const ExposureVerdict&;
  add("exposure_j_m2", [](H h, V) { return h.exposure_j_m2; });
  add("exposure_error_j_m2", [](H h, V) { return h.error_j_m2; });
  add("peak_irradiance_w_m2", [](H h, V) { return h.peak_w_m2; });
  add("peak_time_s", [](H h, V) { return h.peak_time_s; });
  add("time_above_mpe_s", [](H, V v) { return v.time_above_mpe_s; });
  add("hazard_ratio", [](H, V v) { return v.ratio; });
  add(
      "hazard_rule", [](H, V v) { return static_cast<double>(v.rule); }, true);
  add("worst_window_ratio", [](H, V v) { return v.worst_window.ratio; });
  add("worst_window_s", [](H, V v) { return v.worst_window.duration_s; });
  add("worst_window_start_s", [](H, V v) { return v.worst_window.start_s; });
  add("worst_window_exposure_j_m2", [](H, V v) { return v.worst_window.exposure_j_m2; });
  add("worst_window_mpe_j_m2", [](H, V v) { return v.worst_window.mpe_j_m2; });
  add(
      "pulses", [](H, V v) { return static_cast<double>(v.train.pulses); }, true);
  add("pulse_train_ratio", [](H, V v) { return v.train.ratio; });
  add("effective_pulses", [](H, V v) { return v.train.effective_pulses; });
  add("pulse_reduction", [](H, V v) { return v.train.reduction; });
  add("pulse_ratio", [](H, V v) { return v.train.pulse_ratio; });
  add(
      "pulse_by_half_peak", [](H, V v) { return v.train.by_half_peak ? 1.0 : 0.0; }, true);
  add("pulse_window_s", [](H, V v) { return v.train.pulse.duration_s; });
  add("pulse_window_exposure_j_m2", [](H, V v) { return v.train.pulse.exposure_j_m2; });
  add("pulse_duration_s", [](H, V v) { return v.train.pulse_duration_s; });
  add("pulse_exposure_j_m2", [](H, V v) { return v.train.pulse_exposure_j_m2; });
  if (hazard.aid) add("aided_hazard_ratio", [](H, V v) { return v.aided_ratio; });
  add("stare_hazard_ratio", [](H, V v) { return v.stare_ratio; });
  for (std::size_t k = 0; k < hazard.levels.size(); ++k) {
    const ExposureLevel& l = hazard.levels[k];
    add(output_names::levelPeakRatio(l.name), [&](H h, V) { return l.ratio(h.peak_w_m2); });
    add(output_names::levelTimeAbove(l.name), [k](H, V v) { return v.time_above_level_s.at(k); });
  }
  add(
      "time_samples", [](H h, V) { return static_cast<double>(h.time_s.size()); }, true);
  add(
      "evaluations", [](H h, V) { return static_cast<double>(h.evaluations); }, true);
  add(
      "converged", [](H h, V) { return h.converged ? 1.0 : 0.0; }, true);
  return columns;
}

void writeTimeSeriesCsv(std::ostream& out, const EngagementResults& results) {
  for (std::size_t o = 0; o < results.histories.size(); ++o) {
    for (double e : results.histories[o].irradiance_w_m2) {
      if (!std::isfinite(e)) {
        throw OutputError("observer " + std::to_string(o + 1) +
                          ": an irradiance sample is not finite; nothing was written");
      }
    }
  }
  std::string text = "observer,time_s,irradiance_w_m2,pulse\n";
  char buf[32];
  for (std::size_t o = 0; o < results.histories.size(); ++o) {
    const ExposureHistory& h = results.histories[o];
    const std::vector<HistoryPulse>& spans = results.verdicts[o].train.spans;
    std::size_t pulse = 0;  // the first span that does not end before the sample
    for (std::size_t i = 0; i < h.time_s.size(); ++i) {
      const double t = h.time_s[i];
      while (pulse < spans.size() && spans[pulse].end_s < t) ++pulse;
      const bool inside = pulse < spans.size() && spans[pulse].start_s <= t;
      text += std::to_string(o + 1);
      for (double v : {t, h.irradiance_w_m2[i]}) {
        text += ',';
        text.append(buf, std::to_chars(buf, buf + sizeof buf, v).ptr);
      }
      text += ',' + std::to_string(inside ? pulse + 1 : 0) + '\n';
    }
  }
  out << text;
}

void printEngagementSummary(std::ostream& err, const Scene& scene, std::span<const Vec3> points,
                            const EngagementResults& results, int threads) {
  const EngagementSpec& e = *scene.engagement;
  const std::size_t n = results.histories.size();
  std::size_t samples = 0, lo = 0, hi = 0, unconverged = 0, stare_worst = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t s = results.histories[i].time_s.size();
    samples += s;
    lo = i == 0 ? s : std::min(lo, s);
    hi = std::max(hi, s);
    unconverged += results.histories[i].converged ? 0 : 1;
    if (results.verdicts[i].stare_ratio > results.verdicts[stare_worst].stare_ratio)
      stare_worst = i;
  }
  err << "glint points: " << n << " observers over an engagement of "
      << formatNumber("%g", e.motion.end_s - e.motion.start_s) << " s ("
      << formatNumber("%g", e.motion.start_s) << " to " << formatNumber("%g", e.motion.end_s)
      << " s), adaptive in time, tolerance " << formatNumber("%g", e.time.tolerance) << ", floor "
      << formatNumber("%.3g", e.time.floor_w_m2) << " W/m², " << threads
      << (threads == 1 ? " thread\n" : " threads\n");
  if (n == 0) return;
  err << "  time samples: " << samples << " in all; per observer "
      << formatNumber("%.4g", static_cast<double>(samples) / static_cast<double>(n))
      << " on average, " << lo << " to " << hi << "\n";
  const std::size_t worst = worstRow(results);
  const ExposureHistory& h = results.histories[worst];
  const ExposureVerdict& v = results.verdicts[worst];
  const Vec3& p = points[worst];
  err << "  worst observer: row " << worst + 1 << " at (" << p.x << ", " << p.y << ", " << p.z
      << "): hazard ratio " << formatNumber("%.3g", v.ratio) << " by " << decidedBy(v);
  if (scene.hazard.aid) err << "; aided " << formatNumber("%.3g", v.aided_ratio);
  err << "\n    its worst window " << formatNumber("%.3g", v.worst_window.duration_s) << " s from "
      << formatNumber("%.6g", v.worst_window.start_s) << " s collects "
      << formatNumber("%.3g", v.worst_window.exposure_j_m2) << " J/m² against an MPE of "
      << formatNumber("%.3g", v.worst_window.mpe_j_m2) << " J/m² (ratio "
      << formatNumber("%.3g", v.worst_window.ratio) << "); " << v.train.pulses
      << (v.train.pulses == 1 ? " pulse" : " pulses") << " counted";
  err << "\n    exposure " << formatNumber("%.4g", h.exposure_j_m2) << " J/m², peak "
      << formatNumber("%.4g", h.peak_w_m2) << " W/m² at " << formatNumber("%.6g", h.peak_time_s)
      << " s, " << formatNumber("%.3g", v.time_above_mpe_s) << " s at or above the stare MPE\n";
  // Per level, the observer that spends the longest at or above it.
  for (std::size_t k = 0; k < scene.hazard.levels.size(); ++k) {
    std::size_t longest = 0;
    for (std::size_t i = 1; i < n; ++i) {
      if (results.verdicts[i].time_above_level_s.at(k) >
          results.verdicts[longest].time_above_level_s.at(k))
        longest = i;
    }
    const double t = results.verdicts[longest].time_above_level_s.at(k);
    err << "  " << levelLine(scene.hazard.levels[k]) << ": ";
    if (t > 0.0) {
      err << "longest " << formatNumber("%.4g", t) << " s at or above it, row " << longest + 1
          << " (peak ratio "
          << formatNumber("%.3g",
                          scene.hazard.levels[k].ratio(results.histories[longest].peak_w_m2))
          << ")\n";
    } else {
      err << "no observer reaches it\n";
    }
  }
  const ExposureVerdict& s = results.verdicts[stare_worst];
  err << "  judged pose by pose as a " << formatNumber("%g", scene.hazard.exposure_s)
      << " s stare (" << hazardLine(scene.hazard) << "): peak ratio "
      << formatNumber("%.3g", s.stare_ratio) << " at row " << stare_worst + 1 << "\n";
  err << "  time: " << formatDuration(results.seconds) << "\n";
  if (unconverged > 0) {
    err << "  warning: " << unconverged << " of " << n
        << " observers did not reach the tolerance in time or in a sample (converged = 0); "
           "raise engagement.time.max_depth or accuracy.max_evaluations, or loosen the "
           "tolerance\n";
  }
}

namespace {

// A region's hazardous extent: a plane's area, a box's volume, and the keys that name it.
class Extent {
 public:
  explicit Extent(const FieldSpec& spec)
      : plane_(spec.plane),
        cell_(spec.plane ? spec.voxel_m * spec.voxel_m
                         : spec.voxel_m * spec.voxel_m * spec.voxel_m) {}
  [[nodiscard]] double of(std::int64_t points) const { return static_cast<double>(points) * cell_; }
  // "hazardous_area_m2" or "hazard_volume_m3", after @p prefix.
  [[nodiscard]] std::string key(const std::string& prefix) const {
    return prefix + (plane_ ? "hazardous_area_m2" : "hazard_volume_m3");
  }
  [[nodiscard]] const char* unit() const { return plane_ ? "m²" : "m³"; }

 private:
  bool plane_;
  double cell_;
};

}  // namespace

nlohmann::json engagementRegionJson(const std::string& name, const std::string& file,
                                    const FieldSpec& spec, const EngagementRegion& region,
                                    const HazardSpec& hazard) {
  const EngagementMaps& maps = region.maps;
  const EngagementResults& results = region.results;
  const Extent extent(spec);
  std::int64_t samples = 0, evaluations = 0;
  for (const ExposureHistory& h : results.histories) {
    samples += static_cast<std::int64_t>(h.time_s.size());
    evaluations += h.evaluations;
  }
  const std::array<int, 3> n = spec.nodes();
  const auto total = static_cast<std::int64_t>(maps.status.size());
  nlohmann::json j = {{"name", name}, {"file", file}};
  if (spec.plane) {
    j["pixels"] = {n[0], n[1]};
    j["pixel_m"] = spec.voxel_m;
  } else {
    j["lattice"] = {n[0], n[1], n[2]};
    j["voxel_m"] = spec.voxel_m;
  }
  j["points"] = {{"integrated", maps.integrated},
                 {"dark_by_bound", total - maps.integrated},
                 {"unconverged", maps.unconverged},
                 {"decided_by_pulse_train", maps.train_decides}};
  j["time_samples"] = samples;
  j["evaluations"] = evaluations;
  j["seconds"] = results.seconds;
  j[extent.key("")] = extent.of(maps.hazardous);
  j[extent.key("stare_")] = extent.of(maps.stare_hazardous);
  if (hazard.aid) j[extent.key("aided_")] = extent.of(maps.aided_hazardous);
  for (std::size_t k = 0; k < hazard.levels.size(); ++k) {
    // Where the irradiance reaches the level at some moment of the span.
    j["levels"][hazard.levels[k].name][spec.plane ? "area_m2" : "volume_m3"] =
        extent.of(maps.level_reached.at(k));
  }
  if (!results.histories.empty()) {
    const std::size_t w = worstRow(results);
    const ExposureHistory& h = results.histories[w];
    const ExposureVerdict& v = results.verdicts[w];
    const Vec3& x = region.points[w];
    j["worst"] = {{"at_m", {x.x, x.y, x.z}},
                  {"hazard_ratio", v.ratio},
                  {"hazard_rule", toString(v.rule)},
                  {"decided_by", decidedBy(v)},
                  {"window_ratio", v.worst_window.ratio},
                  {"window_s", v.worst_window.duration_s},
                  {"window_start_s", v.worst_window.start_s},
                  {"window_exposure_j_m2", v.worst_window.exposure_j_m2},
                  {"window_mpe_j_m2", v.worst_window.mpe_j_m2},
                  {"pulse_train",
                   {{"pulses", v.train.pulses},
                    {"effective_pulses", v.train.effective_pulses},
                    {"hazard_ratio", v.train.ratio},
                    {"reduction", v.train.reduction},
                    {"grouped", v.train.grouped},
                    {"pulse_ratio", v.train.pulse_ratio},
                    {"pulse_reading", v.train.by_half_peak ? "half peak" : "worst window"},
                    {"pulse_window_ratio", v.train.pulse.ratio},
                    {"pulse_window_s", v.train.pulse.duration_s},
                    {"pulse_duration_s", v.train.pulse_duration_s},
                    {"pulse_exposure_j_m2", v.train.pulse_exposure_j_m2}}},
                  {"exposure_j_m2", h.exposure_j_m2},
                  {"peak_irradiance_w_m2", h.peak_w_m2},
                  {"peak_time_s", h.peak_time_s},
                  {"stare_hazard_ratio", v.stare_ratio}};
  }
  return j;
}

nlohmann::json engagementJson(const EngagementSpec& e) {
  const MotionSpec& m = e.motion;
  const char* pointing[] = {"fixed", "track", "keyed"};
  return {{"start_s", m.start_s},
          {"end_s", m.end_s},
          {"pivot_m", {m.pivot_m.x, m.pivot_m.y, m.pivot_m.z}},
          {"target_poses", m.poses.size()},
          {"interpolation", m.interpolation == PoseInterpolation::Linear ? "linear" : "spline"},
          {"laser_pointing", pointing[static_cast<int>(m.pointing)]},
          {"observer_velocity_m_s",
           {m.observer_velocity_m_s.x, m.observer_velocity_m_s.y, m.observer_velocity_m_s.z}},
          {"longest_window_s", e.longest_window_s},
          {"time",
           {{"tolerance", e.time.tolerance},
            {"floor_w_m2", e.time.floor_w_m2},
            {"initial_intervals", e.time.initial_intervals},
            {"max_depth", e.time.max_depth}}},
          {"rule",
           "the larger of: for every duration t up to longest_window_s, the largest radiant "
           "exposure any window of length t collects against the MPE for t (rules 1 and 2); and "
           "the pulses above the floor (or above a doubling of it) counted as a pulse train, "
           "each pulse's worst window against the single-pulse MPE times C_P (ANSI) or C5 (IEC) "
           "of the count (rule 3)"}};
}

void printEngagementRegion(std::ostream& err, const std::string& what, const FieldSpec& spec,
                           const EngagementRegion& region, const HazardSpec& hazard) {
  const EngagementMaps& maps = region.maps;
  const EngagementResults& results = region.results;
  const Extent extent(spec);
  err << what << ": " << maps.integrated << " of " << maps.status.size()
      << " points sampled in time (the rest dark by the bound), "
      << formatDuration(results.seconds);
  if (results.histories.empty()) {
    err << "; nothing reaches it\n";
    return;
  }
  const std::size_t w = worstRow(results);
  const ExposureVerdict& v = results.verdicts[w];
  const Vec3& x = region.points[w];
  err << "\n  worst point (" << x.x << ", " << x.y << ", " << x.z << "): hazard ratio "
      << formatNumber("%.3g", v.ratio) << " by " << decidedBy(v) << "; worst window "
      << formatNumber("%.3g", v.worst_window.ratio) << " over "
      << formatNumber("%.3g", v.worst_window.duration_s) << " s (stare verdict "
      << formatNumber("%.3g", v.stare_ratio) << "); hazardous "
      << formatNumber("%.4g", extent.of(maps.hazardous)) << " " << extent.unit() << ", as a stare "
      << formatNumber("%.4g", extent.of(maps.stare_hazardous)) << " " << extent.unit();
  if (maps.train_decides > 0)
    err << "; the pulse train sets the verdict at " << maps.train_decides << " points";
  err << "\n";
  for (std::size_t k = 0; k < maps.time_above_level_s.size(); ++k) {
    const std::vector<float>& t = maps.time_above_level_s[k].second;
    err << "  " << levelLine(hazard.levels.at(k)) << ": reached over "
        << formatNumber("%.4g", extent.of(maps.level_reached.at(k))) << " " << extent.unit()
        << ", at most "
        << formatNumber("%.3g", static_cast<double>(*std::max_element(t.begin(), t.end())))
        << " s at a point\n";
  }
  if (maps.unconverged > 0) {
    err << "  warning: " << maps.unconverged
        << " points did not reach the tolerance in time (status 5)\n";
  }
}

}  // namespace glint
