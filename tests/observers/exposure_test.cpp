// Engagements in time: the motion's bounds, the swept beam's, the windows of a varying exposure,
// and the adaptive time sampling against an independent fine-step integration.
#include "observers/exposure.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <tuple>
#include <utility>

#include "hazard/exposure_window.h"
#include "observers/motion.h"
#include "pipeline/input/scene.h"
#include "pipeline/setup/target_builder.h"
#include "support/exposure_compare.h"

namespace glint {
namespace {

// A 0.3 m mirror disk at the origin facing a 1 kW Gaussian beam from −x (1064 nm, 10 s: MPE
// 50 W/m²), its lobe σ = @p sigma, moved over [−0.5, 0.5] s by @p target and the laser's
// @p pointing, time sampled by @p time.
std::string mirrorEngagement(double sigma, const std::string& target,
                             const std::string& pointing = "fixed",
                             const std::string& time = "{}") {
  return R"({"laser": {"position": [-100, 0, 0], "direction": [1, 0, 0], "power_w": 1000,
             "wavelength_nm": 1064, "exposure_s": 10, "beam": {"profile": "gaussian", "w_m": 1.0}},
   "materials": {"m": {"specular_reflectance": 0.9, "sigma": )" +
         std::to_string(sigma) + R"(}},
   "objects": [{"shape": "disk", "center": [0, 0, 0], "normal": [-1, 0, 0], "radius": 0.3,
                "material": "m", "segments": 8}],
   "engagement": {"start_s": -0.5, "end_s": 0.5, "target": )" +
         target + R"(, "laser": {"pointing": ")" + pointing + R"("}, "time": )" + time + "}}";
}

// The disk turning about z at @p turn_deg_s: its reflection sweeps across observers 50 m back
// at 2 × turn × 50 m per second, a glint of about (disk + lobe) / speed.
std::string turningMirror(double turn_deg_s, double sigma, const std::string& time = "{}") {
  return mirrorEngagement(sigma, R"({"turn_deg_s": [)" + std::to_string(turn_deg_s) + ", 0, 0]}",
                          "fixed", time);
}

// The disk crossing a tracking beam at 300 m/s along y: its reflection reaches x = −50 at y =
// 1.5 × the disk's y, so it sweeps past observers there at 450 m/s, a glint of about
// (0.9 m + 4σ × 50 m) / 450 m/s.
std::string crossingMirror(double sigma) {
  return mirrorEngagement(sigma, R"({"velocity_m_s": [0, 300, 0]})", "track");
}

std::vector<Vec3> crossingObservers() {
  std::vector<Vec3> points;
  for (int i = 0; i <= 6; ++i) points.emplace_back(-50.0, -101.0 + 33.0 * i, 0.3);
  return points;
}

std::vector<Vec3> observerLine() {
  std::vector<Vec3> points;
  for (int i = 0; i <= 10; ++i) points.emplace_back(-50.0, -15.0 + 3.0 * i, 0.5);
  return points;
}

MotionSpec splineSpec() {
  MotionSpec m;
  m.start_s = 0.0;
  m.end_s = 3.0;
  m.pivot_m = Vec3(1.0, 2.0, 3.0);
  m.interpolation = PoseInterpolation::Spline;
  m.poses = {{0.0, Vec3(0.0), Vec3(0.0)},
             {1.0, Vec3(30.0, 5.0, 0.0), Vec3(20.0, -10.0, 5.0)},
             {1.5, Vec3(40.0, -5.0, 2.0), Vec3(45.0, 0.0, -30.0)},
             {3.0, Vec3(100.0, 0.0, 10.0), Vec3(90.0, 15.0, 0.0)}};
  m.pointing = LaserPointing::Track;
  m.observer_velocity_m_s = Vec3(0.0, 20.0, 0.0);
  return m;
}

Beam laserFromMinusX() {
  Beam b;
  b.origin_m = Vec3(-200.0, 10.0, 0.0);
  b.direction = glm::normalize(Vec3(1.0, -0.05, 0.01));
  b.radius_m = 0.5;
  return b;
}

TEST(Motion, AConstantVelocityCrossingMovesTheWorldBackThroughTheTargetsFrame) {
  MotionSpec m;
  m.start_s = -1.0;
  m.end_s = 1.0;
  m.poses = {{-1.0, Vec3(-300.0, 0.0, 0.0), Vec3(0.0)}, {1.0, Vec3(300.0, 0.0, 0.0), Vec3(0.0)}};
  const Motion motion(m, laserFromMinusX());
  for (double t : {-1.0, -0.3, 0.0, 0.7, 1.0}) {
    const Vec3 q = motion.toTargetFrame(t, Vec3(5.0, 6.0, 7.0));
    EXPECT_NEAR(q.x, 5.0 - 300.0 * t, 1e-9) << "t = " << t;
    EXPECT_NEAR(q.y, 6.0, 1e-12) << "t = " << t;
  }
  const MotionRates r = motion.ratesOver(-0.2, 0.4);
  EXPECT_NEAR(r.target_speed_m_s, 300.0, 1e-9) << "a linear pose's speed is its chord's";
  EXPECT_EQ(r.target_turn_rad_s, 0.0);
}

// The rate bounds of a spline hold wherever it is sampled: finite differences of the pose, the
// tracking laser's direction and the observer's place never move faster than the bounds say.
TEST(Motion, SweepBoundsHoldAtEveryInstantOfASplineEngagement) {
  const Motion motion(splineSpec(), laserFromMinusX());
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0.0, 3.0), len(1e-3, 0.4);
  const Vec3 observer(-50.0, 30.0, 1.5);
  for (int trial = 0; trial < 300; ++trial) {
    const double t0 = u(rng), t1 = std::min(3.0, t0 + len(rng)), mid = 0.5 * (t0 + t1);
    const Beam swept = motion.sweptBeam(t0, t1);
    const double observer_sweep = motion.observerSweepM(t0, t1, observer);
    const Vec3 observer_mid = motion.toTargetFrame(mid, motion.observerAt(mid, observer));
    for (int k = 0; k <= 20; ++k) {
      const double t = t0 + (t1 - t0) * k / 20.0;
      const Beam b = motion.beamAt(t);
      ASSERT_LE(glm::length(b.origin_m - swept.origin_m), swept.sweep_offset_m * (1 + 1e-9) + 1e-9)
          << "laser outside the sweep at t = " << t << " of [" << t0 << ", " << t1 << "]";
      ASSERT_LE(angleBetween(b.direction, swept.direction),
                swept.sweep_angle_rad * (1 + 1e-9) + 1e-12)
          << "beam turned beyond the sweep at t = " << t;
      const Vec3 x = motion.toTargetFrame(t, motion.observerAt(t, observer));
      ASSERT_LE(glm::length(x - observer_mid), observer_sweep * (1 + 1e-9) + 1e-9)
          << "observer outside its sweep at t = " << t;
    }
  }
}

TEST(Motion, ATrackingLaserKeepsItsAxisOnTheSamePointOfTheTarget) {
  const MotionSpec spec = splineSpec();
  const Beam laser = laserFromMinusX();
  const Motion motion(spec, laser);
  // Seen from the target, the beam's axis passes through the same point at every instant.
  const double along = glm::dot(spec.pivot_m - laser.origin_m, laser.direction);
  const Vec3 aim = laser.origin_m + along * laser.direction;
  for (double t : {0.0, 0.4, 1.2, 2.9}) {
    const Beam b = motion.beamAt(t);
    const Vec3 rel = aim - b.origin_m;
    const double miss = glm::length(rel - glm::dot(rel, b.direction) * b.direction);
    EXPECT_LT(miss, 1e-9 * glm::length(rel)) << "t = " << t;
  }
}

// Keyed directions through a tracking laser's own directions meet it at every key, and turn at
// a constant rate between: the keyed laser's bound over an interval holds its instants too.
TEST(Motion, KeyedDirectionsRunAtAConstantRateBetweenTheirKeys) {
  MotionSpec tracking = splineSpec();
  const Beam laser = laserFromMinusX();
  const Motion track(tracking, laser);
  MotionSpec keyed = tracking;
  keyed.pointing = LaserPointing::Keyed;
  for (double t : {0.0, 0.5, 1.0, 2.0, 3.0})
    keyed.laser_keys.push_back({t, track.laserDirectionAt(t)});
  const Motion motion(keyed, laser);
  for (double t : {0.0, 0.5, 1.0, 2.0, 3.0}) {
    EXPECT_LT(angleBetween(motion.laserDirectionAt(t), track.laserDirectionAt(t)), 1e-12)
        << "at the key " << t;
  }
  // Halfway between two keys the direction is halfway along the great circle.
  const Vec3 a = keyed.laser_keys[3].direction, b = keyed.laser_keys[4].direction;
  const Vec3 mid = motion.laserDirectionAt(2.5);
  EXPECT_NEAR(angleBetween(a, mid), 0.5 * angleBetween(a, b), 1e-12);
  EXPECT_NEAR(angleBetween(mid, b), 0.5 * angleBetween(a, b), 1e-12);
  EXPECT_NEAR(motion.ratesOver(2.1, 2.9).laser_turn_rad_s, angleBetween(a, b) / 1.0, 1e-12);
}

// An observer riding a platform at the target's own velocity (the target not turning) stays
// where it is in the target's frame.
TEST(Motion, AnObserverRidingWithTheTargetStandsStillInItsFrame) {
  MotionSpec m;
  m.start_s = 0.0;
  m.end_s = 2.0;
  m.poses = {{0.0, Vec3(0.0), Vec3(0.0)}, {2.0, Vec3(40.0, -20.0, 6.0), Vec3(0.0)}};
  m.observer_velocity_m_s = Vec3(20.0, -10.0, 3.0);
  const Motion motion(m, laserFromMinusX());
  const Vec3 start(5.0, 50.0, 1.0);
  for (double t : {0.0, 0.7, 2.0}) {
    EXPECT_LT(glm::length(motion.toTargetFrame(t, motion.observerAt(t, start)) - start), 1e-12)
        << "t = " << t;
  }
}

// A triangle of height E and half-width a: a centred window of t ≤ 2a collects E t − E t²/(4a),
// and the irradiance is at or above θ for 2a (1 − θ/E).
TEST(ExposureWindow, ATrianglesLargestWindowAndTimeAboveAreItsClosedForms) {
  const std::vector<double> t{0.0, 1.0, 1.2, 1.4, 3.0};
  const std::vector<double> e{0.0, 0.0, 10.0, 0.0, 0.0};
  const double a = 0.2, top = 10.0;
  for (double tau : {0.01, 0.1, 0.25, 0.4}) {
    const WindowExposure w = largestWindowExposure(t, e, tau);
    EXPECT_NEAR(w.exposure_j_m2, top * tau - top * tau * tau / (4 * a), 1e-12) << "t = " << tau;
    EXPECT_NEAR(w.start_s, 1.2 - 0.5 * tau, 1e-9) << "the best window is centred, t = " << tau;
  }
  EXPECT_NEAR(largestWindowExposure(t, e, 5.0).exposure_j_m2, top * a, 1e-12);
  EXPECT_NEAR(timeAtOrAbove(t, e, 2.5), 2 * a * (1 - 2.5 / top), 1e-12);
}

// A rectangular exposure E0 for D at 1064 nm: H_max(t) = E0 min(t, D), and the MPE grows as
// t^0.75 there, so the ratio rises as t^0.25 to t = D and falls after: the worst window is the
// pulse itself, E0 D / MPE(D).
TEST(ExposureWindow, AConstantExposureIsWorstOverItsOwnLength) {
  HazardSpec h;
  h.wavelength_nm = 1064.0;
  for (double d : {2e-3, 0.05, 0.8}) {
    const std::vector<double> t{0.0, 1.0, 1.0 + 1e-12, 1.0 + d, 1.0 + d + 1e-12, 3.0};
    const std::vector<double> e{0.0, 0.0, 400.0, 400.0, 0.0, 0.0};
    const WindowHazard w = worstWindow(t, e, h, 10.0);
    const double exact = 400.0 * d / ocularMpe(1064.0, d).radiant_exposure_j_m2;
    EXPECT_GE(w.ratio, exact * (1 - 1e-9)) << "never below the worst window, D = " << d;
    EXPECT_LE(w.ratio, exact * (1 + 1.1e-3)) << "within the search's 0.1 %, D = " << d;
    EXPECT_NEAR(w.duration_s, d, 0.02 * d) << "D = " << d;
  }
}

// Within each row of the tables the MPE as radiant exposure never falls as the duration grows,
// at every wavelength row glint uses, for either standard and tissue: what the window search's
// bound H_max(b) / MPE(a) rests on between the rows' edges.
TEST(ExposureWindow, TheMpeAsRadiantExposureGrowsWithDurationWithinEachRow) {
  const std::vector<double>& edges = mpeRowEdgesS();
  for (SafetyStandard standard :
       {SafetyStandard::AnsiZ136_1_2014, SafetyStandard::Iec60825_1_2014}) {
    for (Tissue tissue : {Tissue::Eye, Tissue::Skin}) {
      for (double nm : {400.0, 450.0, 532.0, 600.0, 700.0, 905.0, 1064.0, 1200.0, 1300.0, 1450.0,
                        1550.0, 2000.0, 10600.0}) {
        double before = 0.0, previous_t = 0.0;
        for (double lg = -9.0; lg <= 4.4; lg += 0.002) {
          const double t = std::pow(10.0, lg);
          const bool new_row = std::any_of(edges.begin(), edges.end(),
                                           [&](double e) { return previous_t < e && e <= t; });
          const double h = tableMpe(nm, t, standard, tissue).radiant_exposure_j_m2;
          if (!new_row) {
            ASSERT_GE(h, before * (1 - 1e-12)) << clauses(standard).name << " " << toString(tissue)
                                               << " " << nm << " nm at " << t << " s";
          }
          before = h;
          previous_t = t;
        }
      }
    }
  }
}

struct Compared {
  test::ExposureErrors errors;  // of the adaptive samples against the fine steps
  std::size_t adaptive_samples = 0, uniform_samples = 0;
};

struct Engagement {
  Scene scene;
  FacetIntegrator reference;
  Motion motion;
  explicit Engagement(const std::string& json)
      : scene(parseScene(json, "test.json")),
        reference(buildIntegrator(scene, scene.accuracy)),
        motion(scene.engagement->motion, scene.laser) {}
};

// The adaptive sampling against uniform steps 100 times finer than its own mean step, at
// every observer above 1 % of the brightest peak; and the fine steps themselves.
Compared compareWithFineSteps(const Engagement& e, const std::vector<Vec3>& points,
                              std::vector<ExposureHistory>* fine_out = nullptr) {
  const std::vector<ExposureHistory> adaptive =
      integrateExposures(e.reference, e.motion, points, e.scene.engagement->time);
  Compared c;
  c.adaptive_samples = test::sampleCount(adaptive);
  for (const ExposureHistory& h : adaptive) EXPECT_TRUE(h.converged);
  const double mean_step = e.motion.durationS() * static_cast<double>(points.size()) /
                           static_cast<double>(c.adaptive_samples - points.size());
  const int steps = static_cast<int>(std::ceil(100.0 * e.motion.durationS() / mean_step));
  std::vector<ExposureHistory> fine = uniformExposures(e.reference, e.motion, points, steps);
  c.uniform_samples = static_cast<std::size_t>(steps + 1) * points.size();
  c.errors = test::exposureErrors(adaptive, fine);
  if (fine_out != nullptr) *fine_out = std::move(fine);
  return c;
}

TEST(Exposure, AGlintSweepingPastMatchesFineUniformStepsWithinOnePercent) {
  const Compared c = compareWithFineSteps(Engagement(turningMirror(20.0, 0.005)), observerLine());
  std::printf(
      "turning mirror: adaptive, %zu samples: exposure within %.2e, peak within %.2e of "
      "%zu uniform samples\n",
      c.adaptive_samples, c.errors.exposure, c.errors.peak, c.uniform_samples);
  EXPECT_LT(c.errors.exposure, 0.01) << "exposure against the fine steps";
  EXPECT_LT(c.errors.peak, 0.01) << "peak against the fine steps";
}

// With one initial interval, the glint at every observer lies between the first samples, where
// both ends see nothing: only the bound can say the interval is not dark.
TEST(Exposure, AGlintBetweenTheFirstSamplesIsFoundByTheBound) {
  const Compared c = compareWithFineSteps(
      Engagement(turningMirror(20.0, 0.002, R"({"initial_intervals": 1})")), observerLine());
  EXPECT_LT(c.errors.exposure, 0.01) << "every glint found and followed";
  EXPECT_LT(c.errors.peak, 0.01);
}

// On a crossing target, uniform steps need more than ten times the adaptive samples to reach
// the same 1 %: the glint lasts a few milliseconds of the second, and uniform steps must resolve
// it everywhere to resolve it where it is.
TEST(Exposure, ACrossingGlintNeedsTenfoldMoreUniformStepsForOnePercent) {
  const Engagement e(crossingMirror(0.002));
  const std::vector<Vec3> points = crossingObservers();
  std::vector<ExposureHistory> fine;
  const Compared c = compareWithFineSteps(e, points, &fine);
  EXPECT_LT(c.errors.exposure, 0.01);
  EXPECT_LT(c.errors.peak, 0.01);
  // The coarsest uniform steps (by doubling) within 1 % of the fine ones at every observer.
  int steps = 64;
  for (;; steps *= 2) {
    if (test::exposureErrors(uniformExposures(e.reference, e.motion, points, steps), fine)
            .within(0.01)) {
      break;
    }
    ASSERT_LT(steps, 1 << 16) << "uniform steps never reached 1 %";
  }
  const double uniform = static_cast<double>(steps + 1) * static_cast<double>(points.size());
  std::printf(
      "crossing mirror: adaptive %zu samples within %.2e (exposure) and %.2e (peak); "
      "uniform steps need %d steps, %.0f samples, for 1 %%: %.1f x the adaptive\n",
      c.adaptive_samples, c.errors.exposure, c.errors.peak, steps, uniform,
      uniform / static_cast<double>(c.adaptive_samples));
  EXPECT_GE(uniform, 10.0 * static_cast<double>(c.adaptive_samples));
}

// A 2 ms glint at random places along the crossing mirror's path, from a single initial
// interval: wherever it crosses, between whichever samples, the bound finds it and the samples
// follow it to 1 % of uniform steps a hundred times finer.
TEST(Exposure, NoGlintIsSkippedWhereverItCrossesBetweenTheSamples) {
  const Engagement e(mirrorEngagement(0.001, R"({"velocity_m_s": [0, 300, 0]})", "track",
                                      R"({"initial_intervals": 1})"));
  std::mt19937_64 rng(38);
  std::uniform_real_distribution<double> y(-140.0, 140.0), z(-0.3, 0.3);
  std::vector<Vec3> points;
  for (int i = 0; i < 20; ++i) points.emplace_back(-50.0, y(rng), z(rng));
  std::vector<ExposureHistory> fine;
  const Compared c = compareWithFineSteps(e, points, &fine);
  for (std::size_t i = 0; i < points.size(); ++i) {
    EXPECT_GT(fine[i].peak_w_m2, 10.0) << "every observer lies on the glint's path: " << i;
  }
  EXPECT_LT(c.errors.exposure, 0.01);
  EXPECT_LT(c.errors.peak, 0.01);
  std::printf(
      "random crossings: %zu adaptive samples, exposure within %.2e, peak within %.2e of "
      "%zu uniform samples\n",
      c.adaptive_samples, c.errors.exposure, c.errors.peak, c.uniform_samples);
}

// An observer no reflection can reach (behind the mirror) is proven dark by its first bounds:
// it costs its first samples and nothing more.
TEST(Exposure, AnObserverNoGlintCanReachCostsOnlyItsFirstSamples) {
  const Scene scene = parseScene(turningMirror(20.0, 0.005), "test.json");
  const FacetIntegrator reference = buildIntegrator(scene, scene.accuracy);
  const Motion motion(scene.engagement->motion, scene.laser);
  const std::vector<Vec3> behind{Vec3(30.0, 0.0, 0.0)};
  const std::vector<ExposureHistory> h =
      integrateExposures(reference, motion, behind, scene.engagement->time);
  EXPECT_EQ(h[0].time_s.size(),
            static_cast<std::size_t>(scene.engagement->time.initial_intervals + 1));
  EXPECT_EQ(h[0].exposure_j_m2, 0.0);
  EXPECT_TRUE(h[0].converged);
}

}  // namespace
}  // namespace glint
