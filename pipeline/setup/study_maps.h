#pragma once
/// @file
/// @brief A study's hazard over its observer lattices: each region's maximum irradiance and,
/// per lattice point, how many scenarios reach the MPE there (and the aided MPE, with an
/// optical aid), from which the coverage maps are made (docs/batch.md).

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "observers/field.h"
#include "pipeline/input/scene.h"

namespace glint {

/// @brief How many points of one scenario's map reach the MPE, the aided MPE (0 without an
/// aid) and each level.
struct HazardousPoints {
  std::int64_t unaided = 0;
  std::int64_t aided = 0;
  std::vector<std::int64_t> levels;  ///< per level of the scene: points that reach it
};

/// @brief A confidence interval for a proportion.
struct ProportionInterval {
  double lower = 0.0;
  double upper = 1.0;
};

/// @brief The exact (Clopper–Pearson) interval for @p k successes in @p n trials: each end
/// misses the true proportion with probability at most @p alpha_each_side, whatever it is
/// (lower = 0 at k = 0, upper = 1 at k = n). The ends are quantiles of Beta distributions,
/// B(α; k, n − k + 1) and B(1 − α; k + 1, n − k), through Boost.Math.
ProportionInterval clopperPearson(std::uint64_t k, std::uint64_t n, double alpha_each_side);

/// @brief Each point's coverage interval: its ends, as floats.
struct CoverageBounds {
  std::vector<float> lower, upper;
};

/// @brief One scenario's values over a region, as a study adds them.
struct RegionValues {
  /// A pose's irradiance, or an engagement's peak irradiance over its span (W/m²).
  std::vector<float> irradiance_w_m2;
  /// An engagement's hazard ratio of the worst window, and through the aid (empty without
  /// one). Both empty for a pose, whose ratios are its irradiance's against the MPE.
  std::vector<float> hazard_ratio, aided_hazard_ratio;
};

/// @brief One observer lattice of a study (the box or a plane): the same in every scenario,
/// since poses move the target, never the observers.
struct StudyLattice {
  std::string name;  ///< "box" or the plane's name
  bool plane = false;
  std::size_t plane_index = 0;
  FieldSpec spec;
  // Over the scenarios this rank has added (rank 0, after the reduction: all of them).
  std::vector<float> max_w_m2;
  std::vector<std::uint32_t> hazardous;        ///< scenarios with hazard ratio ≥ 1 at the point
  std::vector<std::uint32_t> aided_hazardous;  ///< with aided ratio ≥ 1; empty without an aid
  bool aided = false;                          ///< the scene has an optical aid
  /// The scene is an engagement: a point's ratio is its worst window's, not E / MPE, so the
  /// largest ratio is kept beside the largest irradiance (which no longer gives it).
  bool engagement = false;
  std::vector<float> max_ratio, aided_max_ratio;  ///< engagement only (aided: with an aid)
  /// The study's combinations of other parameters that share each jitter sample. Above 1 their
  /// scenarios are independent trials only within a combination, so each combination's counts
  /// are kept apart, [combination × points + point], for intervals that hold.
  std::size_t combinations = 1;
  std::vector<std::uint32_t> hazardous_by_combination, aided_hazardous_by_combination;
  /// Per level of the scene (HazardSpec::levels): its threshold, and the scenarios whose
  /// irradiance reaches it at the point (a pose's, or an engagement's peak over its span: the
  /// levels are irradiance reached at some moment, not an exposure), with the combinations'
  /// counts kept apart as above.
  std::vector<double> level_thresholds_w_m2;
  std::vector<std::vector<std::uint32_t>> level_reached, level_reached_by_combination;

  /// @brief Bytes of the maps allocate() makes.
  [[nodiscard]] std::uint64_t mapBytes() const;
  /// @brief Makes the maps, zeroed (aided counts only with an aid).
  void allocate();

  /// @brief The map of this region a resumed scenario's irradiance is read back from: one of
  /// the maps its folder keeps (ScenarioMaps::names(), pipeline/report/run_outputs.h).
  [[nodiscard]] std::string scenarioFile() const;
  /// @brief The aggregated map of the study's folder.
  [[nodiscard]] std::string studyFile() const;
  /// @brief m² of a plane's pixel, m³ of a box's voxel.
  [[nodiscard]] double cell() const;

  /// @brief Adds one scenario's values to the maxima and the counts. Each point is judged by
  /// the stored floats, so that a scenario read back from its file counts as it did when
  /// fresh.
  /// @throw std::logic_error when the values do not fit the lattice or the scene's kind (a
  /// programming error).
  HazardousPoints add(const RegionValues& values, const HazardSpec& h, std::size_t combination = 0);

  /// @brief Each point's coverage interval after @p scenarios (every combination's), each end
  /// wrong with probability at most @p alpha_each_side: clopperPearson() of its count, or with
  /// combinations the mean over them of each one's interval at alpha_each_side / combinations
  /// (Bonferroni: when every combination's interval holds, so does their mean's).
  [[nodiscard]] CoverageBounds coverageBounds(bool aided_counts, std::size_t scenarios,
                                              double alpha_each_side) const;
  /// @brief coverageBounds() of the counts of level @p level.
  [[nodiscard]] CoverageBounds levelCoverageBounds(std::size_t level, std::size_t scenarios,
                                                   double alpha_each_side) const;
};

/// @brief The lattices of @p base (its box, then its planes), their maps not yet allocated.
std::vector<StudyLattice> studyLattices(const Scene& base);

/// @brief The coverage probability at each point: @p counts / @p scenarios.
std::vector<float> coverage(const std::vector<std::uint32_t>& counts, std::size_t scenarios);

/// @brief Half the width of the widest coverage interval of any point of @p lattices after
/// @p scenarios (clopperPearson() at @p confidence, half the rest a side), aided and level counts
/// included: what a study asking for a precision compares with it.
double widestCoverageHalfWidth(const std::vector<StudyLattice>& lattices, std::size_t scenarios,
                               double confidence);

/// @brief What a study's coverage map says of the region hazardous with probability at least
/// @p probability, at confidence @p confidence over the whole map at once: each point's
/// interval at 1 − α/(2m) a side, m the map's points (Bonferroni, which needs nothing of how
/// the points depend on one another). With probability at least the confidence, every point
/// counted in `certain` has a true probability of at least @p probability, and every point
/// with that probability is counted in `possible`.
struct SimultaneousCoverage {
  std::int64_t points = 0;    ///< m
  std::int64_t certain = 0;   ///< lower bound ≥ probability
  std::int64_t possible = 0;  ///< upper bound ≥ probability
  /// The coverage a point needs to be counted certain: the fewest hazardous scenarios (of n)
  /// whose lower bound reaches the probability; n + 1 where none does.
  std::uint64_t certain_from_count = 0;
};
SimultaneousCoverage simultaneousCoverage(const std::vector<std::uint32_t>& counts,
                                          std::size_t scenarios, double confidence,
                                          double probability);

/// @brief simultaneousCoverage() of a lattice's (unaided) counts, with its combinations kept
/// apart as StudyLattice::coverageBounds() keeps them; `certain_from_count` is then the
/// hazardous scenarios needed when they are spread evenly over the combinations.
SimultaneousCoverage simultaneousCoverage(const StudyLattice& lattice, std::size_t scenarios,
                                          double confidence, double probability);

}  // namespace glint
