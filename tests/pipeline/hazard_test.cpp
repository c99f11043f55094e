// The hazard module: pulse trains' MPE by the worked examples of the standards, the air's
// extinction, optical aids, and what each does to a scene's irradiance and hazard.
#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>

#include "observers/far_field.h"
#include "pipeline/input/scene.h"
#include "pipeline/report/hazard_report.h"
#include "pipeline/setup/target_builder.h"
#include "support/refusal.h"

namespace glint {
namespace {

using nlohmann::json;

PulseSpec train(double duration_s, double rate_hz) { return {1e-3, duration_s, rate_hz}; }

// The textbook Q-switched Nd:YAG: 1064 nm, 10 ns pulses at 10 Hz viewed for 10 s, worked by
// hand from the standard's rows. Rule 1: 2.0e-6 J/cm² (Table 5a, 1050–1400 nm below 13 µs, C_C =
// 1); rule 2: 5 mW/cm² × 10 s over 100 pulses = 5e-4 J/cm²; rule 3: 2.0e-6 × 100^-0.25 = 6.3e-7
// J/cm², the limit.
TEST(PulseTrainMpe, QSwitchedNdYagAtTenHertzForTenSecondsIsSetByRuleThree) {
  const PulseTrainMpe m = pulseTrainMpe(1064.0, train(10e-9, 10.0), 10.0);
  EXPECT_DOUBLE_EQ(m.pulses, 100.0);
  EXPECT_FALSE(m.grouped);
  EXPECT_NEAR(m.single_pulse_j_m2, 2.0e-2, 1e-15) << "2.0e-6 J/cm²";
  EXPECT_NEAR(m.average_j_m2, 5.0, 1e-12) << "500 J/m² over 100 pulses";
  EXPECT_NEAR(m.c_p, 1.0 / std::sqrt(10.0), 1e-15) << "100^-0.25";
  EXPECT_EQ(m.rule, 3);
  EXPECT_NEAR(m.per_pulse_j_m2, 2.0e-2 / std::sqrt(10.0), 1e-15) << "6.32e-7 J/cm²";
}

// Beyond 1400 nm there is no rule 3: 1550 nm, 10 ns at 10 Hz for 10 s. Rule 1: 1 J/cm² (flat to
// 10 s); rule 2: 0.1 W/cm² × 10 s over 100 pulses = 1e-2 J/cm², the limit.
TEST(PulseTrainMpe, BeyondTheRetinalRegionTheAverageRuleSetsIt) {
  const PulseTrainMpe m = pulseTrainMpe(1550.0, train(10e-9, 10.0), 10.0);
  EXPECT_NEAR(m.single_pulse_j_m2, 1.0e4, 1e-9);
  EXPECT_NEAR(m.average_j_m2, 100.0, 1e-9);
  EXPECT_EQ(m.reduced_j_m2, 0.0) << "no rule 3 outside 400–1400 nm";
  EXPECT_EQ(m.rule, 2);
  EXPECT_NEAR(m.per_pulse_j_m2, 100.0, 1e-9);
}

// A 1 MHz train at 532 nm: pulses 1 µs apart, closer than t_min = 5 µs, count as groups of 5 at
// 200 kHz. Its MPE as mean irradiance then equals the continuous MPE for the same 0.25 s
// (18 t^0.75 J/m² / t): the retina cannot tell it from a continuous beam.
TEST(PulseTrainMpe, AMegahertzTrainIsJudgedAsTheContinuousBeamItLooksLike) {
  const PulseTrainMpe m = pulseTrainMpe(532.0, train(1e-9, 1e6), 0.25);
  EXPECT_TRUE(m.grouped);
  EXPECT_DOUBLE_EQ(m.pulses, 0.25 / 5e-6);
  const double continuous_w_m2 = 18.0 * std::pow(0.25, 0.75) / 0.25;
  EXPECT_NEAR(m.per_pulse_j_m2 * 1e6, continuous_w_m2, 1e-9 * continuous_w_m2);
}

// Rule 2 makes every train at least as restrictive as a continuous beam of its mean power.
TEST(PulseTrainMpe, NoTrainIsLessRestrictiveThanContinuousLightOfItsMeanPower) {
  for (double nm : {450.0, 532.0, 633.0, 800.0, 1064.0, 1300.0, 1550.0, 2000.0, 10600.0})
    for (double tau : {1e-9, 1e-7, 1e-5, 1e-3})
      for (double f : {1.0, 10.0, 1e3, 1e5})
        for (double t : {0.25, 10.0, 100.0}) {
          if (tau * f > 1.0 || f * t < 1.0) continue;
          const PulseTrainMpe m = pulseTrainMpe(nm, train(tau, f), t);
          const double cw = ocularMpe(nm, t).irradiance_w_m2;
          EXPECT_LE(m.per_pulse_j_m2 * f, cw * (1.0 + 1e-12))
              << nm << " nm, " << tau << " s at " << f << " Hz for " << t << " s";
          EXPECT_GT(m.per_pulse_j_m2, 0.0);
        }
}

// Kim's and Kruse's relations agree at 550 nm, where visibility is defined: μ = 3.912 / V.
TEST(Atmosphere, VisibilityGivesTheKoschmiederExtinctionAt550Nanometres) {
  for (double v : {200.0, 800.0, 3000.0, 23000.0, 80000.0}) {
    for (VisibilityModel model : {VisibilityModel::Kim, VisibilityModel::Kruse}) {
      EXPECT_NEAR(extinctionFromVisibility(v, 550.0, model), 3.912 / v, 1e-15 / v) << v << " m";
    }
  }
}

// Clear air (23 km, q = 1.3) attenuates 1064 nm less than 550 nm by (1064/550)^-1.3; Kim's fog
// (below 500 m, q = 0) is grey.
TEST(Atmosphere, WavelengthDependenceFollowsTheModelsExponent) {
  EXPECT_NEAR(extinctionFromVisibility(23e3, 1064.0, VisibilityModel::Kim),
              3.912 / 23e3 * std::pow(1064.0 / 550.0, -1.3), 1e-18);
  EXPECT_NEAR(extinctionFromVisibility(400.0, 1064.0, VisibilityModel::Kim), 3.912 / 400.0, 1e-15);
  const double q = 0.585 * std::cbrt(0.4);
  EXPECT_NEAR(extinctionFromVisibility(400.0, 1064.0, VisibilityModel::Kruse),
              3.912 / 400.0 * std::pow(1064.0 / 550.0, -q), 1e-15);
}

// 7×50 binoculars: the 50 mm objective would gather (50/7)² = 51× a 7 mm pupil's power, but the
// 7.1 mm exit pupil caps the gain at M² = 49; with τ = 0.7, 34.3. 8×20: the objective limits it,
// (20/7)² τ = 5.71.
TEST(OpticalAid, GainIsTransmissionTimesTheSmallerOfMagnificationAndApertureRatioSquared) {
  EXPECT_NEAR(opticalGain(0.050, 7.0, 0.7, 1064.0), 0.7 * 49.0, 1e-12);
  EXPECT_NEAR(opticalGain(0.020, 8.0, 0.7, 532.0), 0.7 * std::pow(20.0 / 7.0, 2), 1e-12);
  EXPECT_NEAR(opticalGain(0.020, 8.0, 0.7, 1550.0), 0.7 * 64.0, 1e-12)
      << "beyond 1400 nm the limiting aperture is 1 mm: the magnification limits";
}

// The distance at which a source's irradiance, attenuated, falls to the threshold.
TEST(HazardDistance, SolvesTheAttenuatedInverseSquareLaw) {
  EXPECT_DOUBLE_EQ(hazardDistance(1e4, 1.0, 0.0, 0.5), 100.0) << "vacuum: √(I/E)";
  const double mu = 2e-3, a = 0.5;
  const double r = hazardDistance(1e4, 1.0, mu, a);
  EXPECT_NEAR(1e4 * std::exp(-mu * (r - a)) / (r * r), 1.0, 1e-9) << r;
  EXPECT_LT(r, 100.0);
  EXPECT_EQ(hazardDistance(0.0, 1.0, mu, a), 0.0);
  EXPECT_TRUE(std::isinf(hazardDistance(std::nan(""), 1.0, mu, a))) << "fail safe";
}

// A small scene: a Lambertian disk facing the laser, 10 m away, 1 W flat-top beam.
json diskScene() {
  return json::parse(R"({
    "laser": {"position": [-10, 0, 0], "direction": [1, 0, 0], "power_w": 1.0,
              "wavelength_nm": 1064, "beam": {"profile": "flat_top", "radius_m": 0.2}},
    "materials": {"white": {"specular_reflectance": 0.0, "sigma": 0.1,
                            "diffuse_reflectance": 0.8}},
    "objects": [{"shape": "disk", "center": [0, 0, 0], "normal": [-1, 0, 0], "radius": 0.05,
                 "material": "white"}],
    "accuracy": {"tolerance": 1e-7}
  })");
}

double irradianceAt(const json& scene_json, const Vec3& observer_m) {
  const Scene scene = parseScene(scene_json.dump(), "scene.json");
  const FacetIntegrator integrator(buildTarget(scene), scene.laser, scene.accuracy);
  IntegratorWorkspace ws;
  return integrator.adaptive(observer_m, ws).irradiance_w_m2;
}

// Beer–Lambert on both legs: 10 m from the laser to the disk and 20 m back to the observer, so
// the irradiance falls by exp(−30 μ), to within the disk's extent (±5 cm of path: ±1e-4).
TEST(Atmosphere, AttenuatesTheLaserPathAndTheReflectedPath) {
  const Vec3 observer(-20.0, 1.0, 0.0);
  json scene = diskScene();
  const double vacuum = irradianceAt(scene, observer);
  scene["atmosphere"] = {{"extinction_per_m", 1e-3}};
  const double air = irradianceAt(scene, observer);
  const double path_m = 10.0 + std::hypot(20.0, 1.0);
  EXPECT_NEAR(air / vacuum, std::exp(-1e-3 * path_m), 2e-4 * std::exp(-1e-3 * path_m))
      << "vacuum " << vacuum << " W/m², air " << air << " W/m²";
}

TEST(SceneHazard, PulseTrainSetsTheMeanIrradianceMpeAndPulseExposure) {
  json j = diskScene();
  j["laser"].erase("power_w");
  j["laser"]["pulse"] = {{"energy_j", 0.1}, {"duration_s", 10e-9}, {"repetition_rate_hz", 10}};
  const Scene s = parseScene(j.dump(), "scene.json");
  EXPECT_DOUBLE_EQ(s.laser.power_w, 1.0) << "0.1 J × 10 Hz";
  EXPECT_EQ(s.hazard.exposure_s, 10.0);
  ASSERT_TRUE(s.hazard.train.has_value());
  EXPECT_NEAR(s.hazard.mpe_w_m2, 10.0 * 2e-2 / std::sqrt(10.0), 1e-12)
      << "6.32e-3 J/m² a pulse at 10 Hz";
  EXPECT_DOUBLE_EQ(s.hazard.pulseRadiantExposureJ_m2(5.0), 0.5) << "E / f";
  EXPECT_NE(hazardCitation(s.hazard).find("rule 3"), std::string::npos) << hazardCitation(s.hazard);
}

TEST(SceneHazard, SinglePulseExposureIsItsDuration) {
  json j = diskScene();
  j["laser"]["pulse"] = {{"peak_power_w", 1.0}, {"duration_s", 1e-6}};
  const Scene s = parseScene(j.dump(), "scene.json");
  EXPECT_EQ(s.hazard.exposure_s, 1e-6);
  EXPECT_FALSE(s.hazard.exposure_default) << "the file gives the pulse's duration";
  EXPECT_EQ(hazardLine(s.hazard).find("default"), std::string::npos) << hazardLine(s.hazard);
  EXPECT_NEAR(s.hazard.pulse->energy_j, 1e-6, 1e-21);
  // 1064 nm below 13 µs: 2.0e-2 C_C J/m², as mean irradiance over 1 µs.
  EXPECT_NEAR(s.hazard.mpe_w_m2, 2.0e-2 / 1e-6, 1e-6);
  EXPECT_DOUBLE_EQ(s.hazard.pulseRadiantExposureJ_m2(1e4), 1e-2) << "E τ";
}

TEST(SceneHazard, RefusesAPulseThatDisagreesOrCannotBe) {
  json j = diskScene();
  j["laser"]["pulse"] = {{"energy_j", 0.2}, {"duration_s", 10e-9}, {"repetition_rate_hz", 10}};
  EXPECT_NE(test::refusalOf([&] {
              parseScene(j.dump(), "scene.json");
            }).find("is not the pulse's mean power"),
            std::string::npos);
  j["laser"]["pulse"] = {{"duration_s", 0.2}, {"repetition_rate_hz", 10}};
  EXPECT_NE(test::refusalOf([&] {
              parseScene(j.dump(), "scene.json");
            }).find("longer than the time between pulses"),
            std::string::npos);
  j["laser"]["pulse"] = {{"duration_s", 1e-8}};
  j["laser"]["exposure_s"] = 1.0;
  EXPECT_NE(test::refusalOf([&] {
              parseScene(j.dump(), "scene.json");
            }).find("a single pulse's exposure is its duration"),
            std::string::npos);
}

TEST(SceneHazard, OpticalAidScalesTheAidedRatioAndLowersTheFloorsDefault) {
  json j = diskScene();
  j["optical_aid"] = {{"aperture_m", 0.05}, {"magnification", 7}, {"transmission", 0.7}};
  const Scene s = parseScene(j.dump(), "scene.json");
  ASSERT_TRUE(s.hazard.aid.has_value());
  EXPECT_NEAR(s.hazard.aidGain(), 34.3, 1e-12);
  EXPECT_NEAR(s.hazard.aidedRatio(s.hazard.mpe_w_m2), 34.3, 1e-12);
  EXPECT_NEAR(s.hazard.lowestHazardousW_m2(), s.hazard.mpe_w_m2 / 34.3, 1e-15);
  j["laser"]["wavelength_nm"] = 10600;
  EXPECT_NE(test::refusalOf([&] { parseScene(j.dump(), "scene.json"); }).find("302.5 nm to 4000"),
            std::string::npos);
}

TEST(SceneHazard, AtmosphereFromVisibilityOrExtinctionButNotBoth) {
  json j = diskScene();
  j["atmosphere"] = {{"visibility_m", 23000}};
  const Scene s = parseScene(j.dump(), "scene.json");
  EXPECT_NEAR(s.hazard.atmosphere.extinction_per_m,
              extinctionFromVisibility(23000, 1064, VisibilityModel::Kim), 1e-18);
  EXPECT_NEAR(s.laser.extinction_per_m, s.hazard.atmosphere.extinction_per_m, 0.0);
  j["atmosphere"]["extinction_per_m"] = 1e-4;
  EXPECT_NE(test::refusalOf([&] { parseScene(j.dump(), "scene.json"); }).find("one of them"),
            std::string::npos);
}

// Issue 50 (3): the default floor was 1e-9 × the beam's peak irradiance, whatever the MPE. A
// 1.5 kW, 450 nm welding laser focused to 0.3 mm on a copper disk lights its spot at 5.3e9 W/m²,
// so the floor was 5.3 W/m², five times the 1 W/m² MPE of a 1000 s exposure: glint points read
// the diffuse glow at (5, 0, 5) and (6, 0, 6) as 0. The spot is a point at these distances (its
// radius a ten-thousandth of them), so the closed form is the BRDF at the spot times its power:
// E = P f_r cos θi cos θr / d², f_r = ρs Ξ(θN) / (4 cos θi cos θr) + ρd / π.
constexpr const char* kWeldingScene = R"({"laser": {"position": [0, 0, 10],
    "direction": [0, 0, -1], "power_w": 1500, "wavelength_nm": 450, "exposure_s": 1000,
    "beam": {"profile": "flat_top", "radius_m": 0.0003}},
  "materials": {"copper": {"specular_reflectance": 0.4, "sigma": 0.1, "diffuse_reflectance": 0.3}},
  "objects": [{"shape": "disk", "center": [0, 0, 0], "normal": [0, 0, 1], "radius": 0.05,
               "material": "copper"}]})";

