#include "pipeline/engagement_report.h"

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
#include "pipeline/hazard_report.h"
#include "pipeline/memory_budget.h"
#include "pipeline/output_names.h"
#include "pipeline/progress.h"

namespace glint {
namespace {

// What to change when an engagement's samples outgrow the memory budget.
constexpr std::string_view kEngagementAdvice =
    "Raise --memory, or loosen engagement.time.tolerance, or give fewer observer points";

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

EngagementResults sampleEngagement(const FacetIntegrator& reference, const Scene& scene,
                                   std::span<const Vec3> points, const MemoryWatch& watch,
                                   std::ostream* progress_to, bool terminal,
                                   const std::string& what, PointExchange* exchange) {
  const Motion motion(scene.engagement->motion, scene.laser);
  WorkCounter counter;
  counter.stop = &watch.stopFlag();
  const auto start = std::chrono::steady_clock::now();
  std::vector<ExposureHistory> histories;
  const std::string stage = what + "' time samples";
  {
    std::unique_ptr<ProgressReporter> progress;
    if (progress_to != nullptr) {
      progress =
          std::make_unique<ProgressReporter>(*progress_to, terminal, "time samples", 0, counter);
    }
    try {
      histories =
          integrateExposures(reference, motion, points, scene.engagement->time, &counter, exchange);
    } catch (const WorkStopped&) {
      if (progress) progress->stop();
      watch.check(stage, kEngagementAdvice);
      throw;
    }
  }
  watch.check(stage, kEngagementAdvice);
  EngagementResults results = judgeEngagement(std::move(histories), scene);
  results.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return results;
}

EngagementResults judgeEngagement(std::vector<ExposureHistory> histories, const Scene& scene) {
  EngagementResults r;
  r.histories = std::move(histories);
  r.verdicts.reserve(r.histories.size());
  for (const ExposureHistory& h : r.histories) {
    r.verdicts.push_back(judgeExposure(h.time_s, h.irradiance_w_m2, h.peak_w_m2, scene.hazard,
                                       scene.engagement->longest_window_s,
                                       scene.engagement->time.floor_w_m2));
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

namespace glint {

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

std::vector<ExrChannel> EngagementMaps::channels() const {
  std::vector<ExrChannel> c = {
      {"exposure_j_m2", &exposure_j_m2},       {"peak_irradiance_w_m2", &peak_irradiance_w_m2},
      {"time_above_mpe_s", &time_above_mpe_s}, {"hazard_ratio", &hazard_ratio},
      {"hazard_rule", &hazard_rule},           {"pulses", &pulses},
      {"worst_window_s", &worst_window_s},     {"stare_hazard_ratio", &stare_hazard_ratio}};
  if (!aided_hazard_ratio.empty()) c.push_back({"aided_hazard_ratio", &aided_hazard_ratio});
  c.push_back({"status", &status});
  return c;
}

std::vector<LatticeChannel> EngagementMaps::latticeChannels() const {
  std::vector<LatticeChannel> c = {
      {"exposure_j_m2", "J/m^2", &exposure_j_m2},
      {"peak_irradiance_w_m2", "W/m^2", &peak_irradiance_w_m2},
      {"time_above_mpe_s", "s", &time_above_mpe_s},
      {"hazard_ratio",
       "1 (the larger of the worst window's exposure / its MPE and the pulse train's rule 3)",
       &hazard_ratio},
      {"hazard_rule", "1, 2 or 3: the repetitive-pulse rule that sets hazard_ratio (0 dark)",
       &hazard_rule},
      {"pulses", "1 (pulses rule 3 counted)", &pulses},
      {"worst_window_s", "s", &worst_window_s},
      {"stare_hazard_ratio", "1 (peak irradiance / MPE for exposure_s)", &stare_hazard_ratio}};
  if (!aided_hazard_ratio.empty()) {
    c.push_back(
        {"aided_hazard_ratio", "1 (worst window through the optical aid)", &aided_hazard_ratio});
  }
  c.push_back({"status", "1 integrated, 3 dark by the bound, 5 unconverged", &status});
  return c;
}

EngagementMaps engagementMaps(const FieldSpec& spec, std::span<const std::uint8_t> lit,
                              const EngagementResults& results, const HazardSpec& hazard) {
  const std::array<int, 3> n = spec.nodes();
  EngagementMaps m;
  m.grid = {n[0], n[1], spec.min_m, spec.axes[0], spec.axes[1], spec.voxel_m};
  const std::size_t count = lit.size();
  for (auto* channel :
       {&m.exposure_j_m2, &m.peak_irradiance_w_m2, &m.time_above_mpe_s, &m.hazard_ratio,
        &m.hazard_rule, &m.pulses, &m.stare_hazard_ratio, &m.worst_window_s}) {
    channel->assign(count, 0.0f);
  }
  if (hazard.aid) m.aided_hazard_ratio.assign(count, 0.0f);
  m.status.assign(count, 3.0f);  // dark over the whole span by the bound
  std::size_t row = 0;
  for (std::size_t p = 0; p < count; ++p) {
    if (lit[p] == 0) continue;
    const ExposureHistory& h = results.histories[row];
    const ExposureVerdict& v = results.verdicts[row];
    ++row;
    m.exposure_j_m2[p] = static_cast<float>(h.exposure_j_m2);
    m.peak_irradiance_w_m2[p] = static_cast<float>(h.peak_w_m2);
    m.time_above_mpe_s[p] = static_cast<float>(v.time_above_mpe_s);
    m.hazard_ratio[p] = static_cast<float>(v.ratio);
    m.hazard_rule[p] = static_cast<float>(v.rule);
    m.pulses[p] = static_cast<float>(v.train.pulses);
    m.worst_window_s[p] = static_cast<float>(v.worst_window.duration_s);
    m.stare_hazard_ratio[p] = static_cast<float>(v.stare_ratio);
    if (hazard.aid) m.aided_hazard_ratio[p] = static_cast<float>(v.aided_ratio);
    m.status[p] = h.converged ? 1.0f : 5.0f;
    ++m.integrated;
    m.hazardous += v.ratio >= 1.0 ? 1 : 0;
    m.train_decides += v.rule == DecidingRule::Train ? 1 : 0;
    m.stare_hazardous += v.stare_ratio >= 1.0 ? 1 : 0;
    m.aided_hazardous += hazard.aid && v.aided_ratio >= 1.0 ? 1 : 0;
    m.unconverged += h.converged ? 0 : 1;
  }
  return m;
}

EngagementRegion engagementRegion(const FacetIntegrator& target, const Scene& scene,
                                  const FieldSpec& spec, const MemoryWatch& watch,
                                  std::ostream* progress_to, bool terminal, const std::string& what,
                                  PointExchange* exchange) {
  const auto start = std::chrono::steady_clock::now();
  const Motion motion(scene.engagement->motion, scene.laser);
  // Each sample is integrated to the scene's accuracy, as glint points integrates it: a plane's
  // map holds at each of its points what the table gives for that point.
  const FacetIntegrator integrator =
      target.withAccuracy(scene.accuracy.tolerance, scene.accuracy.floor_w_m2);
  const std::vector<std::uint8_t> lit =
      litByBound(integrator, motion, spec, scene.engagement->time);
  const std::array<int, 3> n = spec.nodes();
  EngagementRegion region;
  std::size_t p = 0;  // lit's index, [(k × nodes[1] + j) × nodes[0] + i]
  for (int k = 0; k < n[2]; ++k)
    for (int j = 0; j < n[1]; ++j)
      for (int i = 0; i < n[0]; ++i, ++p)
        if (lit[p] != 0) region.points.push_back(spec.position(i, j, k));
  region.results = sampleEngagement(integrator, scene, region.points, watch, progress_to, terminal,
                                    what + "'s points", exchange);
  region.results.seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  region.maps = engagementMaps(spec, lit, region.results, scene.hazard);
  for (const ExrChannel& channel : region.maps.channels()) {
    for (float v : *channel.values) {
      if (!std::isfinite(v)) {
        throw std::runtime_error(what + ": " + channel.name +
                                 " is not a finite number somewhere; nothing was written");
      }
    }
  }
  return region;
}

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
                           const EngagementRegion& region) {
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
  if (maps.unconverged > 0) {
    err << "  warning: " << maps.unconverged
        << " points did not reach the tolerance in time (status 5)\n";
  }
}

}  // namespace glint
