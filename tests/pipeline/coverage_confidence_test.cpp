// The coverage maps' confidence: exact (Clopper–Pearson) intervals per point, and the region
// hazardous with a given probability bounded over the whole map at once.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <utility>
#include <vector>

#include "export/exr_map.h"
#include "pipeline/setup/study_maps.h"
#include "support/cli.h"
#include "support/files.h"

namespace glint {
namespace {

// P(X ≥ k) for X ~ Binomial(n, p), summed term by term in logarithms: independent of the Beta
// quantiles the interval is computed from.
double upperTail(int k, int n, double p) {
  double sum = 0.0;
  for (int j = k; j <= n; ++j) {
    sum += std::exp(std::lgamma(n + 1.0) - std::lgamma(j + 1.0) - std::lgamma(n - j + 1.0) +
                    j * std::log(p) + (n - j) * std::log1p(-p));
  }
  return sum;
}
double lowerTail(int k, int n, double p) { return 1.0 - upperTail(k + 1, n, p); }

TEST(ClopperPearson, EachEndLeavesExactlyAlphaInTheBinomialTailItInverts) {
  const double alpha = 0.025;
  for (const auto& [k, n] :
       std::vector<std::pair<int, int>>{{1, 20}, {7, 20}, {19, 20}, {3, 100}, {50, 100}, {1, 5}}) {
    const ProportionInterval i = clopperPearson(k, n, alpha);
    EXPECT_NEAR(upperTail(k, n, i.lower), alpha, 1e-9) << k << " of " << n << ": the lower end";
    EXPECT_NEAR(lowerTail(k, n, i.upper), alpha, 1e-9) << k << " of " << n << ": the upper end";
    EXPECT_LT(i.lower, static_cast<double>(k) / n);
    EXPECT_GT(i.upper, static_cast<double>(k) / n);
  }
  // At the ends the tails have one term: (1 − U)^n = α with none seen, L^n = α with all.
  for (const int n : {1, 20, 1000}) {
    const ProportionInterval none = clopperPearson(0, n, alpha);
    EXPECT_EQ(none.lower, 0.0);
    EXPECT_NEAR(none.upper, 1.0 - std::pow(alpha, 1.0 / n), 1e-12) << n;
    const ProportionInterval all = clopperPearson(n, n, alpha);
    EXPECT_EQ(all.upper, 1.0);
    EXPECT_NEAR(all.lower, std::pow(alpha, 1.0 / n), 1e-12) << n;
  }
}

// Over repeated seeds the 95 % intervals hold the true proportion at least 95 % of the time
// (Clopper–Pearson is exact, so conservative: it never falls short of its rate, whatever p).
TEST(ClopperPearson, CoversTheTrueProportionAtLeastAtItsNominalRateOverRepeatedSeeds) {
  const int n = 40, repeats = 2000;
  const double alpha_each_side = 0.025;
  // Three standard errors of a 95 % rate over 2000 repeats: 0.0146.
  const double slack = 3.0 * std::sqrt(0.95 * 0.05 / repeats);
  for (const double p : {0.02, 0.1, 0.3, 0.5, 0.8}) {
    int covered = 0;
    for (int seed = 0; seed < repeats; ++seed) {
      std::mt19937_64 rng(static_cast<std::uint64_t>(seed) * 7919u + 1u);
      std::binomial_distribution<int> draw(n, p);
      const ProportionInterval i = clopperPearson(draw(rng), n, alpha_each_side);
      covered += i.lower <= p && p <= i.upper ? 1 : 0;
    }
    const double rate = static_cast<double>(covered) / repeats;
    EXPECT_GE(rate, 0.95 - slack) << "p = " << p;
    std::printf("[ coverage ] p = %.2f: the 95 %% intervals held it in %.4f of %d seeds\n", p, rate,
                repeats);
  }
}

// The simultaneous statement over a map: 200 points, half with a true probability of 0.3 and
// half of 0.8, each seen in 60 scenarios. At 95 % over the whole map, a map where any 0.3 point
// is counted certainly hazardous with probability ≥ 0.5, or any 0.8 point is left out of the
// possible region, happens in at most 5 % of seeds.
TEST(ClopperPearson, TheWholeMapsStatementFailsInAtMostItsShareOfSeeds) {
  const int points = 200, n = 60, repeats = 400;
  int failed = 0;
  std::int64_t certain_high = 0;
  for (int seed = 0; seed < repeats; ++seed) {
    std::mt19937_64 rng(static_cast<std::uint64_t>(seed) + 11u);
    std::vector<std::uint32_t> counts(points);
    for (int i = 0; i < points; ++i) {
      std::binomial_distribution<int> draw(n, i < points / 2 ? 0.3 : 0.8);
      counts[static_cast<std::size_t>(i)] = static_cast<std::uint32_t>(draw(rng));
    }
    const SimultaneousCoverage s = simultaneousCoverage(counts, n, 0.95, 0.5);
    bool wrong = false;
    for (int i = 0; i < points; ++i) {
      const std::uint32_t k = counts[static_cast<std::size_t>(i)];
      const bool certain = k >= s.certain_from_count;
      if (i < points / 2 && certain) wrong = true;  // a 0.3 point certified
    }
    // The possible region must hold every 0.8 point: each one's upper bound, at the map's α
    // split over all its points, must reach 0.5.
    const double alpha_each_side = 0.05 / (2.0 * points);
    std::int64_t high_possible = 0;
    for (int i = points / 2; i < points; ++i) {
      const std::uint32_t k = counts[static_cast<std::size_t>(i)];
      high_possible += clopperPearson(k, n, alpha_each_side).upper >= 0.5 ? 1 : 0;
    }
    if (high_possible < points / 2) wrong = true;
    EXPECT_GE(s.possible, high_possible);
    failed += wrong ? 1 : 0;
    for (int i = points / 2; i < points; ++i)
      certain_high += counts[static_cast<std::size_t>(i)] >= s.certain_from_count ? 1 : 0;
  }
  EXPECT_LE(failed, 0.05 * repeats) << failed << " of " << repeats;
  EXPECT_GT(certain_high, 0) << "the statement is not empty: some 0.8 points are certified";
  std::printf(
      "[ coverage ] the whole map's statement failed in %d of %d seeds; %.3f of the "
      "0.8 points certified\n",
      failed, repeats,
      static_cast<double>(certain_high) / (static_cast<double>(repeats) * points / 2));
}

// Studies of the jittered mirror (tests/data/jitter_mirror.json) in a folder of their own: a
// mirror square to the beam sends it back, and an eye 10 m out on the axis is in the returning
// pencil exactly when the pointing error θ has 110 m × tan θ < 0.5 m. With Gaussian jitter of
// σ per axis the true probability is 1 − exp(−(0.5/110)² / 2σ²) = 0.4757 at σ = 4 mrad.
struct JitterMirrorStudies {
  static constexpr double kSigmaRad = 0.004;
  std::filesystem::path dir;