double weldingSpotIrradiance(const Vec3& x) {
  const double d = glm::length(x), sigma = 0.1;
  const Vec3 wi(0.0, 0.0, 1.0), wo = x / d;
  const double cos_r = wo.z;
  const Vec3 h = glm::normalize(wi + wo);
  const double tan2 = (h.x * h.x + h.y * h.y) / (h.z * h.z);
  const double beckmann =
      std::exp(-tan2 / (2.0 * sigma * sigma)) / (2.0 * kPi * sigma * sigma * std::pow(h.z, 4));
  const double brdf = 0.4 * beckmann / (4.0 * cos_r) + 0.3 / kPi;
  return 1500.0 * brdf * cos_r / (d * d);
}

TEST(Floor, TheDefaultFloorStaysBelowALowMpeBesideAFocusedBeam) {
  const Scene s = parseScene(kWeldingScene, "welding.json");
  ASSERT_NEAR(s.hazard.mpe_w_m2, 1.0, 1e-12) << "premise: ANSI's 1e-4 W/cm² at 450 nm, 1000 s";
  EXPECT_LE(s.accuracy.floor_w_m2, 1e-3 * s.hazard.mpe_w_m2) << "the floor is tied to the MPE";
  const FacetIntegrator integrator = buildIntegrator(s, s.accuracy);
  IntegratorWorkspace ws;
  for (const Vec3& x : {Vec3(3, 0, 3), Vec3(5, 0, 5), Vec3(6, 0, 6)}) {
    const ObserverResult r = integrator.adaptive(x, ws);
    const double exact = weldingSpotIrradiance(x);
    EXPECT_TRUE(r.converged) << x.x;
    // The integrator's tolerance (1e-3) and the spot's size against the distance (1e-8).
    EXPECT_NEAR(r.irradiance_w_m2, exact, 2e-3 * exact)
        << "at (" << x.x << ", 0, " << x.z << "): hazard ratio " << r.irradiance_w_m2 << " of "
        << exact;
  }
}

