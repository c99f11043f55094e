// Where the far field actually begins: along directions of the glint fan, the distance beyond
// which E(c + r ω) r² stays within the far field's tolerance of I(ω) (relative to the peak), by
// direct integration, against the far radius the first-order rule gives and the one the far
// field's own check settles on (verifyFarRadius(), as glint run computes it). A second column
// of settled distances allows what the check allows beside the tolerance: the tolerance × the
// lowest hazardous irradiance × r², an error no verdict at r can turn on.
//
//   glint_settle_bench SCENE... [--directions N] [--csv FILE]
//
// The far field is computed with its floor at 1e-3 × MPE × (16 lit radii)², which lets the
// check come in that far (far_field.floor_w_sr).
//
// Directions: the beam reflected off the lit facets' normals (the specular fan), each spread by
// the lobe's width; I(ω) is E r² at a hundred far radii. Distances: 16 per decade from twice the
// lit radius out.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "observers/far_field.h"
#include "pipeline/input/scene.h"
#include "pipeline/setup/target_builder.h"

using namespace glint;

namespace {

struct Direction {
  Vec3 omega;
  double intensity_w_sr = 0.0;
  double settled_m = 0.0;  // beyond this, |E r² − I| ≤ tolerance × peak at every sampled r
  double settled_hazard_m = 0.0;  // the same, ≤ tolerance × max(peak, lowest hazardous × r²)
  double far_radius_m = 0.0;
};

// The beam reflected specularly off each of up to @p count lit facets, spread by the lobe.
std::vector<Vec3> fanDirections(const FacetIntegrator& integrator, int count, double spread_rad) {
  const auto lit = integrator.candidates();
  std::vector<Vec3> out;
  if (lit.empty()) return out;
  std::mt19937_64 rng(7);
  std::normal_distribution<double> gauss(0.0, spread_rad);
  const Vec3 d = integrator.beam().direction;
  for (int k = 0; k < count; ++k) {
    const Candidate& c = lit[static_cast<std::size_t>(k) * lit.size() / count];
    const Vec3 n = c.geometry.normal;
    const Vec3 r = d - 2.0 * glm::dot(d, n) * n;
    const Vec3 u = anyPerpendicular(r);
    const Vec3 v = glm::cross(r, u);
    if (auto w = tryNormalize(r + gauss(rng) * u + gauss(rng) * v)) out.push_back(*w);
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Where E r² settles to I(ω), against the far radius"};
  std::vector<std::string> scenes;
  int count = 400;
  std::string csv_path;
  app.add_option("scenes", scenes, "scene files")->required();
  app.add_option("--directions", count, "directions per scene");
  app.add_option("--csv", csv_path, "every direction's figures");
  CLI11_PARSE(app, argc, argv);
  std::ofstream csv;
  if (!csv_path.empty()) {
    csv.open(csv_path);
    csv << "scene,omega_x,omega_y,omega_z,intensity_w_sr,settled_m,far_radius_m\n";
  }
  std::printf("%-24s %9s %11s %11s %11s %10s %11s %9s %9s\n", "scene", "lit r (m)", "1st order",
              "checked", "settled", "median", "for hazard", "chk/set", "chk/haz");
  for (const std::string& path : scenes) {
    const Scene scene = loadScene(path);
    const SceneTarget target = sceneTarget(scene, FieldSpec{});
    // Intensity, as the far field reads it: no attenuation on the way out.
    const FacetIntegrator direct =
        target.integrator.withAccuracy(1e-5, 1e-30).withReturnExtinction(0.0);
    const FarFieldSpec spec = checkedFarFieldSpec(scene, target.integrator);
    const LitBall ball = litBall(direct);
    IntegratorWorkspace ws;
    const double width = std::isfinite(spec.narrowest_sigma) ? spec.narrowest_sigma : 0.1;
    std::vector<Direction> dirs;
    double peak = 0.0;
    for (const Vec3& w : fanDirections(direct, count, 2.0 * width)) {
      Direction d{w, 0.0, 0.0, 0.0, farRadiusToward(spec, w)};
      if (!std::isfinite(d.far_radius_m)) continue;
      const double r_inf = 100.0 * d.far_radius_m;
      d.intensity_w_sr =
          direct.adaptive(ball.centre_m + r_inf * w, ws).irradiance_w_m2 * r_inf * r_inf;
      peak = std::max(peak, d.intensity_w_sr);
      dirs.push_back(d);
    }
    std::vector<double> settled;
    double worst = 0.0, worst_hazard = 0.0, far_at_worst = spec.far_radius_m;
    const double hazard_w_m2 = scene.hazard.lowestHazardousW_m2();
    for (Direction& d : dirs) {
      if (!(d.intensity_w_sr >= 1e-2 * peak)) continue;
      // From the far radius inward: the last r at which the promise still held all the way out.
      const double r_min = 2.0 * ball.radius_m;
      const int steps = static_cast<int>(std::ceil(16.0 * std::log10(d.far_radius_m / r_min)));
      d.settled_m = d.settled_hazard_m = d.far_radius_m;
      bool held = true;
      for (int s = 0; s <= steps; ++s) {
        const double r = d.far_radius_m * std::pow(10.0, -s / 16.0);
        const double e = direct.adaptive(ball.centre_m + r * d.omega, ws).irradiance_w_m2;
        const double departure = std::abs(e * r * r - d.intensity_w_sr);
        held = held && departure <= spec.tolerance * peak;
        if (held) d.settled_m = r;
        if (!(departure <= spec.tolerance * std::max(peak, hazard_w_m2 * r * r))) break;
        d.settled_hazard_m = r;
      }
      settled.push_back(d.settled_m);
      if (d.settled_m > worst) worst = d.settled_m, far_at_worst = d.far_radius_m;
      worst_hazard = std::max(worst_hazard, d.settled_hazard_m);
      if (csv.is_open()) {
        csv << path << ',' << d.omega.x << ',' << d.omega.y << ',' << d.omega.z << ','
            << d.intensity_w_sr << ',' << d.settled_m << ',' << d.far_radius_m << '\n';
      }
    }
    std::sort(settled.begin(), settled.end());
    const double median = settled.empty() ? 0.0 : settled[settled.size() / 2];
    // The far field as glint run computes it, for the radius its check settles on.
    const FarField far = computeFarField(target.integrator, spec);
    const double checked_m = far.spec().far_radius_m;
    std::printf(
        "%-24s %9.4g %11.4g %11.4g %11.4g %10.4g %11.4g %9.3g %9.3g   (%zu directions within "
        "1e-2 of the peak; check %.1f s on %zu spheres)\n",
        std::filesystem::path(path).filename().c_str(), ball.radius_m, far_at_worst, checked_m,
        worst, median, worst_hazard, worst > 0.0 ? checked_m / worst : 0.0,
        worst_hazard > 0.0 ? checked_m / worst_hazard : 0.0, settled.size(),
        far.farRadiusCheck().seconds, far.farRadiusCheck().spheres.size());
  }
  return 0;
}
