// Every bound, sum and decision that meets a NaN or an infinity must choose "refine", never
// "skip" or "accept": a hazard tool fails safe. These are the pieces the observer field's
// decisions rest on; tests/observers/field_test.cpp has the scene where the failure showed.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "facets/integrator.h"
#include "facets/reflection.h"
#include "facets/sum.h"
#include "facets/tessellate.h"
#include "support/scenes.h"

namespace glint {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
const double kNaN = std::nan("");

TEST(CompensatedSumFailSafe, AnInfiniteTermMakesAnInfiniteTotalNotNaN) {
  // Neumaier's compensation subtracts the new total from the terms: with ∞ that is ∞ − ∞.
  CompensatedSum sum;
  sum.add(1.0);
  sum.add(kInf);
  sum.add(2.0);
  EXPECT_EQ(sum.value(), kInf) << "a bound of +∞ (an observer on the target) stays +∞";
  CompensatedSum first;
  first.add(kInf);
  first.add(1e300);
  EXPECT_EQ(first.value(), kInf) << "+∞ first, then finite terms";
}

TEST(CompensatedSumFailSafe, OverflowIsInfiniteAndNaNStaysNaN) {
  CompensatedSum big;
  big.add(1.7e308);
  big.add(1.7e308);
  EXPECT_EQ(big.value(), kInf) << "finite terms whose sum overflows";
  CompensatedSum nan;
  nan.add(1.0);
  nan.add(kNaN);
  nan.add(1.0);
  EXPECT_TRUE(std::isnan(nan.value())) << "a NaN is never laundered into a number";
}

TEST(CompensatedSumFailSafe, FiniteSumsKeepTheirCompensation) {
  CompensatedSum sum;
  sum.add(1.0);
  for (int i = 0; i < 1000; ++i) sum.add(1e-17);
  EXPECT_NEAR(sum.value(), 1.0 + 1e-14, 2e-16) << "the rounding errors are still carried";
}

TEST(BeckmannFailSafe, MaxBeyondANaNAngleIsTheLobePeak) {
  for (double sigma : {0.001, 0.1, 0.9}) {
    const Beckmann lobe{sigma};
    EXPECT_EQ(lobe.maxXiBeyond(kNaN), lobe.maxXiBeyond(0.0))
        << "σ " << sigma << ": an angle that could not be computed bounds nothing away";
    EXPECT_GT(lobe.maxXiBeyond(kNaN), 0.0) << "σ " << sigma;
  }
}

// A 1 m flat-top beam along +x onto a 0.5 m mirror sphere at the origin (12 segments).
Target sphereTarget(const Beam& beam) {
  Target t;
  t.addMaterial(test::mirror(0.9, 0.01, 0.0));
  addSphere(t, {Vec3(0), 0.5}, 0, 12, -beam.direction);
  return t;
}

TEST(ContributionBoundFailSafe, ANaNNormalBoundsAsTheLobePeakNeverZero) {
  const Beam beam = test::flatTop(Vec3(0), Vec3(1, 0, 0), 1000.0, 1.0);
  const Target t = sphereTarget(beam);
  const Material& m = t.materials[0];
  const Vec3 observer(-5, 0, 0);
  PatchGeometry g = patchGeometry(t, coarseSubFacet(t, 0), NormalModel::Surface);
  // The largest bound any normal can give: the normal along the half vector.
  PatchGeometry aligned = g;
  aligned.normal = glm::normalize(-beam.direction + glm::normalize(observer - g.centre_m));
  const double peak = contributionBound(aligned, observer, beam, m, {}).upper_w_m2;
  ASSERT_GT(peak, 0.0);
  g.normal = Vec3(kNaN, 0.0, 0.0);
  const ContributionBound b = contributionBound(g, observer, beam, m, {});
  EXPECT_GE(b.upper_w_m2, peak) << "an angle that cannot be computed bounds like the peak";
  EXPECT_FALSE(b.resolved()) << "and is never trusted to a sample";
  EXPECT_TRUE(mayFaceObserver(g, observer)) << "culling must be proven";
  EXPECT_EQ(lightVerdict(g, beam), LightVerdict::MayBeLit) << "so must 'faces away'";
}

TEST(ContributionBoundFailSafe, OverflowingBeamPowerGivesAnInfiniteBoundNeverNaN) {
  // 1.7e308 W over a beam of 1 m: the irradiance is finite, but times the lobe's peak and an
  // area it overflows, and ∞ · 0 (no diffuse reflectance) would be NaN. The bound is linear in
  // the power, so the same facet under 1 W says what it must be: 1.7e308 times that, +∞ where
  // that product passes the largest double. A factor 2 either side of it is left out, where
  // the bound's own order of products may round to the other side.
  constexpr double kPower = 1.7e308, kMax = std::numeric_limits<double>::max();
  Beam beam = test::flatTop(Vec3(0), Vec3(1, 0, 0), 1.0, 1.0);
  Beam one_watt = beam;
  one_watt.power_w = 1.0;
  beam.power_w = kPower;
  const Target t = sphereTarget(beam);
  const Material& m = t.materials[0];
  const Vec3 observer(-5, 0.3, 0.1);
  constexpr double kObserverRadius = 0.2;
  int infinite = 0, finite = 0;
  for (std::uint32_t i = 0; i < t.facetCount(); ++i) {
    const PatchGeometry g = patchGeometry(t, coarseSubFacet(t, i), NormalModel::Surface);
    const ContributionBound b = contributionBound(g, observer, beam, m, {}, kObserverRadius);
    const double per_watt =
        contributionBound(g, observer, one_watt, m, {}, kObserverRadius).upper_w_m2;
    ASSERT_TRUE(std::isfinite(per_watt)) << "facet " << i << ": premise, 1 W overflows nothing";
    EXPECT_FALSE(std::isnan(b.upper_w_m2)) << "facet " << i;
    EXPECT_FALSE(std::isnan(b.unresolved_w_m2)) << "facet " << i;
    if (per_watt > 2.0 * (kMax / kPower)) {
      EXPECT_EQ(b.upper_w_m2, kInf) << "facet " << i << ": " << per_watt << " W/m² a watt";
      EXPECT_EQ(b.unresolved_w_m2, kInf) << "facet " << i << ": an overflow is never resolved";
      ++infinite;
    } else if (per_watt < 0.5 * (kMax / kPower)) {
      ASSERT_TRUE(std::isfinite(b.upper_w_m2)) << "facet " << i << ": no overflow, no +∞";
      // The same dozen products and quotients at another scale: a few roundings of 1.1e-16
      // each apart, well inside 1e-12.
      EXPECT_NEAR(b.upper_w_m2, per_watt * kPower, 1e-12 * per_watt * kPower) << "facet " << i;
      if (per_watt > 0.0) ++finite;
    }
    if (!std::isfinite(b.upper_w_m2)) continue;
    // A finite bound holds for every observer of its ball: the facet's sample at its centre
    // and at the ends of its three axes stays below it.
    for (const Vec3& at :
         {observer, observer + Vec3(kObserverRadius, 0, 0), observer - Vec3(kObserverRadius, 0, 0),
          observer + Vec3(0, kObserverRadius, 0), observer - Vec3(0, kObserverRadius, 0),
          observer + Vec3(0, 0, kObserverRadius), observer - Vec3(0, 0, kObserverRadius)}) {
      const double sample = facetIrradiance(g, at, beam, m);
      ASSERT_TRUE(std::isfinite(sample)) << "facet " << i;
      EXPECT_GE(b.upper_w_m2, sample)
          << "facet " << i << " at " << at.x << "," << at.y << "," << at.z;
    }
  }
  // The premise that makes the test one of overflow: the power overflows some bounds, not all
  // (measured: 24 of the 120 facets +∞, 36 finite and positive, 60 zero).
  EXPECT_GT(infinite, 0) << "no bound overflowed at " << kPower << " W";
  EXPECT_GT(finite, 0) << "every bound overflowed at " << kPower << " W";
}

TEST(RegionBoundFailSafe, ABallReachingTheTargetIsUnboundedNotNaN) {
  // A ball of observers around the sphere's lit side reaches its facets: their bounds are +∞.
  // Summed with compensation they once gave NaN, which no decision could see.
  const Beam beam = test::flatTop(Vec3(0), Vec3(1, 0, 0), 1000.0, 1.0);
  const FacetIntegrator fi(sphereTarget(beam), beam, test::accuracy(1e-3));
  BallBoundOptions options;
  options.drop_allowance_w_m2 = 1e-3;
  options.sample_spacing_m = 0.4;
  std::vector<Candidate> kept;
  const BallBound touching =
      fi.boundBall(Vec3(-0.6, 0, 0), 0.3, fi.candidates(), 0.0, options, kept);
  EXPECT_EQ(touching.upper_w_m2, kInf);
  EXPECT_FALSE(touching.bounded()) << "the field refines such a block";
  EXPECT_FALSE(std::isnan(touching.narrow_w_m2));
  EXPECT_FALSE(kept.empty()) << "no facet the ball touches may be dropped";

  const BallBound away = fi.boundBall(Vec3(-5, 0, 0), 0.3, fi.candidates(), 0.0, options, kept);
  EXPECT_TRUE(away.bounded()) << "a ball clear of the target has a finite bound";
  EXPECT_GT(away.upper_w_m2, 0.0) << "in front of a lit mirror ball";
}

TEST(RegionBoundFailSafe, AnInfiniteDropAllowanceStillKeepsUnboundedCandidates) {
  // An allowance of +∞ must not let unbounded candidates go: the region's points would then
  // integrate over a list without the facets they touch. Only finite bounds are dropped.
  const Beam beam = test::flatTop(Vec3(0), Vec3(1, 0, 0), 1000.0, 1.0);
  const FacetIntegrator fi(sphereTarget(beam), beam, test::accuracy(1e-3));
  BallBoundOptions options;
  options.drop_allowance_w_m2 = kInf;
  std::vector<Candidate> kept;
  const BallBound b = fi.boundBall(Vec3(-0.6, 0, 0), 0.3, fi.candidates(), 0.0, options, kept);
  EXPECT_FALSE(std::isnan(b.upper_w_m2));
  EXPECT_EQ(b.upper_w_m2, kInf);
  EXPECT_FALSE(kept.empty()) << "the facets the ball reaches are kept for its points";
}

}  // namespace
}  // namespace glint