// The same with binoculars of gain 1000: the aided MPE is 1e-3 W/m², and at 0.9 × the aided
// reach along 45° the aided hazard ratio is 1/0.81 = 1.23 (glint read 0).
TEST(Floor, TheDefaultFloorStaysBelowTheAidedMpeOfALargeGain) {
  nlohmann::json j = nlohmann::json::parse(kWeldingScene);
  j["optical_aid"] = {{"gain", 1000.0}};
  const Scene s = parseScene(j.dump(), "welding.json");
  EXPECT_LE(s.accuracy.floor_w_m2, 1e-3 * s.hazard.aidedMpeW_m2());
  const FacetIntegrator integrator = buildIntegrator(s, s.accuracy);
  IntegratorWorkspace ws;
  // The aided reach along (1, 0, 1)/√2: E(d) = E(1 m) / d² = aided MPE.
  const Vec3 along = glm::normalize(Vec3(1.0, 0.0, 1.0));
  const double reach_m = std::sqrt(weldingSpotIrradiance(along) / s.hazard.aidedMpeW_m2());
  const Vec3 x = 0.9 * reach_m * along;
  const double aided = s.hazard.aidedRatio(integrator.adaptive(x, ws).irradiance_w_m2);
  EXPECT_NEAR(aided, 1.0 / 0.81, 3e-3) << "at 0.9 × the aided reach of " << reach_m << " m";
}

