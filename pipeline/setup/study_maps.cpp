#include "pipeline/setup/study_maps.h"

#include <algorithm>
#include <boost/math/special_functions/beta.hpp>
#include <stdexcept>

#include "pipeline/base/output_names.h"
#include "pipeline/setup/target_builder.h"

namespace glint {

std::string StudyLattice::scenarioFile() const {
  if (plane) return output_names::planeExr(name);
  return engagement ? output_names::kEngagementVdb : output_names::kIrradianceVdb;
}

std::string StudyLattice::studyFile() const {
  return plane ? output_names::planeExr(name) : output_names::kStudyBoxVdb;
}

double StudyLattice::cell() const {
  return plane ? spec.voxel_m * spec.voxel_m : spec.voxel_m * spec.voxel_m * spec.voxel_m;
}

HazardousPoints StudyLattice::add(const RegionValues& v, const HazardSpec& h,
                                  std::size_t combination) {
  const std::vector<float>& e_w_m2 = v.irradiance_w_m2;
  const bool fits = e_w_m2.size() == max_w_m2.size() &&
                    (engagement ? v.hazard_ratio.size() == e_w_m2.size() &&
                                      (!aided || v.aided_hazard_ratio.size() == e_w_m2.size())
                                : v.hazard_ratio.empty() && v.aided_hazard_ratio.empty());
  if (!fits || combination >= combinations)
    throw std::logic_error("batch: a scenario's map does not fit its region's lattice");
  const bool apart = combinations > 1;
  const std::size_t offset = combination * e_w_m2.size();
  HazardousPoints n;
  for (std::size_t i = 0; i < e_w_m2.size(); ++i) {
    max_w_m2[i] = std::max(max_w_m2[i], e_w_m2[i]);
    const double e = static_cast<double>(e_w_m2[i]);
    const double ratio = engagement ? static_cast<double>(v.hazard_ratio[i]) : h.ratio(e);
    if (engagement) max_ratio[i] = std::max(max_ratio[i], v.hazard_ratio[i]);
    if (ratio >= 1.0) {
      ++hazardous[i];
      if (apart) ++hazardous_by_combination[offset + i];
      ++n.unaided;
    }
    if (!aided) continue;
    const double aided_ratio =
        engagement ? static_cast<double>(v.aided_hazard_ratio[i]) : h.aidedRatio(e);
    if (engagement) aided_max_ratio[i] = std::max(aided_max_ratio[i], v.aided_hazard_ratio[i]);
    if (aided_ratio >= 1.0) {
      ++aided_hazardous[i];
      if (apart) ++aided_hazardous_by_combination[offset + i];
      ++n.aided;
    }
  }
  n.levels.assign(level_thresholds_w_m2.size(), 0);
  for (std::size_t k = 0; k < level_thresholds_w_m2.size(); ++k) {
    const double threshold = level_thresholds_w_m2[k];
    std::vector<std::uint32_t>& reached = level_reached[k];
    for (std::size_t i = 0; i < e_w_m2.size(); ++i) {
      if (!(static_cast<double>(e_w_m2[i]) >= threshold)) continue;
      ++reached[i];
      if (apart) ++level_reached_by_combination[k][offset + i];
      ++n.levels[k];
    }
  }
  return n;
}

std::uint64_t StudyLattice::mapBytes() const {
  const auto n = spec.nodes();
  const std::uint64_t points = static_cast<std::uint64_t>(n[0]) * static_cast<std::uint64_t>(n[1]) *
                               static_cast<std::uint64_t>(n[2]);
  const std::uint64_t ratios = engagement ? sizeof(float) * (aided ? 2 : 1) : 0;
  const std::uint64_t counts = sizeof(std::uint32_t) *
                               ((aided ? 2 : 1) + level_thresholds_w_m2.size()) *
                               (1 + (combinations > 1 ? combinations : 0));
  return points * (sizeof(float) + counts + ratios);
}

void StudyLattice::allocate() {
  const auto n = spec.nodes();
  const std::size_t points = static_cast<std::size_t>(n[0]) * static_cast<std::size_t>(n[1]) *
                             static_cast<std::size_t>(n[2]);
  max_w_m2.assign(points, 0.0f);
  hazardous.assign(points, 0u);
  if (aided) aided_hazardous.assign(points, 0u);
  if (engagement) {
    max_ratio.assign(points, 0.0f);
    if (aided) aided_max_ratio.assign(points, 0.0f);
  }
  if (combinations > 1) {
    hazardous_by_combination.assign(points * combinations, 0u);
    if (aided) aided_hazardous_by_combination.assign(points * combinations, 0u);
  }
  const std::size_t levels = level_thresholds_w_m2.size();
  level_reached.assign(levels, std::vector<std::uint32_t>(points, 0u));
  level_reached_by_combination.assign(
      levels, std::vector<std::uint32_t>(combinations > 1 ? points * combinations : 0, 0u));
}

std::vector<StudyLattice> studyLattices(const Scene& base) {
  std::vector<StudyLattice> lattices;
  StudyLattice kind;
  kind.aided = base.hazard.aid.has_value();
  kind.engagement = base.engagement.has_value();
  for (const ExposureLevel& l : base.hazard.levels)
    kind.level_thresholds_w_m2.push_back(l.thresholdW_m2());
  if (base.observers) {
    StudyLattice& box = lattices.emplace_back(kind);
    box.name = output_names::kStudyBoxName;
    box.spec = fieldSpec(base);
  }
  for (std::size_t p = 0; p < base.planes.size(); ++p) {
    StudyLattice& plane = lattices.emplace_back(kind);
    plane.name = base.planes[p].name;
    plane.plane = true;
    plane.plane_index = p;
    plane.spec = planeFieldSpec(base, base.planes[p]);
  }
  return lattices;
}

ProportionInterval clopperPearson(std::uint64_t k, std::uint64_t n, double alpha_each_side) {
  ProportionInterval i;
  if (n == 0) return i;  // nothing observed: the whole of [0, 1]
  const auto kd = static_cast<double>(k), nd = static_cast<double>(n);
  if (k > 0) i.lower = boost::math::ibeta_inv(kd, nd - kd + 1.0, alpha_each_side);
  if (k < n) i.upper = boost::math::ibeta_inv(kd + 1.0, nd - kd, 1.0 - alpha_each_side);
  return i;
}

namespace {

// The intervals of 0 .. n successes in n trials: a map has at most n + 1 distinct counts.
std::vector<ProportionInterval> intervalTable(std::size_t n, double alpha_each_side) {
  std::vector<ProportionInterval> table(n + 1);
  for (std::size_t k = 0; k <= n; ++k) table[k] = clopperPearson(k, n, alpha_each_side);
  return table;
}

// Each point's interval ends in double precision (StudyLattice::coverageBounds()).
struct Bounds {
  std::vector<double> lower, upper;
};

// The intervals of @p counts (their combinations' apart in @p by where r has several).
Bounds latticeBounds(const StudyLattice& r, const std::vector<std::uint32_t>& counts,
                     const std::vector<std::uint32_t>& by, std::size_t scenarios,
                     double alpha_each_side) {
  Bounds b;
  b.lower.resize(counts.size());
  b.upper.resize(counts.size());
  if (r.combinations <= 1) {
    const std::vector<ProportionInterval> table = intervalTable(scenarios, alpha_each_side);
    for (std::size_t i = 0; i < counts.size(); ++i) {
      b.lower[i] = table.at(counts[i]).lower;
      b.upper[i] = table.at(counts[i]).upper;
    }
    return b;
  }
  // Each combination's samples are independent trials among themselves. Each combination's
  // interval misses on a side with probability at most alpha / combinations, so on that side
  // all hold together with probability at least 1 − alpha; and when they all hold, the mean of
  // their ends holds the mean of their probabilities, which the coverage estimates.
  const std::size_t c = r.combinations;
  const std::vector<ProportionInterval> table =
      intervalTable(scenarios / c, alpha_each_side / static_cast<double>(c));
  const std::size_t points = counts.size();
  for (std::size_t i = 0; i < points; ++i) {
    double lower = 0.0, upper = 0.0;
    for (std::size_t k = 0; k < c; ++k) {
      lower += table.at(by[k * points + i]).lower;
      upper += table.at(by[k * points + i]).upper;
    }
    b.lower[i] = lower / static_cast<double>(c);
    b.upper[i] = upper / static_cast<double>(c);
  }
  return b;
}

Bounds latticeBounds(const StudyLattice& r, bool aided_counts, std::size_t scenarios,
                     double alpha_each_side) {
  return aided_counts ? latticeBounds(r, r.aided_hazardous, r.aided_hazardous_by_combination,
                                      scenarios, alpha_each_side)
                      : latticeBounds(r, r.hazardous, r.hazardous_by_combination, scenarios,
                                      alpha_each_side);
}

double widestHalfWidthOf(const StudyLattice& r, std::size_t scenarios, double confidence) {
  double widest = 0.0;
  const auto widen = [&](const Bounds& b) {
    for (std::size_t i = 0; i < b.lower.size(); ++i)
      widest = std::max(widest, 0.5 * (b.upper[i] - b.lower[i]));
  };
  const double alpha_each_side = 0.5 * (1.0 - confidence);
  for (const bool aided_counts : {false, true}) {
    if (aided_counts && !r.aided) continue;
    widen(latticeBounds(r, aided_counts, scenarios, alpha_each_side));
  }
  for (std::size_t k = 0; k < r.level_reached.size(); ++k) {
    widen(latticeBounds(r, r.level_reached[k], r.level_reached_by_combination[k], scenarios,
                        alpha_each_side));
  }
  return widest;
}

CoverageBounds toFloats(const Bounds& b) {
  CoverageBounds f;
  for (double x : b.lower) f.lower.push_back(static_cast<float>(x));
  for (double x : b.upper) f.upper.push_back(static_cast<float>(x));
  return f;
}

}  // namespace

CoverageBounds StudyLattice::coverageBounds(bool aided_counts, std::size_t scenarios,
                                            double alpha_each_side) const {
  return toFloats(latticeBounds(*this, aided_counts, scenarios, alpha_each_side));
}

CoverageBounds StudyLattice::levelCoverageBounds(std::size_t level, std::size_t scenarios,
                                                 double alpha_each_side) const {
  return toFloats(latticeBounds(*this, level_reached.at(level),
                                level_reached_by_combination.at(level), scenarios,
                                alpha_each_side));
}

double widestCoverageHalfWidth(const std::vector<StudyLattice>& lattices, std::size_t scenarios,
                               double confidence) {
  double widest = 0.0;
  for (const StudyLattice& r : lattices)
    widest = std::max(widest, widestHalfWidthOf(r, scenarios, confidence));
  return widest;
}

SimultaneousCoverage simultaneousCoverage(const StudyLattice& r, std::size_t scenarios,
                                          double confidence, double probability) {
  if (r.combinations <= 1) {
    return simultaneousCoverage(r.hazardous, scenarios, confidence, probability);
  }
  SimultaneousCoverage c;
  c.points = static_cast<std::int64_t>(r.hazardous.size());
  if (r.hazardous.empty()) return c;
  const double alpha_each_side = (1.0 - confidence) / (2.0 * static_cast<double>(c.points));
  const Bounds b = latticeBounds(r, false, scenarios, alpha_each_side);
  for (std::size_t i = 0; i < b.lower.size(); ++i) {
    c.certain += b.lower[i] >= probability ? 1 : 0;
    c.possible += b.upper[i] >= probability ? 1 : 0;
  }
  // Spread evenly: every combination hazardous in k of its samples.
  const std::size_t samples = scenarios / r.combinations;
  const std::vector<ProportionInterval> table =
      intervalTable(samples, alpha_each_side / static_cast<double>(r.combinations));
  c.certain_from_count = scenarios + 1;
  for (std::size_t k = 0; k <= samples; ++k) {
    if (table[k].lower >= probability) {
      c.certain_from_count = k * r.combinations;
      break;
    }
  }
  return c;
}

SimultaneousCoverage simultaneousCoverage(const std::vector<std::uint32_t>& counts,
                                          std::size_t scenarios, double confidence,
                                          double probability) {
  SimultaneousCoverage c;
  c.points = static_cast<std::int64_t>(counts.size());
  if (counts.empty()) return c;
  const double alpha_each_side = (1.0 - confidence) / (2.0 * static_cast<double>(counts.size()));
  const std::vector<ProportionInterval> table = intervalTable(scenarios, alpha_each_side);
  c.certain_from_count = scenarios + 1;
  for (std::size_t k = 0; k <= scenarios; ++k) {
    if (table[k].lower >= probability) {
      c.certain_from_count = k;
      break;
    }
  }
  for (const std::uint32_t k : counts) {
    c.certain += table.at(k).lower >= probability ? 1 : 0;
    c.possible += table.at(k).upper >= probability ? 1 : 0;
  }
  return c;
}

std::vector<float> coverage(const std::vector<std::uint32_t>& counts, std::size_t scenarios) {
  std::vector<float> c(counts.size());
  for (std::size_t i = 0; i < c.size(); ++i)
    c[i] = static_cast<float>(static_cast<double>(counts[i]) / static_cast<double>(scenarios));
  return c;
}

}  // namespace glint
