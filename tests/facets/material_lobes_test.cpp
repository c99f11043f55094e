// Materials of several specular lobes (Material::more_lobes): each lobe normalised, the
// integrator's sum of terms equal to separate runs, the bounds holding every lobe.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "facets/integrator.h"
#include "facets/material.h"
#include "facets/patch.h"
#include "facets/reflection.h"
#include "facets/tessellate.h"
#include "support/brdf_quadrature.h"
#include "support/quadrature.h"
#include "support/scenes.h"

namespace glint {
namespace {

using test::accuracy;
using test::flatTop;

// A painted finish: a narrow specular lobe, a wide haze lobe and a Lambertian floor.
Material paint() {
  Material m{0.5, 0.1, Beckmann{0.02}};
  m.more_lobes = {{0.3, Beckmann{0.08}}};
  return m;
}

// The lobes here lie more than 5 of their widths (2σ after reflection) above the horizon,
// so the brute-force integrand is smooth wherever it is not negligible.
double hemisphericalReflectance(const Material& m, const Vec3& wi) {
  return test::hemisphericalReflectance(m, wi, 6000);
}

// The same for one lobe of reflectance 1 in slope space, where the Beckmann lobe is the
// density of a 2-D Gaussian of the microfacet slopes p (Ξ cos θN dω = g(p) d²p): with the
// reflection's Jacobian, ∫ g(p) (1 − ωi,t · p / cos θi) over the slopes whose mirror direction
// lies above the horizon. An independent path: no BRDF, no outgoing directions.
double slopeSpaceReflectance(double sigma, const Vec3& wi) {
  const auto nodes = test::gaussLegendre(64);
  const double cos_i = wi.z;
  double sum = 0.0;
  const double r_max = 8.0 * sigma;  // beyond it the Gaussian's mass is e^-32
  for (const auto& [xr, wr] : nodes) {
    const double rad = 0.5 * r_max * (xr + 1.0);
    for (int k = 0; k < 256; ++k) {
      const double phi = 2.0 * kPi * (k + 0.5) / 256.0;
      const Vec3 p(rad * std::cos(phi), rad * std::sin(phi), 0.0);
      const Vec3 h = glm::normalize(Vec3(-p.x, -p.y, 1.0));
      const Vec3 wo = 2.0 * glm::dot(wi, h) * h - wi;
      if (!(glm::dot(wi, h) > 0.0) || !(wo.z > 0.0)) continue;
      const double g = std::exp(-rad * rad / (2.0 * sigma * sigma)) / (2.0 * kPi * sigma * sigma);
      sum += 0.5 * r_max * wr * (2.0 * kPi / 256.0) * rad * g *
             (1.0 - (wi.x * p.x + wi.y * p.y) / cos_i);
    }
  }
  return sum;
}

TEST(MaterialLobes, HemisphericalReflectanceIsEachLobesOwnPlusTheFloor) {
  const Material m = paint();
  for (double deg : {0.0, 20.0, 40.0}) {
    const double t = deg * kPi / 180.0;
    const Vec3 wi(std::sin(t), 0.0, std::cos(t));
    const double brute = hemisphericalReflectance(m, wi);
    const double reference =
        0.5 * slopeSpaceReflectance(0.02, wi) + 0.3 * slopeSpaceReflectance(0.08, wi) + 0.1;
    // Both quadratures are far finer than the lobes (Simpson's error ~ (h / 2σ)⁴, Gauss's
    // converged): agreement to 1e-6 of the albedo.
    EXPECT_NEAR(brute, reference, 1e-6) << deg << " deg";
    // The lobes lie well above the horizon: each reflects its ρ whole (to e^-12).
    EXPECT_NEAR(reference, 0.9, 1e-5) << deg << " deg";
    std::printf("[ lobes ] albedo at %g deg: brute force %.9f, slope space %.9f\n", deg, brute,
                reference);
  }
}

TEST(MaterialLobes, TheNarrowestLobeIsFoundWhereverItIsListed) {
  Material m{0.2, 0.0, Beckmann{0.1}};
  m.more_lobes = {{0.3, Beckmann{0.004}}, {0.1, Beckmann{0.5}}};
  const std::optional<double> narrowest = narrowestWidthRad({&m, 1});
  ASSERT_TRUE(narrowest.has_value());
  EXPECT_EQ(*narrowest, 0.004) << "the second lobe is the narrowest";
  m.more_lobes[0].reflectance = 0.0;
  EXPECT_EQ(*narrowestWidthRad({&m, 1}), 0.1) << "a lobe that reflects nothing does not count";
  const std::vector<Material> terms = m.terms();
  ASSERT_EQ(terms.size(), 3u);
  EXPECT_EQ(terms[0].diffuse_reflectance, 0.0);
  EXPECT_EQ(terms[2].lobe.sigma, 0.5);
  EXPECT_TRUE(terms[1].more_lobes.empty()) << "each term is one lobe";
}

// A cylinder of the painted finish under a flat-top beam.
FacetIntegrator paintedCylinder(const Material& m, const IntegratorOptions& o) {
  const Beam beam = flatTop(Vec3(0), Vec3(1, 0, 0), 100.0, 2.0);
  return test::singleObject(
      m, beam,
      [](Target& t, std::uint32_t mi, Vec3 toward_laser) {
        addCylinder(t, {Vec3(0), Vec3(0, 0, 1), 0.5, 2.0}, mi, 16, toward_laser);
      },
      o);
}

// Observers near and far, in the narrow lobe's stripe, in the haze beside it and off both.
std::vector<Vec3> observersAround() {
  std::vector<Vec3> out;
  for (double dist : {1.5, 6.0, 40.0}) {
    for (double deg : {0.0, 4.0, 25.0, 70.0, 140.0}) {
      const double a = deg * kPi / 180.0;
      out.emplace_back(-dist * std::cos(a), dist * std::sin(a), 0.3);
    }
    out.emplace_back(-dist, 0.0, 0.3 + 0.15 * dist);  // above the stripe: the haze only
  }
  return out;
}

// The light is linear in the BRDF: the two-lobe finish gives, at every observer, the sum of a
// run of its first lobe (with the floor) and a run of its second, each to the tolerance; and it
// costs no more than the two runs.
TEST(MaterialLobes, ATwoLobeFinishIsTheSumOfItsLobesRunAlone) {
  const double tolerance = 1e-4;
  const Material m = paint();
  const std::vector<Material> terms = m.terms();
  const FacetIntegrator both = paintedCylinder(m, accuracy(tolerance));
  const FacetIntegrator first = paintedCylinder(terms[0], accuracy(tolerance));
  const FacetIntegrator second = paintedCylinder(terms[1], accuracy(tolerance));
  IntegratorWorkspace ws;
  std::int64_t both_evaluations = 0, alone_evaluations = 0;
  double worst = 0.0, worst_uniform = 0.0;
  for (const Vec3& obs : observersAround()) {
    const ObserverResult r = both.adaptive(obs, ws);
    const ObserverResult a = first.adaptive(obs, ws);
    const ObserverResult b = second.adaptive(obs, ws);
    ASSERT_TRUE(r.converged && a.converged && b.converged) << obs.x << "," << obs.y << "," << obs.z;
    const double sum = a.irradiance_w_m2 + b.irradiance_w_m2;
    ASSERT_GT(sum, 0.0);
    // Each of the three within tolerance × its own value (+ the floor) of the truth.
    const double allowed = 2.0 * tolerance * sum + 3e-12;
    EXPECT_NEAR(r.irradiance_w_m2, sum, allowed) << obs.x << "," << obs.y << "," << obs.z;
    worst = std::max(worst, std::abs(r.irradiance_w_m2 - sum) / sum);
    both_evaluations += r.evaluations;
    alone_evaluations += a.evaluations + b.evaluations;
    // An independent path: the uniform twin samples the whole BRDF, both lobes in one kernel,
    // at every piece's centre; at level 6 its pieces (3 mm, 0.003 rad of normals) resolve the
    // narrow lobe (σ = 0.02) to a sixth of its width: the midpoint rule's error there is about
    // (1/6)² / 24 ≈ 1e-3, the terminator's clipped pieces a little more.
    if (glm::length(obs) > 5.0) {
      const double uniform = both.uniform(obs, 6, ws).irradiance_w_m2;
      EXPECT_NEAR(uniform / r.irradiance_w_m2, 1.0, 5e-3) << obs.x << "," << obs.y << "," << obs.z;
      worst_uniform = std::max(worst_uniform, std::abs(uniform / r.irradiance_w_m2 - 1.0));
    }
  }
  // The terms are the separate runs, but for the floor each gets half of.
  EXPECT_LE(both_evaluations, alone_evaluations * 11 / 10)
      << "two lobes cost about what the two runs do";
  std::printf(
      "[ lobes ] two lobes vs the sum of their runs: worst %.2e relative; %lld against "
      "%lld evaluations; against the uniform twin at level 6: worst %.2e\n",
      worst, static_cast<long long>(both_evaluations), static_cast<long long>(alone_evaluations),
      worst_uniform);
}

// What the bounds promise holds for every lobe: a piece's bound is never below its own sample,
// in the haze lobe's light above the narrow lobe's stripe as in the stripe. (A bound of the
// first lobe alone falls below the haze wherever the haze is brighter than the narrow lobe's
// tail.)
TEST(MaterialLobes, EachPiecesBoundHoldsTheHazeLobesLightToo) {
  const FacetIntegrator fi = paintedCylinder(paint(), accuracy(1e-4));
  const Target& t = fi.target();
  const Material& m = t.materials.at(0);
  std::vector<SubFacet> pieces;
  for (std::uint32_t f = 0; f < t.facetCount(); ++f) subFacetsAtDepth(t, f, 3, pieces);
  int lit = 0;
  for (const Vec3& obs : observersAround()) {
    for (const SubFacet& piece : pieces) {
      const PatchGeometry g = patchGeometry(t, piece, NormalModel::Surface);
      const double sample = facetIrradiance(g, obs, fi.beam(), m);
      if (sample == 0.0) continue;
      ++lit;
      const ContributionBound b = contributionBound(g, obs, fi.beam(), m, ResolutionLimits{});
      ASSERT_GE(b.upper_w_m2, sample) << obs.x << "," << obs.y << "," << obs.z;
    }
  }
  EXPECT_GT(lit, 500) << "the pieces must be lit and seen";
}

}  // namespace
}  // namespace glint