// A floor set in the scene above a hundredth of the lowest hazardous irradiance could read a
// hazard as none: it is refused, for the integrator, the regions and an engagement's time.
TEST(Floor, AFloorThatCouldHideAHazardIsRefused) {
  nlohmann::json j = nlohmann::json::parse(kWeldingScene);
  j["accuracy"] = {{"floor_w_m2", 0.02}};
  EXPECT_EQ(test::refusalOf([&] { parseScene(j.dump(), "welding.json"); }),
            "welding.json: /accuracy/floor_w_m2: 0.02 W/m² could hide a hazard: it must be at "
            "most a hundredth of the lowest hazardous irradiance (the MPE, 1 W/m²), 0.01 W/m²");
  j["accuracy"] = {{"floor_w_m2", 0.01}};
  EXPECT_EQ(test::refusalOf([&] { parseScene(j.dump(), "welding.json"); }), "(accepted)");
  j["optical_aid"] = {{"gain", 10.0}};
  j["observers"] = {{"min", {-1, -1, 0}}, {"max", {1, 1, 1}}, {"voxel_m", 0.1}};
  const std::string aided = test::refusalOf([&] { parseScene(j.dump(), "welding.json"); });
  EXPECT_NE(aided.find("/accuracy/floor_w_m2: 0.01 W/m² could hide a hazard"), std::string::npos)
      << aided;
  EXPECT_NE(aided.find("the MPE through the optical aid, 0.1 W/m²"), std::string::npos) << aided;
  j["accuracy"] = {{"floor_w_m2", 1e-4}};
  j["observers"]["floor_w_m2"] = 0.01;
  const std::string box = test::refusalOf([&] { parseScene(j.dump(), "welding.json"); });
  EXPECT_NE(box.find("/observers/floor_w_m2: 0.01 W/m² could hide"), std::string::npos) << box;
}

}  // namespace
}  // namespace glint