  explicit JitterMirrorStudies(const std::string& folder)
      : dir(std::filesystem::temp_directory_path() / folder) {
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    std::filesystem::copy_file(std::filesystem::path(GLINT_TEST_DATA_DIR) / "jitter_mirror.json",
                               dir / "jitter_mirror.json");
  }
  ~JitterMirrorStudies() { std::filesystem::remove_all(dir); }
  JitterMirrorStudies(const JitterMirrorStudies&) = delete;
  JitterMirrorStudies& operator=(const JitterMirrorStudies&) = delete;

  [[nodiscard]] static double truth() {
    const double edge = 0.5 / 110.0;
    return 1.0 - std::exp(-edge * edge / (2.0 * kSigmaRad * kSigmaRad));
  }
  // The study `name` with pointing_jitter {sigma_rad: σ, @p jitter} and the top-level keys
  // @p more, run quietly into dir/name.
  test::Outcome run(const std::string& name, const std::string& jitter,
                    const std::string& more = "") const {
    std::ofstream(dir / (name + ".json"))
        << R"({"scene": "jitter_mirror.json", )" << more << R"("pointing_jitter": {"sigma_rad": )"
        << kSigmaRad << ", " << jitter << "}}";
    std::filesystem::remove_all(out(name));
    return test::glint(
        {"batch", (dir / (name + ".json")).string(), "-o", out(name).string(), "-q"});
  }
  [[nodiscard]] std::filesystem::path out(const std::string& name) const { return dir / name; }
  // The eye's coverage interval (pixel 0, 1.4 mm off the axis: its probability differs from the
  // axis's by ~0.3 %) in the study's map.
  [[nodiscard]] std::pair<double, double> eyeInterval(const std::string& name) const {
    const std::string map = (out(name) / "eye.exr").string();
    int w = 0, h = 0;
    return {static_cast<double>(readExrChannel(map, "coverage_lower", w, h)[0]),
            static_cast<double>(readExrChannel(map, "coverage_upper", w, h)[0])};
  }
};

// A study with a known answer (JitterMirrorStudies): over 100 seeds of 40 samples each, the
// eye's 95 % interval in the study's map holds the true probability at least 95 % of the time
// (less three standard errors of that rate over 100 seeds).
TEST(ClopperPearson, AStudysIntervalsHoldAKnownProbabilityAtTheirRateOverSeeds) {
  const JitterMirrorStudies studies("glint_coverage_seeds");
  const double truth = JitterMirrorStudies::truth();
  const int seeds = 100, samples = 40;
  int held = 0;
  double mean_fraction = 0.0;
  for (int seed = 1; seed <= seeds; ++seed) {
    const test::Outcome run = studies.run("seed", R"("samples": )" + std::to_string(samples) +
                                                      R"(, "seed": )" + std::to_string(seed));
    ASSERT_EQ(run.status, 0) << run.err;
    const auto [lower, upper] = studies.eyeInterval("seed");
    int w = 0, h = 0;
    mean_fraction += static_cast<double>(readExrChannel((studies.out("seed") / "eye.exr").string(),
                                                        "coverage_probability", w, h)[0]) /
                     seeds;
    held += lower <= truth && truth <= upper ? 1 : 0;
  }
  const double rate = static_cast<double>(held) / seeds;
  EXPECT_GE(rate, 0.95 - 3.0 * std::sqrt(0.95 * 0.05 / seeds)) << held << " of " << seeds;
  // The premise: the study sees the probability the geometry says (the mean of 100 fractions
  // of 40 has a standard error of 0.008).
  EXPECT_NEAR(mean_fraction, truth, 4.0 * std::sqrt(truth * (1.0 - truth) / (seeds * samples)));
  std::printf(
      "[ coverage ] jittered mirror: true probability %.4f, mean fraction %.4f; the 95 %% "
      "intervals held it in %d of %d seeds\n",
      truth, mean_fraction, held, seeds);
}

// The same study with two reflectances swept beside the jitter: both put the eye in the pencil
// alike, so the two scenarios of each jitter sample are one trial twice. Counted as 80
// independent trials, a 95 % interval would be √2 too narrow and hold the truth with
// probability 0.847 (the binomial sum over the 41 outcomes); kept apart per combination (the
// mean of each one's interval at 2.5 % / 2 a side: 0.984 by the same sum), they hold it at
// least at their rate over 100 seeds.
TEST(ClopperPearson, ASweptStudysIntervalsStillHoldAKnownProbabilityOverSeeds) {
  const JitterMirrorStudies studies("glint_coverage_swept_seeds");
  const double truth = JitterMirrorStudies::truth();
  const int seeds = 100;
  int held = 0;
  for (int seed = 1; seed <= seeds; ++seed) {
    const test::Outcome run =
        studies.run("seed", R"("samples": 40, "seed": )" + std::to_string(seed),
                    R"("sweep": {"specular_reflectance": [0.9, 1.0]}, )");
    ASSERT_EQ(run.status, 0) << run.err;
    const auto [lower, upper] = studies.eyeInterval("seed");
    held += lower <= truth && truth <= upper ? 1 : 0;
  }
  const double rate = static_cast<double>(held) / seeds;
  EXPECT_GE(rate, 0.95 - 3.0 * std::sqrt(0.95 * 0.05 / seeds)) << held << " of " << seeds;
  std::printf(
      "[ coverage ] jittered mirror with a swept reflectance: the 95 %% intervals held p = %.4f "
      "in %d of %d seeds\n",
      truth, held, seeds);
}

// A study asking for a precision runs jitter samples in rounds of 32, 64, 128, ... and stops at
// the first whose every interval is within it: on the jittered mirror (its eye at p = 0.4757,
// where ±0.1 needs about 100 samples) it stops at 128 samples, 64 having left the eye's interval
// wider. Its map is that of a study of as many samples (common random numbers: sample k is the
// same however many are drawn), and over 100 seeds the stopped intervals still hold the true
// probability at their rate (the stop depends on the data, and the intervals do not allow for
// it: this measures what that costs).
TEST(StudyPrecision, StopsAtTheFirstRoundWithinItAndHoldsItsConfidence) {
  const JitterMirrorStudies studies("glint_study_precision");
  const double truth = JitterMirrorStudies::truth();
  auto widest = [&](const std::string& name) {
    const std::string map = (studies.out(name) / "eye.exr").string();
    int w = 0, h = 0;
    const std::vector<float> lo = readExrChannel(map, "coverage_lower", w, h);
    const std::vector<float> hi = readExrChannel(map, "coverage_upper", w, h);
    double widest_half = 0.0;
    for (std::size_t i = 0; i < lo.size(); ++i)
      widest_half =
          std::max(widest_half, 0.5 * (static_cast<double>(hi[i]) - static_cast<double>(lo[i])));
    return widest_half;
  };
  for (const auto& [name, jitter] : {std::pair{"stopped", R"("precision": 0.1, "seed": 5)"},
                                     std::pair{"fewer", R"("samples": 64, "seed": 5)"},
                                     std::pair{"fixed", R"("samples": 128, "seed": 5)"}}) {
    const test::Outcome run = studies.run(name, jitter);
    ASSERT_EQ(run.status, 0) << name << ": " << run.err;
  }
  const auto summary =
      nlohmann::json::parse(std::ifstream(studies.out("stopped") / "summary.json"));
  const nlohmann::json& p = summary.at("precision");
  EXPECT_TRUE(p.at("reached").get<bool>()) << p;
  EXPECT_EQ(p.at("jitter_samples"), 128) << p;
  EXPECT_EQ(summary.at("scenarios").at("count"), 128) << summary.at("scenarios");
  EXPECT_FALSE(summary.at("regions")[0].at("coverage_confidence").contains("combinations"))
      << "the jitter alone: every scenario an independent trial";
  EXPECT_LE(widest("stopped"), 0.1) << "the map's own intervals";
  EXPECT_NEAR(widest("stopped"), p.at("widest_half_width").get<double>(), 1e-6);
  EXPECT_GT(widest("fewer"), 0.1) << "64 samples must not have been enough, or it stopped late";
  EXPECT_EQ(test::readFile(studies.out("stopped") / "eye.exr"),
            test::readFile(studies.out("fixed") / "eye.exr"))
      << "the stopped study's map is the map of as many samples";

  const int seeds = 100;
  int held = 0, samples = 0;
  for (int seed = 1; seed <= seeds; ++seed) {
    const test::Outcome run =
        studies.run("seed", R"("precision": 0.1, "seed": )" + std::to_string(seed));
    ASSERT_EQ(run.status, 0) << run.err;
    const auto [lower, upper] = studies.eyeInterval("seed");
    ASSERT_LE(0.5 * (upper - lower), 0.1) << "seed " << seed;
    held += lower <= truth && truth <= upper ? 1 : 0;
    samples += nlohmann::json::parse(std::ifstream(studies.out("seed") / "summary.json"))
                   .at("precision")
                   .at("jitter_samples")
                   .get<int>();
  }
  const double rate = static_cast<double>(held) / seeds;
  EXPECT_GE(rate, 0.95 - 3.0 * std::sqrt(0.95 * 0.05 / seeds)) << held << " of " << seeds;
  std::printf(
      "[ coverage ] jittered mirror, stopping at ±0.1: the 95 %% intervals held p = %.4f in %d "
      "of %d seeds, after %.1f jitter samples on average\n",
      truth, held, seeds, static_cast<double>(samples) / seeds);
}

// With a sweep beside the jitter, the scenarios of one jitter sample are not independent trials:
// the intervals would be too narrow and a precision reached too soon, so it is refused.
TEST(StudyPrecision, IsRefusedBesideASweepWhoseScenariosShareTheirJitter) {
  const JitterMirrorStudies studies("glint_study_precision_sweep");
  const test::Outcome run = studies.run("swept", R"("precision": 0.1)",
                                        R"("sweep": {"specular_reflectance": [0.9, 1.0]}, )");
  EXPECT_EQ(run.status, 2) << run.err;
  EXPECT_NE(run.err.find("/pointing_jitter/precision: a precision is for a study whose only "
                         "variation is the jitter; this one has 2 combinations"),
            std::string::npos)
      << run.err;
  EXPECT_FALSE(std::filesystem::exists(studies.out("swept")));
}

// A level beside the MPE in a study: each scenario counts where its irradiance reaches the
// level's threshold, and the map gives that share with its interval as for the MPE. In the
// jittered mirror's pencil the eye sees 0.9 × 100 W / (π 0.25 m²) = 114.6 W/m² or nothing: a
// level of 10 W/m² is reached exactly where the MPE (50 W/m²) is, and one of 200 W/m² nowhere.
// The per-scenario records agree with the map, and the summary gives each level's share.
TEST(ClopperPearson, EachLevelOfAStudyHasItsCoverageAndIntervalAsTheMpeHas) {
  const JitterMirrorStudies studies("glint_coverage_levels");
  nlohmann::json scene = nlohmann::json::parse(
      std::ifstream(std::filesystem::path(GLINT_TEST_DATA_DIR) / "jitter_mirror.json"));
  scene["hazard"] = {{"levels",
                      {{{"name", "glare"}, {"irradiance_w_m2", 10.0}},
                       {{"name", "beyond_the_pencil"}, {"irradiance_w_m2", 200.0}}}}};
  std::ofstream(studies.dir / "jitter_mirror.json") << scene.dump();
  const test::Outcome run = studies.run("levels", R"("samples": 40, "seed": 3)");
  ASSERT_EQ(run.status, 0) << run.err;
  const std::string map = (studies.out("levels") / "eye.exr").string();
  int w = 0, h = 0;
  for (const char* channel : {"coverage_probability", "coverage_lower", "coverage_upper"}) {
    const std::vector<float> mpe = readExrChannel(map, channel, w, h);
    const std::vector<float> glare = readExrChannel(map, std::string("glare_") + channel, w, h);
    const std::vector<float> none =
        readExrChannel(map, std::string("beyond_the_pencil_") + channel, w, h);
    ASSERT_EQ(glare.size(), mpe.size()) << channel;
    ASSERT_EQ(none.size(), mpe.size()) << channel;
    for (std::size_t i = 0; i < mpe.size(); ++i) {
      EXPECT_EQ(glare[i], mpe[i]) << channel << " " << i;
      if (std::string(channel) != "coverage_upper") {
        EXPECT_EQ(none[i], 0.0F) << channel << " " << i;
      }
    }
  }
  // Nothing reached in 40 scenarios: the upper end is 1 − 0.025^(1/40).
  EXPECT_NEAR(static_cast<double>(readExrChannel(map, "beyond_the_pencil_coverage_upper", w, h)[0]),
              1.0 - std::pow(0.025, 1.0 / 40.0), 1e-6);
  const double cover = static_cast<double>(readExrChannel(map, "coverage_probability", w, h)[0]);
  EXPECT_GT(cover, 0.2) << "premise: the pencil covers the eye in some scenarios";
  EXPECT_LT(cover, 0.8) << "premise: and misses it in others";
  const nlohmann::json summary =
      nlohmann::json::parse(std::ifstream(studies.out("levels") / "summary.json"));
  const nlohmann::json& region = summary.at("regions").at(0);
  EXPECT_EQ(region.at("levels").at("glare").at("scenarios_reaching"),
            region.at("scenarios_with_hazard"))
      << region.dump();
  EXPECT_EQ(region.at("levels").at("beyond_the_pencil").at("scenarios_reaching"), 0)
      << region.dump();
}

}  // namespace
}  // namespace glint
