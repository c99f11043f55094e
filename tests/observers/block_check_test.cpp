// The field's block check alone: which blocks it skips, fills by interpolation or refines,
// on fields written out at the block's samples.
#include "observers/block_check.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>

namespace glint::field {
namespace {

constexpr BlockSize kSize{8, 8, 8};  // voxels per block edge: 35 samples

// A bounded, wide-light bound (nothing narrower than the samples).
BallBound boundOf(double upper_w_m2, double narrow_w_m2 = 0.0) {
  BallBound b;
  b.upper_w_m2 = upper_w_m2;
  b.narrow_w_m2 = narrow_w_m2;
  return b;
}

// The samples of a block of @p size of E(x) with x ∈ [0, 1]³ across the block, and their
// distances from a centre at @p centre (in block units).
BlockSamples sampleBlock(const BlockSize& size,
                         const std::function<double(double, double, double)>& e, bool far = false,
                         const std::array<double, 3>& centre = {0.0, 0.0, 0.0}) {
  BlockSamples s;
  s.far_from_target = far;
  forEachSample(size, [&](int i, int j, int k) {
    const double x = double(i) / size[0], y = double(j) / size[1], z = double(k) / size[2];
    s.irradiance_w_m2[s.count] = e(x, y, z);
    s.distance_m[s.count] = std::hypot(x - centre[0], y - centre[1], z - centre[2]);
    ++s.count;
  });
  return s;
}

BlockSamples sample(const std::function<double(double, double, double)>& e, bool far = false,
                    const std::array<double, 3>& centre = {0.0, 0.0, 0.0}) {
  return sampleBlock(kSize, e, far, centre);
}

Decision decide(const BlockSamples& samples, const BallBound& bound, double tolerance,
                double floor_w_m2) {
  return decideBySamples(samples, kSize, bound, tolerance, floor_w_m2);
}

TEST(BlockCheck, TheBoundAloneSkipsDarkBlocksAndRefinesWhereItKnowsNothing) {
  const double floor = 0.05;
  EXPECT_EQ(decideByBound(boundOf(0.05), kSize, floor)->verdict, Verdict::Skip)
      << "at most the floor everywhere: skipped";
  EXPECT_FALSE(decideByBound(boundOf(0.06), kSize, floor).has_value())
      << "above the floor: the samples decide";
  EXPECT_EQ(decideByBound(boundOf(std::numeric_limits<double>::infinity()), kSize, floor)->verdict,
            Verdict::Refine)
      << "the ball reaches a lit facet";
  EXPECT_EQ(decideByBound(boundOf(std::nan("")), kSize, floor)->verdict, Verdict::Refine)
      << "a NaN bound never skips";
  EXPECT_EQ(decideByBound(boundOf(1.0), {2, 2, 2}, floor)->verdict, Verdict::Finest)
      << "a 2-voxel block is all samples";
  EXPECT_FALSE(decideByBound(boundOf(1.0), {8, 2, 2}, floor).has_value())
      << "a block that is exact along two axes still interpolates along the third";
  EXPECT_EQ(
      decideByBound(boundOf(std::numeric_limits<double>::infinity()), {8, 2, 4}, floor)->split,
      0b101)
      << "an unbounded block is halved along every axis but its exact one";
}

TEST(BlockCheck, AcceptsATrilinearFieldAndRefinesACurvedOne) {
  // Trilinear fields are interpolated exactly. 10 x², interpolated from the corners, misses
  // the middle sample by 2.5 (a quarter of its range; the octant fill misses by 0.625): a 1 %
  // tolerance refuses it, 30 % (3.05 allowed) accepts it.
  const auto trilinear = [](double x, double y, double z) { return 10.0 + 3 * x - 2 * y * z; };
  const Decision d = decide(sample(trilinear), boundOf(20.0), 0.01, 0.05);
  EXPECT_EQ(d.verdict, Verdict::Accept) << "exact for trilinear";
  EXPECT_EQ(d.power, 0);
  const auto curved = [](double x, double, double) { return 10.0 * x * x; };
  EXPECT_EQ(decide(sample(curved), boundOf(20.0), 0.01, 0.05).verdict, Verdict::Refine)
      << "x² is not trilinear to 1 %";
  EXPECT_EQ(decide(sample(curved), boundOf(20.0), 0.3, 0.05).verdict, Verdict::Accept)
      << "but it is to 30 %";
}

TEST(BlockCheck, AClassifyingFieldResolvesBelowItsThresholdOnlyToTheThresholdsAccuracy) {
  // 0.1 x², interpolated from the corners, misses its middle sample by 0.025 (the octant
  // centres by 0.00625). That is more than 1 % of its largest sample plus the floor (0.0011)
  // and of a threshold of 1 (0.0101), less than 1 % of a threshold of 3 (0.0301): a field that
  // only sorts its points against 3 accepts the block, its points then known to within what a
  // point at the threshold is; one that resolves values, or sorts against 1, refines it.
  const auto low = [](double x, double, double) { return 0.1 * x * x; };
  EXPECT_EQ(decide(sample(low), boundOf(2.0), 0.01, 1e-4).verdict, Verdict::Refine)
      << "resolved to 1 % of itself";
  EXPECT_EQ(decideBySamples(sample(low), kSize, boundOf(2.0), 0.01, 1e-4, 1.0).verdict,
            Verdict::Refine)
      << "a miss of 0.025 is more than 1 % of the threshold (0.0101)";
  EXPECT_EQ(decideBySamples(sample(low), kSize, boundOf(2.0), 0.01, 1e-4, 3.0).verdict,
            Verdict::Accept)
      << "and less than 1 % of a threshold of 3 (0.0301)";
  // At or above the threshold the samples' own tolerance rules, as in a resolving field.
  const auto high = [](double x, double, double) { return 10.0 * x * x; };
  EXPECT_EQ(decideBySamples(sample(high), kSize, boundOf(20.0), 0.01, 1e-4, 3.0).verdict,
            Verdict::Refine)
      << "x² from 0 to 10 is not trilinear to 1 % of 10";
}

TEST(BlockCheck, OctantCentresCatchAStepOnTheMiddleSamplePlane) {
  // A lobe edge exactly on the middle sample plane: 0, 0.5·E, E at x = 0, ½, 1 is linear to
  // the 3×3×3 lattice, but the octant centres (x = ¼, ¾) see 0 and E where the fill says ¼ E
  // and ¾ E.
  const auto step = [](double x, double, double) { return x < 0.5 ? 0.0 : x > 0.5 ? 8.0 : 4.0; };
  const Decision d = decide(sample(step), boundOf(10.0), 0.01, 0.05);
  EXPECT_EQ(d.verdict, Verdict::Refine);
  EXPECT_EQ(d.split, kSplitAll) << "no line of the 3×3×3 lattice bends: every axis is halved";
}

TEST(BlockCheck, AStepAcrossOneAxisHalvesOnlyThatAxis) {
  // A rim's edge at z = 0.6, level in x and y: only the lines along z bend, so the block is
  // halved across the step and kept whole along it.
  const auto rim = [](double x, double y, double z) { return z < 0.6 ? 10.0 + x + y : 0.0; };
  const Decision d = decide(sample(rim), boundOf(20.0), 0.01, 0.05);
  EXPECT_EQ(d.verdict, Verdict::Refine);
  EXPECT_EQ(d.split, 0b001) << "halved along z only";
  // A smooth curve in x and the step in z: both bend.
  const auto both = [](double x, double, double z) { return z < 0.6 ? 10.0 * x * x : 0.0; };
  EXPECT_EQ(decide(sample(both), boundOf(20.0), 0.01, 0.05).split, 0b101);
}

TEST(BlockCheck, AnExactAxisIsNotInterpolatedAcrossAStepOnIt) {
  // The rim's step between two lattice layers of a block exact along z (2 voxels: every layer
  // is a sample): each layer is linear in x and y, so the block is filled layer by layer.
  const BlockSize thin{8, 8, 2};
  const auto rim = [](double x, double y, double z) { return z < 0.75 ? 10.0 + x - y : 0.0; };
  const Decision d = decideBySamples(sampleBlock(thin, rim), thin, boundOf(20.0), 0.01, 0.05);
  EXPECT_EQ(d.verdict, Verdict::Accept) << "nothing is interpolated across z";
  // The same step in a block of 8 along z is not interpolated over.
  EXPECT_EQ(decide(sample(rim), boundOf(20.0), 0.01, 0.05).verdict, Verdict::Refine);
  // Curved in x on the thin block: halved along x only, never along its exact z.
  const auto curved = [](double x, double, double z) { return z < 0.75 ? 10.0 * x * x : 0.0; };
  const Decision c = decideBySamples(sampleBlock(thin, curved), thin, boundOf(20.0), 0.01, 0.05);
  EXPECT_EQ(c.verdict, Verdict::Refine);
  EXPECT_EQ(c.split, 0b100);
  // The fill of such a block reads each layer's own values: at t = 0 or 1 along z.
  std::array<double, kLatticeSamples> u{};
  for (std::size_t n = 0; n < u.size(); ++n) u[n] = static_cast<double>(n * n);
  EXPECT_DOUBLE_EQ(octantFill(u, {0, 1, 1}, {0.5, 0.0, 0.0}), 0.5 * (u[4] + u[13]))
      << "the middle layer (z = 1) halfway along x";
}

TEST(BlockCheck, FarFromTheTargetEOverRSquaredIsInterpolatedAsERSquared) {
  // E = 1/r² with the target a block's length away: E itself is not trilinear to 1 %, but E·r²
  // is constant, accepted as power 2 only where the block is far from the target.
  const std::array<double, 3> centre{-1.0, 0.5, 0.5};
  const auto inverse_square = [&](double x, double y, double z) {
    return 100.0 /
           (std::pow(x - centre[0], 2) + std::pow(y - centre[1], 2) + std::pow(z - centre[2], 2));
  };
  const Decision far = decide(sample(inverse_square, true, centre), boundOf(200.0), 0.01, 0.05);
  EXPECT_EQ(far.verdict, Verdict::Accept) << "E·r² is constant";
  EXPECT_EQ(far.power, 2);
  EXPECT_EQ(decide(sample(inverse_square, false, centre), boundOf(200.0), 0.01, 0.05).verdict,
            Verdict::Refine)
      << "near the target only E itself may be interpolated";
}

TEST(BlockCheck, RefinesWhereASampleIsNotFiniteInsideTheTargetOrAGlintMayPassBetween) {
  const auto flat = [](double, double, double) { return 5.0; };
  BlockSamples nan = sample(flat);
  nan.irradiance_w_m2[13] = std::nan("");
  EXPECT_EQ(decide(nan, boundOf(10.0), 0.01, 0.05).verdict, Verdict::Refine) << "NaN";
  BlockSamples inf = sample(flat);
  inf.irradiance_w_m2[30] = std::numeric_limits<double>::infinity();
  EXPECT_EQ(decide(inf, boundOf(10.0), 0.01, 0.05).verdict, Verdict::Refine) << "+∞";
  BlockSamples inside = sample(flat);
  inside.excluded = true;
  EXPECT_EQ(decide(inside, boundOf(10.0), 0.01, 0.05).verdict, Verdict::Refine)
      << "a sample inside the target";
  // Allowed: 0.01 × 5 + 0.05 = 0.1. A narrow glint bounded above that may pass between the
  // samples of a block whose samples are all flat.
  EXPECT_EQ(decide(sample(flat), boundOf(10.0, 0.11), 0.01, 0.05).verdict, Verdict::Refine)
      << "a glint narrower than the samples may exceed the budget";
  EXPECT_EQ(decide(sample(flat), boundOf(10.0, 0.09), 0.01, 0.05).verdict, Verdict::Accept)
      << "one bounded within the budget may not";
  EXPECT_EQ(decide(sample(flat), boundOf(10.0, std::nan("")), 0.01, 0.05).verdict, Verdict::Refine)
      << "a NaN narrow bound refines";
}

TEST(BlockCheck, AFinestBlockReportsANarrowGlintOnlyWhereItsBoundOutgrowsItsSamples) {
  // Samples up to 5, tolerance 0.01, floor 0.05: they vouch for 5 + 0.01 × 5 + 0.05 = 5.1.
  const auto most = [](double upper, double narrow, double threshold) {
    return narrowGlintBound(boundOf(upper, narrow), 5.0, 0.01, 0.05, threshold);
  };
  EXPECT_EQ(most(20.0, 15.0, 10.0), std::optional<double>(20.0))
      << "a pencil the samples miss, bounded above 10 as a whole";
  ASSERT_TRUE(most(30.0, 15.0, 10.0).has_value());
  EXPECT_NEAR(*most(30.0, 15.0, 10.0), 5.1 + 15.0, 1e-12)
      << "what the samples vouch for plus the narrow light, below the whole bound";
  EXPECT_EQ(most(20.0, 0.09, 10.0), std::nullopt) << "narrow light the samples vouch for";
  EXPECT_EQ(most(5.09, 5.09, 0.0), std::nullopt) << "the whole bound within 5.1";
  EXPECT_EQ(most(9.9, 9.9, 10.0), std::nullopt) << "a bound below the threshold cannot reach it";
  EXPECT_EQ(most(9.9, 9.9, 0.0), std::optional<double>(9.9)) << "without a threshold it counts";
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_EQ(most(inf, inf, 10.0), std::optional<double>(inf)) << "no finite bound";
  EXPECT_EQ(most(std::nan(""), 1.0, 10.0), std::optional<double>(inf)) << "NaN: unbounded";
  EXPECT_EQ(narrowGlintBound(boundOf(20.0, 15.0), std::nan(""), 0.01, 0.05, 10.0),
            std::optional<double>(inf))
      << "a NaN sample vouches for nothing";
}

TEST(BlockCheck, OctantFillMatchesTheCornersAndIsTrilinearWithinEachOctant) {
  std::array<double, kLatticeSamples> u{};
  for (int a = 0; a < 3; ++a)
    for (int c = 0; c < 3; ++c)
      for (int e = 0; e < 3; ++e)
        u[static_cast<std::size_t>(9 * a + 3 * c + e)] = a + 10 * c + 100 * e * e;
  // At an octant's corners, the lattice values; inside, trilinear between them.
  EXPECT_DOUBLE_EQ(octantFill(u, {1, 0, 1}, {0.0, 0.0, 0.0}), u[9 + 0 + 1]);
  EXPECT_DOUBLE_EQ(octantFill(u, {1, 0, 1}, {1.0, 1.0, 1.0}), u[18 + 3 + 2]);
  EXPECT_DOUBLE_EQ(octantFill(u, {0, 1, 1}, {0.5, 0.25, 0.5}), 0.5 + 10 * 1.25 + 100 * 2.5)
      << "e² is linear between e = 1 and 2 (1 and 4)";
}

}  // namespace
}  // namespace glint::field
