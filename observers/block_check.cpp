#include "observers/block_check.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>

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

std::size_t latticeIndex(const std::array<int, 3>& i) {
  return static_cast<std::size_t>(9 * i[0] + 3 * i[1] + i[2]);
}

// The interpolation of the 3×3×3 lattice @p u at lattice index @p at (each 0, 1 or 2): linear
// between the ends (0 and 2) along the axes that are not exact, the lattice's own value along
// the exact ones (both "ends" there are the sample itself, at t = 0).
double interpolateLattice(const std::array<double, kLatticeSamples>& u, const BlockSize& size,
                          const std::array<int, 3>& at) {
  std::array<double, 8> corners{};
  for (int c = 0; c < 8; ++c) {
    std::array<int, 3> i{};
    for (int a = 0; a < 3; ++a) {
      const std::size_t sa = static_cast<std::size_t>(a);
      i[sa] = exactAxis(size, a) ? at[sa] : 2 * ((c >> (2 - a)) & 1);
    }
    corners[static_cast<std::size_t>(c)] = u[latticeIndex(i)];
  }
  const auto t = [&](int a) {
    return exactAxis(size, a) ? 0.0 : 0.5 * at[static_cast<std::size_t>(a)];
  };
  return trilinear(corners, t(0), t(1), t(2));
}

// The fill at the centre of octant @p o: the mean of its eight corners, taken at the middle
// sample along the exact axes.
double octantCentreFill(const std::array<double, kLatticeSamples>& u, const BlockSize& size,
                        const std::array<int, 3>& o) {
  double sum = 0.0;
  for (int c = 0; c < 8; ++c) {
    std::array<int, 3> i{};
    for (int a = 0; a < 3; ++a) {
      const std::size_t sa = static_cast<std::size_t>(a);
      i[sa] = exactAxis(size, a) ? 1 : o[sa] + ((c >> (2 - a)) & 1);
    }
    sum += u[latticeIndex(i)];
  }
  return 0.125 * sum;
}

// How E·w interpolated from the block's corners, divided by w, meets the samples, each within
// `allowed` (v and w in forEachSample's order; the octant centres only if there are any).
struct Fit {
  bool passes = true;          // every sample met
  std::uint8_t bent_axes = 0;  // split mask of the axes along which some line of samples bends
};

Fit fit(const BlockValues& v, const BlockValues& w, std::size_t count, const BlockSize& size,
        double allowed) {
  std::array<double, kLatticeSamples> u{};
  for (std::size_t s = 0; s < kLatticeSamples; ++s) u[s] = v[s] * w[s];
  Fit result;
  for (int a = 0; a < 3; ++a)
    for (int c = 0; c < 3; ++c)
      for (int e = 0; e < 3; ++e) {
        const std::array<int, 3> at{a, c, e};
        const std::size_t s = latticeIndex(at);
        if (!(std::abs(interpolateLattice(u, size, at) / w[s] - v[s]) <= allowed)) {
          result.passes = false;
        }
        // The middle of a line along each axis against the mean of its ends.
        for (int axis = 0; axis < 3; ++axis) {
          const std::size_t sa = static_cast<std::size_t>(axis);
          if (at[sa] != 1 || exactAxis(size, axis)) continue;
          std::array<int, 3> lo = at, hi = at;
          lo[sa] = 0;
          hi[sa] = 2;
          const double mid = 0.5 * (u[latticeIndex(lo)] + u[latticeIndex(hi)]) / w[s];
          if (!(std::abs(mid - v[s]) <= allowed)) {
            result.bent_axes = static_cast<std::uint8_t>(result.bent_axes | (4 >> axis));
          }
        }
      }
  if (count < kBlockSamples) return result;
  for (std::size_t oct = 0; oct < 8; ++oct) {
    const std::array<int, 3> o{static_cast<int>(oct >> 2), static_cast<int>((oct >> 1) & 1),
                               static_cast<int>(oct & 1)};
    const double fill = octantCentreFill(u, size, o) / w[kLatticeSamples + oct];
    if (!(std::abs(fill - v[kLatticeSamples + oct]) <= allowed)) result.passes = false;
  }
  return result;
}

}  // namespace

std::uint8_t splittableAxes(const BlockSize& size) {
  std::uint8_t mask = 0;
  for (int a = 0; a < 3; ++a) {
    if (!exactAxis(size, a)) mask = static_cast<std::uint8_t>(mask | (4 >> a));
  }
  return mask;
}

std::optional<Decision> decideByBound(const BallBound& bound, const BlockSize& size,
                                      double floor_w_m2) {
  if (bound.upper_w_m2 <= floor_w_m2) return Decision{Verdict::Skip};
  const std::uint8_t all = splittableAxes(size);
  if (all == 0) return Decision{Verdict::Finest};
  if (!bound.bounded()) return Decision{Verdict::Refine, 0, all};  // (NaN included)
  return std::nullopt;
}

std::optional<double> narrowGlintBound(const BallBound& bound, double largest_sample_w_m2,
                                       double tolerance, double floor_w_m2, double threshold_w_m2) {
  const double vouched = kCheckShare * (tolerance * largest_sample_w_m2 + floor_w_m2);
  if (std::isnan(vouched) || std::isnan(bound.narrow_w_m2) || std::isnan(bound.upper_w_m2)) {
    return std::numeric_limits<double>::infinity();
  }
  if (bound.narrow_w_m2 <= vouched) return std::nullopt;
  const double most = std::min(bound.upper_w_m2, largest_sample_w_m2 + vouched + bound.narrow_w_m2);
  if (most <= largest_sample_w_m2 + vouched || most < threshold_w_m2) return std::nullopt;
  return most;
}

Decision decideBySamples(const BlockSamples& samples, const BlockSize& size, const BallBound& bound,
                         double tolerance, double floor_w_m2, double resolve_w_m2) {
  const std::uint8_t all = splittableAxes(size);
  const Decision everywhere{Verdict::Refine, 0, all};
  // The target is in the block: resolve it finely.
  if (samples.excluded || samples.count < kLatticeSamples) return everywhere;
  double largest = 0.0;
  for (std::size_t s = 0; s < samples.count; ++s) {
    const double v = samples.irradiance_w_m2[s];
    // A sample that is not a finite number gives no budget to check against: look closer.
    if (!std::isfinite(v)) return everywhere;
    largest = std::max(largest, std::abs(v));
  }
  const double allowed = kCheckShare * (tolerance * std::max(largest, resolve_w_m2) + floor_w_m2);
  // A coarse facet whose light could pass between the samples leaves no trace in them: only
  // the bound can say whether such a glint is too weak to matter.
  if (!(bound.narrow_w_m2 <= allowed)) return everywhere;
  std::uint8_t split = all;
  for (const int power : kInterpolationPowers) {
    if (power > 0 && !samples.far_from_target) break;
    BlockValues w{};
    for (std::size_t s = 0; s < samples.count; ++s) {
      w[s] = spreadWeight(samples.distance_m[s], power);
    }
    const Fit f = fit(samples.irradiance_w_m2, w, samples.count, size, allowed);
    if (f.passes) return {Verdict::Accept, power};
    // Halve only where the lines of samples bend; where none does, the miss lies between the
    // axes (or at an octant centre) and every axis is halved.
    const std::uint8_t bent = f.bent_axes & all;
    if (bent != 0 && std::popcount(bent) < std::popcount(split)) split = bent;
  }
  return {Verdict::Refine, 0, split};
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
