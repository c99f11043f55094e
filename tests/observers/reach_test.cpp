// The hazard reach without a box: the radial lattices and the far field beyond, against direct
// integration along rays.
#include "observers/reach.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <string>

#include "observers/far_field.h"
#include "pipeline/input/scene.h"
#include "pipeline/setup/target_builder.h"

namespace glint {
namespace {

// A scene without observers: laser from −x at 1064 nm for 10 s (MPE 50 W/m²).
std::string sceneWithout(double power_w, const std::string& beam, double sigma,
                         const std::string& object, const std::string& extra = "") {
  return R"({"laser": {"position": [-100, 0, 0], "direction": [1, 0, 0], "power_w": )" +
         std::to_string(power_w) + R"(, "wavelength_nm": 1064, "exposure_s": 10, "beam": )" + beam +
         R"(}, "materials": {"m": {"specular_reflectance": 0.9, "sigma": )" +
         std::to_string(sigma) + R"(}}, "objects": [)" + object + "]" + extra + "}";
}

// The reach of a scene as glint run computes it: the checked far field, then the lattices.
struct Reach {
  Scene scene;
  SceneTarget target;
  FarField far;
  NearReach near;
  ReachSummary summary;
};
Reach reachOf(const std::string& json) {
  Scene scene = parseScene(json, "test.json");
  SceneTarget target = sceneTarget(scene, reachAccuracy(scene));
  FarField far = computeFarField(target.integrator, checkedFarFieldSpec(scene, target.integrator));
  const ReachSpec spec = reachSpec(scene, far);
  const FieldProblem problem = fieldProblem(target, scene, reachFaceSpec(0, spec));
  NearReach near = computeNearReach(problem.integrator, spec, problem.excluded);
  const ReachSummary summary =
      summarizeReach(near, far, 0, farReach(far, spec.thresholds_w_m2.at(0)), 0.0);
  return {std::move(scene), std::move(target), std::move(far), std::move(near), summary};
}

// Where E along the ray from @p from toward @p d falls below @p threshold for good, between
// @p lo (above it) and @p hi (below), bisected with the integrator at 1e-5.
double crossing(const FacetIntegrator& integrator, const Vec3& from, const Vec3& d, double lo,
                double hi, double threshold) {
  const FacetIntegrator direct = integrator.withAccuracy(1e-5, 1e-9 * threshold);
  IntegratorWorkspace ws;
  for (int it = 0; it < 60; ++it) {
    const double m = 0.5 * (lo + hi);
    (direct.adaptive(from + m * d, ws).irradiance_w_m2 >= threshold ? lo : hi) = m;
  }
  return lo;
}

// A mirror ball's glint straight back to the laser: along that ray the lattice's reach is at
// or beyond where direct integration crosses the MPE, and within one layer of it.
TEST(Reach, AMirrorBallsReachIsAtTheCrossingAlongTheRayBackWithinOneLayer) {
  Scene scene = parseScene(
      sceneWithout(1000.0, R"({"profile": "flat_top", "radius_m": 1.0})", 0.01,
                   R"({"shape": "sphere", "center": [0, 0, 0], "radius": 0.5, "material": "m"})"),
      "test.json");
  const SceneTarget target = sceneTarget(scene, reachAccuracy(scene));
  const LitBall ball = litBall(target.integrator);
  ReachSpec spec;
  spec.centre_m = ball.centre_m;
  spec.near_m = ball.radius_m;
  spec.far_m = 60.0;
  spec.face_cells = 32;
  spec.block_voxels = 8;
  spec.thresholds_w_m2 = {0.05};
  spec.floor_w_m2 = 1e-3 * 0.05;
  const FieldProblem problem = fieldProblem(target, scene, reachFaceSpec(0, spec));
  const NearReach near = computeNearReach(problem.integrator, spec, problem.excluded);
  const Vec3 back(-1.0, 0.0, 0.0);  // face 1's centre ray
  const int n = spec.face_cells + 1, mid = spec.face_cells / 2;
  const double reach_m = near.faces[1].reach_m[0][static_cast<std::size_t>(mid * n + mid)];
  const double cross = crossing(target.integrator, ball.centre_m, back, spec.near_m, spec.far_m,
                                spec.thresholds_w_m2[0]);
  EXPECT_GE(reach_m, cross) << "the reach may not fall short of the crossing";
  EXPECT_LE(reach_m, cross * spec.ratio * (1.0 + spec.tolerance)) << "within a layer of it";
  EXPECT_GE(near.toward(back, 0), reach_m) << "between rays, the largest of those around";
  std::printf("[ reach ] mirror ball: back ray %.4g m, crossing %.4g m; volume %.4g m³\n", reach_m,
              cross, near.volume_m3[0]);
}

// A small tilted mirror (10 cm across, σ = 0.005) lit whole by a 100 kW beam sends a thin pencil
// up and across, hazardous hundreds of metres out, where no box one would guess around it
// reaches. The
// reach finds it without one: closed, toward the mirror direction, at or beyond where direct
// integration along it crosses the MPE and within the far field's tolerance of it; and no
// direction about the pencil is hazardous beyond the reach reported for it.
TEST(Reach, AThinObliquePencilIsFollowedToItsEndAndNothingLiesBeyondTheReach) {
  // Normal (−1, 0.6, 0.4): the beam along +x reflects toward d − 2 (d · n) n.
  const Reach r = reachOf(sceneWithout(
      1e5, R"({"profile": "flat_top", "radius_m": 0.2})", 0.005,
      R"({"shape": "disk", "center": [0, 0, 0], "normal": [-1, 0.6, 0.4], "radius": 0.05,
          "material": "m", "segments": 8})",
      R"(, "far_field": {"face_pixels": 512})"));
  const Vec3 n = glm::normalize(Vec3(-1.0, 0.6, 0.4));
  const Vec3 mirror = Vec3(1.0, 0.0, 0.0) - 2.0 * n.x * n;
  const ReachSummary& s = r.summary;
  const double mpe = r.scene.hazard.mpe_w_m2;
  ASSERT_TRUE(s.closed) << "the far radius is verified: " << r.far.spec().far_radius_m << " m";
  EXPECT_TRUE(s.from_far_field);
  EXPECT_LT(std::acos(std::min(1.0, glm::dot(s.direction, mirror))), 3.0 * 0.005)
      << "toward the mirror direction, within the lobe";
  const Vec3 c = r.near.spec.centre_m;
  const double cross =
      crossing(r.target.integrator, c, s.direction, r.far.spec().far_radius_m, 1e4, mpe);
  EXPECT_GT(cross, 300.0) << "the premise: a pencil far beyond any box about the mirror";
  EXPECT_GE(s.distance_m, cross * (1.0 - 1e-4)) << "never short of the crossing";
  // √(I (1 + tolerance)/MPE): the map's intensity is within its tolerance.
  EXPECT_LE(s.distance_m, cross * std::sqrt(1.0 + r.far.spec().tolerance) * 1.001)
      << "and within the far field's tolerance of it";
  // Directions about the pencil, out to four lobe widths: beyond each one's reach, direct
  // integration finds nothing hazardous (within the integrator's tolerance of the MPE).
  const FacetIntegrator direct = r.target.integrator.withAccuracy(1e-4, 1e-9 * mpe);
  IntegratorWorkspace ws;
  std::mt19937 rng(7);
  std::normal_distribution<double> gauss(0.0, 1.0);
  const Vec3 a = glm::normalize(glm::cross(s.direction, Vec3(0.0, 0.0, 1.0)));
  const Vec3 b = glm::cross(s.direction, a);
  int hazardous_beyond = 0, checked = 0;
  double worst_ratio = 0.0;
  for (int k = 0; k < 200; ++k) {
    const Vec3 d = glm::normalize(s.direction + 0.01 * (gauss(rng) * a + gauss(rng) * b));
    const double reach_m = reachToward(r.near, r.far, 0, d, 0.0);
    for (const double beyond : {1.0001, 1.05, 1.5}) {
      const double e = direct.adaptive(c + std::max(reach_m, r.near.spec.near_m) * beyond * d, ws)
                           .irradiance_w_m2;
      worst_ratio = std::max(worst_ratio, e / mpe);
      hazardous_beyond += e > mpe * (1.0 + 1e-3) ? 1 : 0;
      ++checked;
    }
  }
  EXPECT_EQ(hazardous_beyond, 0) << "of " << checked << " points beyond the reach; worst E/MPE "
                                 << worst_ratio;
  std::printf(
      "[ reach ] pencil: %.5g m (crossing %.5g m), far radius %.4g m; beyond the reach the "
      "worst E/MPE %.4f of %d points; lattice %lld points\n",
      s.distance_m, cross, r.far.spec().far_radius_m, worst_ratio, checked,
      static_cast<long long>(r.near.evaluatedPoints()));
}

}  // namespace
}  // namespace glint
