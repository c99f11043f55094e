#pragma once
/// @file
/// @brief The adaptive field's block check: whether a block of the observer lattice is
/// skipped (its bound proves it dark), filled by interpolating its samples, or refined.
///
/// Pure functions of a block's bound and samples, used by the field builder
/// (observers/field.cpp) and testable without a field. Every test that meets a NaN, an
/// infinity, a sample inside the target or a glint narrower than the samples answers
/// "refine", never "accept" or "skip".

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>

#include "facets/integrator.h"

namespace glint::field {

/// A block's edge in voxels per axis, each a power of two and at least 2. Blocks are split
/// only along the axes whose samples show that they must be (a rim's step is resolved across
/// itself and interpolated along itself). An axis of 2 voxels is *exact*: every lattice point
/// along it is a sample, so nothing is interpolated along it.
using BlockSize = std::array<int, 3>;

/// @brief Whether axis @p a of a block of @p size is exact (see BlockSize).
inline bool exactAxis(const BlockSize& size, int a) {
  return size[static_cast<std::size_t>(a)] <= 2;
}

/// Samples of a block: the 3×3×3 lattice at offsets 0, size/2 and size per axis (index
/// 9a + 3c + e), then, for blocks with an axis of 4 voxels or more, the centres of its eight
/// octants (index 27 + 4x + 2y + z): a quarter and three quarters of the way along each axis
/// of 4 or more, the middle sample along an exact one. The octant centres check the fill
/// itself: a step on the middle sample plane (a lobe edge on a round coordinate) looks linear
/// to the 3×3×3 lattice, but not to the points a quarter of the way in.
inline constexpr std::size_t kLatticeSamples = 27;
inline constexpr std::size_t kBlockSamples = 35;
using BlockValues = std::array<double, kBlockSamples>;

/// @brief Calls fn(di, dj, dk) for every sample of a block of edges @p size (voxels), as
/// offsets from its origin, in the order above.
template <class Fn>
void forEachSample(const BlockSize& size, Fn&& fn) {
  for (int a = 0; a < 3; ++a)
    for (int c = 0; c < 3; ++c)
      for (int e = 0; e < 3; ++e) fn(a * size[0] / 2, c * size[1] / 2, e * size[2] / 2);
  if (size[0] < 4 && size[1] < 4 && size[2] < 4) return;
  const auto centre = [&](std::size_t axis, int upper) {
    const int s = size[axis];
    return s >= 4 ? s / 4 * (1 + 2 * upper) : s / 2;
  };
  for (int oct = 0; oct < 8; ++oct) {
    fn(centre(0, oct >> 2), centre(1, (oct >> 1) & 1), centre(2, oct & 1));
  }
}

/// Far from the target the field falls off as a power of the distance r from it: 1/r² from a
/// compact glint, about 1/r where a cylinder's line of glints spreads it in one plane only.
/// Trilinear interpolation of such a field errs by about 0.75 (h/r)² per power, so a 1 % check
/// would keep blocks under a tenth of their distance. A block may instead interpolate E·r^p
/// for the first of these powers whose interpolation passes the same checks against the same
/// samples; E·r² is then nearly constant and a block may be as large as the field is smooth.
inline constexpr std::array<int, 3> kInterpolationPowers = {0, 2, 1};

/// @brief r^p, the weight of E for power p of kInterpolationPowers at distance @p r_m.
inline double spreadWeight(double r_m, int power) {
  return power == 0 ? 1.0 : power == 1 ? r_m : r_m * r_m;
}

enum class Verdict : std::uint8_t { Skip, Accept, Refine, Finest };

/// A split mask names the axes a block is halved along as the child index 4x + 2y + z does:
/// x is 0b100, y 0b010, z 0b001 (axis a is 4 >> a).
inline constexpr std::uint8_t kSplitAll = 0b111;

struct Decision {
  Verdict verdict = Verdict::Refine;
  int power = 0;  ///< an accepted block interpolates E·r^power (see kInterpolationPowers)
  /// The axes a refined block is halved along (a split mask); never an exact one.
  std::uint8_t split = kSplitAll;
};

/// @brief The axes of @p size that may still be halved (a split mask of those not exact).
std::uint8_t splittableAxes(const BlockSize& size);

/// @brief What a block's bound alone decides, before any of its samples is read: Skip where it
/// proves every point at most @p floor_w_m2 (NaN never does), Finest for a block exact along
/// every axis (every lattice point of it is a sample), Refine along every axis that may be
/// halved where the ball around the block reaches a lit facet (a small mirror inside it sends
/// a pencil no sample meets, and no bound says how bright); nothing where the samples must
/// decide.
std::optional<Decision> decideByBound(const BallBound& bound, const BlockSize& size,
                                      double floor_w_m2);

/// @brief What a block that decideByBound() made Finest may receive beyond what its samples
/// show, where a glint narrower than its lattice (BallBound::narrow_w_m2) may pass between them:
/// the light its samples vouch for (the largest, @p largest_sample_w_m2, plus tolerance × it +
/// floor) plus that narrow light's bound, or the block's whole bound if lower. Nothing where
/// the narrow light is within what the samples vouch for, or where that bound stays within
/// it or below @p threshold_w_m2. Every lattice point of such a block is a sample, so nothing
/// finer can be asked of the lattice: only the bound can say how bright the glint may be.
/// +∞ where a bound or sample is NaN.
std::optional<double> narrowGlintBound(const BallBound& bound, double largest_sample_w_m2,
                                       double tolerance, double floor_w_m2, double threshold_w_m2);

/// @brief What one block's samples show.
struct BlockSamples {
  std::size_t count = 0;  ///< 27, or 35 with the octant centres (an axis of 4 voxels or more)
  BlockValues irradiance_w_m2{};  ///< in forEachSample()'s order
  /// Each sample's distance r from the lit facets' centre, whose powers weigh E (see
  /// spreadWeight()); read only where far_from_target.
  BlockValues distance_m{};
  bool excluded = false;         ///< a sample lies inside the target
  bool far_from_target = false;  ///< clear of the centre by the block's own diagonal
};

/// @brief The verdict of a block of @p size that decideByBound() left to its samples: Accept
/// (with the first power of kInterpolationPowers whose interpolation passes) where the
/// interpolation from the corners along the axes that are not exact meets every lattice
/// sample, and the octant-by-octant fill meets every octant centre, within tolerance × the
/// largest sample + floor, and no glint narrower than the samples (the bound's narrow part)
/// can exceed that. Refine otherwise: along every axis that may be halved wherever a sample is
/// inside the target or not finite, a glint may pass between the samples, or no single axis
/// explains the miss; else only along the axes whose lines of three samples are not linear
/// (for the power with the fewest such axes). With @p resolve_w_m2 > 0 (a classifying field's
/// threshold), the tolerance is taken of the largest sample or of it, whichever is more: below
/// the threshold the samples need only the accuracy a point at it has.
Decision decideBySamples(const BlockSamples& samples, const BlockSize& size, const BallBound& bound,
                         double tolerance, double floor_w_m2, double resolve_w_m2 = 0.0);

/// @brief Trilinear interpolation between the corners @p c (index 4x + 2y + z) at (u, v, w).
double trilinear(const std::array<double, 8>& c, double u, double v, double w);

/// @brief The fill of an accepted block: from the 3×3×3 lattice of E·r^p (@p weighted), the
/// trilinear value in octant @p octant (each 0 or 1) at local coordinates @p t ∈ [0, 1]³ (0 or
/// 1 along an exact axis, where the fill is the lattice's own value).
double octantFill(const std::array<double, kLatticeSamples>& weighted,
                  const std::array<int, 3>& octant, const std::array<double, 3>& t);

}  // namespace glint::field
