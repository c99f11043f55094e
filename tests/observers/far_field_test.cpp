// The far field by direction: the map's intensity against geometric optics, and against the
// near field integrated directly at observers from the far radius outward.
#include "observers/far_field.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <string>

#include "pipeline/scene.h"
#include "pipeline/target_builder.h"

namespace glint {
namespace {

constexpr double kPowerW = 1000.0;
constexpr double kBeamRadiusM = 2.0;

// A laser at -100 x shining along +x with a flat-top beam; `objects` and `sigma` spliced in;
// a coarse map (64 pixels per face) at tolerance 0.05.
Scene scene(const std::string& beam_radius, double sigma, const std::string& objects) {
  return parseScene(R"({"laser": {"position": [-100, 0, 0], "direction": [1, 0, 0],
      "power_w": 1000.0, "wavelength_nm": 1064, "beam": {"profile": "flat_top", "radius_m": )" +
                        beam_radius + R"(}}, "materials": {"m": {"specular_reflectance": 0.9,
      "sigma": )" + std::to_string(sigma) +
                        R"(}}, "objects": [)" + objects + R"(], "planes": [],
      "far_field": {"tolerance": 0.05, "face_pixels": 64}})",
                    "far.json");
}

struct Computed {
  SceneTarget target;
  FarField field;
};

Computed compute(const Scene& s, double floor_w_sr) {
  FieldSpec any;  // the integrator's accuracy is set per face by computeFarField()
  any.tolerance = 1e-2;
  SceneTarget target = sceneTarget(s, any);
  FarFieldSpec spec = farFieldSpec(s, target.integrator);
  spec.floor_w_sr = floor_w_sr;
  spec.block_pixels = 4;
  FarField field = computeFarField(target.integrator, spec);
  return {std::move(target), std::move(field)};
}

Vec3 randomDirection(std::mt19937_64& rng) {
  std::normal_distribution<double> g;
  for (;;) {
    const Vec3 v(g(rng), g(rng), g(rng));
    if (glm::length(v) > 1e-6) return glm::normalize(v);
  }
}

// A mirror sphere of radius R in a collimated beam of irradiance E sends ρ E R² / 4 into every
// direction it can reflect to (geometric optics); a Beckmann lobe of σ = 0.02 changes that by
// O(σ²) away from the forward shadow edge.
TEST(FarField, MirrorSphereSendsTheGeometricIntensityBackEverywhere) {
  const Scene s = scene(std::to_string(kBeamRadiusM), 0.02,
                        R"({"shape": "sphere", "center": [0, 0, 0], "radius": 1.0,
                            "material": "m"})");
  const double irradiance_w_m2 = kPowerW / (kPi * kBeamRadiusM * kBeamRadiusM);
  const double exact_w_sr = 0.9 * irradiance_w_m2 * 1.0 / 4.0;
  const Computed c = compute(s, 1e-3 * exact_w_sr);
  const FarField& f = c.field;
  EXPECT_GT(f.spec().far_radius_m, 100.0 * f.ball().radius_m) << "tolerance 0.05, σ = 0.02";
  std::mt19937_64 rng(17);
  int checked = 0;
  for (int n = 0; n < 400; ++n) {
    const Vec3 d = randomDirection(rng);
    // Within 80° of the way back to the laser: clear of the forward shadow's edge.
    if (-d.x < std::cos(80.0 * kPi / 180.0)) continue;
    ++checked;
    EXPECT_NEAR(f.intensity(d), exact_w_sr, 0.05 * exact_w_sr)
        << "direction (" << d.x << ", " << d.y << ", " << d.z << ")";
  }
  EXPECT_GT(checked, 100);
  EXPECT_NEAR(f.peak().intensity_w_sr, exact_w_sr, 0.05 * exact_w_sr);
}

struct NearFarCase {
  std::string name;
  std::string beam_radius;
  double sigma;
  std::string objects;
};

class NearAndFar : public testing::TestWithParam<NearFarCase> {};

