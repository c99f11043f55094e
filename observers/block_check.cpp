#include "observers/block_check.h"

#include <algorithm>
#include <cmath>

namespace glint::field {
namespace {

// Interpolation from a block's corners must match its finer samples, and the fill from those
// must match the octant centres, to this share of the block's budget (tolerance × largest
// sample + floor). The fill is octant by octant from the finer samples: where the field is
// smooth its error is about a quarter of what the corner check measured (trilinear
// interpolation is second order), and the octant centres measure it where it is largest.
constexpr double kCheckShare = 1.0;

// The eight corners of octant (o >> 2, (o >> 1) & 1, o & 1) of the 3×3×3 lattice @p u, in
// trilinear()'s order.
std::array<double, 8> octantCorners(const std::array<double, kLatticeSamples>& u,
                                    const std::array<int, 3>& octant) {
  std::array<double, 8> corners{};
  for (int c = 0; c < 8; ++c) {
    corners[static_cast<std::size_t>(c)] = u[static_cast<std::size_t>(
        9 * (octant[0] + (c >> 2)) + 3 * (octant[1] + ((c >> 1) & 1)) + (octant[2] + (c & 1)))];
  }
  return corners;
}

// Whether E·w interpolated from the block's corners, divided by w, meets every sample of the
// 3×3×3 lattice, and the octant-by-octant fill from those meets every octant centre, within
// `allowed` (v and w in forEachSample's order; the octant centres only if there are any).
bool interpolates(const BlockValues& v, const BlockValues& w, std::size_t count, double allowed) {
  std::array<double, kLatticeSamples> u{};
  for (std::size_t s = 0; s < kLatticeSamples; ++s) u[s] = v[s] * w[s];
  const std::array<double, 8> corners = {u[0], u[2], u[6], u[8], u[18], u[20], u[24], u[26]};
  for (int a = 0; a < 3; ++a)
    for (int c = 0; c < 3; ++c)
      for (int e = 0; e < 3; ++e) {
        const auto s = static_cast<std::size_t>(9 * a + 3 * c + e);
        const double interpolated = trilinear(corners, 0.5 * a, 0.5 * c, 0.5 * e) / w[s];
        if (!(std::abs(interpolated - v[s]) <= allowed)) return false;
      }
  if (count < kBlockSamples) return true;
  // The fill at each octant centre: the mean of the octant's eight corners.
  for (std::size_t oct = 0; oct < 8; ++oct) {
    double mean = 0.0;
    const std::array<int, 3> o{static_cast<int>(oct >> 2), static_cast<int>((oct >> 1) & 1),
                               static_cast<int>(oct & 1)};
    for (const double corner : octantCorners(u, o)) mean += corner;
    if (!(std::abs(0.125 * mean / w[kLatticeSamples + oct] - v[kLatticeSamples + oct]) <=
          allowed)) {
      return false;
    }
  }
  return true;
}

}  // namespace

std::optional<Decision> decideByBound(const BallBound& bound, int size, double floor_w_m2) {
  if (bound.upper_w_m2 <= floor_w_m2) return Decision{Verdict::Skip};
  if (size <= 2) return Decision{Verdict::Finest};
  if (!bound.bounded()) return Decision{Verdict::Refine};  // (NaN included)
  return std::nullopt;
}

Decision decideBySamples(const BlockSamples& samples, const BallBound& bound, double tolerance,
                         double floor_w_m2) {
  // The target is in the block: resolve it finely.
  if (samples.excluded || samples.count < kLatticeSamples) return {Verdict::Refine};
  double largest = 0.0;
  for (std::size_t s = 0; s < samples.count; ++s) {
    const double v = samples.irradiance_w_m2[s];
    // A sample that is not a finite number gives no budget to check against: look closer.
    if (!std::isfinite(v)) return {Verdict::Refine};
    largest = std::max(largest, std::abs(v));
  }
  const double allowed = kCheckShare * (tolerance * largest + floor_w_m2);
  // A coarse facet whose light could pass between the samples leaves no trace in them: only
  // the bound can say whether such a glint is too weak to matter.
  if (!(bound.narrow_w_m2 <= allowed)) return {Verdict::Refine};
  for (const int power : kInterpolationPowers) {
    if (power > 0 && !samples.far_from_target) break;
    BlockValues w{};
    for (std::size_t s = 0; s < samples.count; ++s) {
      w[s] = spreadWeight(samples.distance_m[s], power);
    }
    if (interpolates(samples.irradiance_w_m2, w, samples.count, allowed)) {
      return {Verdict::Accept, power};
    }
  }
  return {Verdict::Refine};
}

double trilinear(const std::array<double, 8>& c, double u, double v, double w) {
  const double x00 = c[0] + u * (c[4] - c[0]), x01 = c[1] + u * (c[5] - c[1]);
  const double x10 = c[2] + u * (c[6] - c[2]), x11 = c[3] + u * (c[7] - c[3]);
  const double y0 = x00 + v * (x10 - x00), y1 = x01 + v * (x11 - x01);
  return y0 + w * (y1 - y0);
}

double octantFill(const std::array<double, kLatticeSamples>& weighted,
                  const std::array<int, 3>& octant, const std::array<double, 3>& t) {
  return trilinear(octantCorners(weighted, octant), t[0], t[1], t[2]);
}

}  // namespace glint::field
