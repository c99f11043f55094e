#include "pipeline/engagement_report.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <string>

#include "export/atomic_file.h"
#include "pipeline/hazard_report.h"
#include "pipeline/progress.h"

namespace glint {

EngagementResults judgeEngagement(std::vector<ExposureHistory> histories, const Scene& scene) {
  EngagementResults r;
  r.histories = std::move(histories);
  r.verdicts.reserve(r.histories.size());
  for (const ExposureHistory& h : r.histories) {
    r.verdicts.push_back(judgeExposure(h.time_s, h.irradiance_w_m2, h.peak_w_m2, scene.hazard,
                                       scene.engagement->longest_window_s));
  }
  return r;
}

std::vector<CsvColumn> engagementColumns(const EngagementResults& results,
                                         const HazardSpec& hazard) {
  std::vector<CsvColumn> columns;
  auto add = [&](const char* name, auto value, bool integer = false) {
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
  add("hazard_ratio", [](H, V v) { return v.window.ratio; });
  add("worst_window_s", [](H, V v) { return v.window.duration_s; });
  add("worst_window_start_s", [](H, V v) { return v.window.start_s; });
  add("worst_window_exposure_j_m2", [](H, V v) { return v.window.exposure_j_m2; });
  add("worst_window_mpe_j_m2", [](H, V v) { return v.window.mpe_j_m2; });
  if (hazard.aid) add("aided_hazard_ratio", [](H, V v) { return v.aided_ratio; });
  add("stare_hazard_ratio", [](H, V v) { return v.stare_ratio; });
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
  std::string text = "observer,time_s,irradiance_w_m2\n";
  char buf[32];
  for (std::size_t o = 0; o < results.histories.size(); ++o) {
    const ExposureHistory& h = results.histories[o];
    for (std::size_t i = 0; i < h.time_s.size(); ++i) {
      text += std::to_string(o + 1);
      for (double v : {h.time_s[i], h.irradiance_w_m2[i]}) {
        text += ',';
        text.append(buf, std::to_chars(buf, buf + sizeof buf, v).ptr);
      }
      text += '\n';
    }
  }
  out << text;
}

void printEngagementSummary(std::ostream& err, const Scene& scene, std::span<const Vec3> points,
                            const EngagementResults& results, int threads) {
  const EngagementSpec& e = *scene.engagement;
  const std::size_t n = results.histories.size();
  std::size_t samples = 0, lo = 0, hi = 0, unconverged = 0, worst = 0, stare_worst = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t s = results.histories[i].time_s.size();
    samples += s;
    lo = i == 0 ? s : std::min(lo, s);
    hi = std::max(hi, s);
    unconverged += results.histories[i].converged ? 0 : 1;
    if (results.verdicts[i].window.ratio > results.verdicts[worst].window.ratio) worst = i;
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
  const ExposureHistory& h = results.histories[worst];
  const ExposureVerdict& v = results.verdicts[worst];
  const Vec3& p = points[worst];
  err << "  worst observer: row " << worst + 1 << " at (" << p.x << ", " << p.y << ", " << p.z
      << "): hazard ratio " << formatNumber("%.3g", v.window.ratio) << ", its worst window "
      << formatNumber("%.3g", v.window.duration_s) << " s from "
      << formatNumber("%.6g", v.window.start_s) << " s collecting "
      << formatNumber("%.3g", v.window.exposure_j_m2) << " J/m² against an MPE of "
      << formatNumber("%.3g", v.window.mpe_j_m2) << " J/m²";
  if (scene.hazard.aid) err << "; aided " << formatNumber("%.3g", v.aided_ratio);
  err << "\n    exposure " << formatNumber("%.4g", h.exposure_j_m2) << " J/m², peak "
      << formatNumber("%.4g", h.peak_w_m2) << " W/m² at " << formatNumber("%.6g", h.peak_time_s)
      << " s, " << formatNumber("%.3g", v.time_above_mpe_s) << " s at or above the stare MPE\n";
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

}  // namespace glint