// Observers at the far radius toward them and beyond receive I(ω)/r² within the promise:
// tolerance × the map's peak (farRadius()), the floor aside. Directions into the forward cone,
// where the far radius grows, are included. The cylinder is lit off its centre by a beam
// smaller than it, so no symmetry cancels the first-order parallax.
TEST_P(NearAndFar, DirectIntegrationAgreesWithTheMapFromTheFarRadiusOut) {
  const NearFarCase& p = GetParam();
  const Scene s = scene(p.beam_radius, p.sigma, p.objects);
  const Computed c = compute(s, 1e-6);
  const FarField& f = c.field;
  const double peak = f.peak().intensity_w_sr;
  ASSERT_GT(peak, 0.0);
  const FacetIntegrator direct = c.target.integrator.withAccuracy(1e-4, 1e-15);
  IntegratorWorkspace ws;
  std::mt19937_64 rng(5);
  double worst = 0.0;
  int lit = 0;
  for (int n = 0; n < 300; ++n) {
    const Vec3 d = randomDirection(rng);
    for (const double factor : {1.0, 3.0}) {
      const double r = factor * farRadiusToward(f.spec(), d);
      const ObserverResult o = direct.adaptive(f.ball().centre_m + r * d, ws);
      const double near_w_sr = o.irradiance_w_m2 * r * r;
      const double far_w_sr = f.intensity(d);
      if (near_w_sr > 1e-3 * peak) ++lit;
      const double error = std::abs(near_w_sr - far_w_sr) / peak;
      worst = std::max(worst, error);
      EXPECT_LE(error, f.spec().tolerance)
          << "r = " << r << " m toward (" << d.x << ", " << d.y << ", " << d.z << "): direct "
          << near_w_sr << " W/sr, map " << far_w_sr << " W/sr, peak " << peak;
    }
  }
  EXPECT_GT(lit, 20) << "too few lit directions to test";
  std::printf("[ far field ] %s: far radius %.4g m, worst |E r² - I| / peak %.3g (allowed %g)\n",
              p.name.c_str(), f.spec().far_radius_m, worst, f.spec().tolerance);
}

INSTANTIATE_TEST_SUITE_P(
    Targets, NearAndFar,
    testing::Values(
        NearFarCase{"Sphere", "2.0", 0.05,
                    R"({"shape": "sphere", "center": [0, 0, 0], "radius": 1.0, "material": "m"})"},
        NearFarCase{"CylinderLitOffCentre", "0.3", 0.05,
                    R"({"shape": "cylinder", "center": [0, 0, -0.6], "axis": [0, 0.2, 1],
                        "radius": 0.5, "length": 2.0, "material": "m"})"}),
    [](const testing::TestParamInfo<NearFarCase>& i) { return i.param.name; });

// The far radius grows as 1/σ and 1/tolerance (first order, farRadius()).
TEST(FarField, FarRadiusGrowsAsTheLobeNarrowsAndTheToleranceTightens) {
  EXPECT_DOUBLE_EQ(farRadius(1.0, 0.01, 0.01), 1.0 + 103.0 / 0.01);
  EXPECT_DOUBLE_EQ(farRadius(2.0, 0.01, 0.01), 2.0 * farRadius(1.0, 0.01, 0.01));
  EXPECT_GT(farRadius(1.0, 0.001, 0.01), 9.0 * farRadius(1.0, 0.01, 0.01));
  EXPECT_DOUBLE_EQ(farRadius(1.0, std::numeric_limits<double>::infinity(), 0.1), 31.0)
      << "diffuse only: 3 per radian";
  EXPECT_DOUBLE_EQ(farRadius(1.0, 0.01, 0.01, kPi / 2), farRadius(1.0, 0.01, 0.01))
      << "beyond 51° of the beam's direction the half vector turns no faster than allowed for";
  EXPECT_NEAR(farRadius(1.0, 0.01, 0.01, 0.1), 1.0 + (3.0 + 0.43 / std::sin(0.05) / 0.01) / 0.01,
              1e-6)
      << "into the forward cone it grows as 1/sin(ψ/2)";
}

}  // namespace
}  // namespace glint
