#include "pipeline/setup/engagement.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string_view>

#include "pipeline/base/memory_budget.h"
#include "pipeline/base/output_names.h"
#include "pipeline/base/progress.h"

namespace glint {
namespace {

// What to change when an engagement's samples outgrow the memory budget.
constexpr std::string_view kEngagementAdvice =
    "Raise --memory, or loosen engagement.time.tolerance, or give fewer observer points";

}  // namespace

EngagementResults sampleEngagement(const FacetIntegrator& reference, const Scene& scene,
                                   std::span<const Vec3> points, const WorkWatch& w) {
  const Motion motion(scene.engagement->motion, scene.laser);
  WorkCounter counter;
  counter.stop = &w.watch.stopFlag();
  const auto start = std::chrono::steady_clock::now();
  std::vector<ExposureHistory> histories;
  const std::string stage = w.what + "' time samples";
  {
    std::unique_ptr<ProgressReporter> progress;
    if (w.progress_to != nullptr) {
      progress = std::make_unique<ProgressReporter>(*w.progress_to, w.terminal, "time samples", 0,
                                                    counter);
    }
    try {
      histories = integrateExposures(reference, motion, points, scene.engagement->time, &counter,
                                     w.exchange);
    } catch (const WorkStopped&) {
      if (progress) progress->stop();
      w.watch.check(stage, kEngagementAdvice);
      throw;
    }
  }
  w.watch.check(stage, kEngagementAdvice);
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

std::vector<ExrChannel> EngagementMaps::channels() const {
  std::vector<ExrChannel> c = {
      {"exposure_j_m2", &exposure_j_m2},       {"peak_irradiance_w_m2", &peak_irradiance_w_m2},
      {"time_above_mpe_s", &time_above_mpe_s}, {"hazard_ratio", &hazard_ratio},
      {"hazard_rule", &hazard_rule},           {"pulses", &pulses},
      {"worst_window_s", &worst_window_s},     {"stare_hazard_ratio", &stare_hazard_ratio}};
  if (!aided_hazard_ratio.empty()) c.push_back({"aided_hazard_ratio", &aided_hazard_ratio});
  for (const auto& [name, values] : time_above_level_s) c.push_back({name, &values});
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
  for (const auto& [name, values] : time_above_level_s) c.push_back({name, "s", &values});
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
  for (const ExposureLevel& l : hazard.levels)
    m.time_above_level_s.push_back(
        {output_names::levelTimeAbove(l.name), std::vector<float>(count, 0.0f)});
  m.level_reached.assign(hazard.levels.size(), 0);
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
    for (std::size_t k = 0; k < m.time_above_level_s.size(); ++k) {
      m.time_above_level_s[k].second[p] = static_cast<float>(v.time_above_level_s.at(k));
      m.level_reached[k] += v.time_above_level_s[k] > 0.0 ? 1 : 0;
    }
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
                                  const FieldSpec& spec, const WorkWatch& w) {
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
  region.results = sampleEngagement(
      integrator, scene, region.points,
      WorkWatch{w.watch, w.what + "'s points", w.progress_to, w.terminal, w.exchange});
  region.results.seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  region.maps = engagementMaps(spec, lit, region.results, scene.hazard);
  for (const ExrChannel& channel : region.maps.channels()) {
    for (float v : *channel.values) {
      if (!std::isfinite(v)) {
        throw std::runtime_error(w.what + ": " + channel.name +
                                 " is not a finite number somewhere; nothing was written");
      }
    }
  }
  return region;
}

}  // namespace glint
