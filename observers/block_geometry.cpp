#include "observers/detail/block_geometry.h"

#include <algorithm>
#include <cmath>

namespace glint::field {
namespace {

// The middle of the bounding box of @p corners: a radial block's centre.
Vec3 middle(const std::array<Vec3, 8>& corners) {
  Vec3 lo = corners[0], hi = corners[0];
  for (const Vec3& p : corners) lo = glm::min(lo, p), hi = glm::max(hi, p);
  return 0.5 * (lo + hi);
}

}  // namespace

Vec3 BlockGeometry::centre(const Index3& o, const BlockSize& size) const {
  if (spec_.surface) return surfaceCentre(o, size);
  if (spec_.radial) return middle(corners(o, size));
  const std::array<Vec3, 3>& e = spec_.axes;
  return spec_.position(o[0], o[1], o[2]) +
         spec_.voxel_m *
             (0.5 * size[0] * e[0] + 0.5 * size[1] * e[1] + (flat_ ? 0.0 : 0.5 * size[2]) * e[2]);
}

// Half the block's diagonal (a plane's block has no depth). The edges are powers of two, so
// their ratios to the longest are exact.
double BlockGeometry::radius(const Index3& o, const BlockSize& size) const {
  if (spec_.surface) return surfaceRadius(o, size);
  if (spec_.radial) {
    const std::array<Vec3, 8> c = corners(o, size);
    const Vec3 m = middle(c);
    double r = 0.0;
    for (const Vec3& p : c) r = std::max(r, glm::length(p - m));
    return r * (1.0 + 1e-12);  // the corners themselves inside, whatever the rounding
  }
  const int longest = std::max({size[0], size[1], flat_ ? 0 : size[2]});
  double squares = 0.0;
  for (std::size_t a = 0; a < (flat_ ? 2u : 3u); ++a) {
    const double ratio = static_cast<double>(size[a]) / longest;
    squares += ratio * ratio;
  }
  return 0.5 * std::sqrt(squares) * spec_.voxel_m * longest;
}

double BlockGeometry::sampleSpacing(const Index3& o, const BlockSize& size) const {
  if (spec_.surface || spec_.radial) return measuredSampleSpacing(o, size);
  const int widest = std::max({size[0], size[1], flat_ ? 0 : size[2]});
  return spec_.voxel_m * std::max(1, widest / 2);
}

// Neither a radial lattice's samples (its layers grow outward, its rays spread) nor a surface's
// (a slope stretches them) are evenly spaced: the widest gap between neighbouring samples of the
// block's 3 × 3 × 3 (3 × 3 on a plane), measured along their straight lines.
double BlockGeometry::measuredSampleSpacing(const Index3& o, const BlockSize& size) const {
  const int depth = flat_ ? 0 : size[2];
  const std::array<int, 3> h = {std::max(1, size[0] / 2), std::max(1, size[1] / 2),
                                std::max(1, depth / 2)};
  double widest_m = 0.0;
  const auto gap = [&](const Vec3& p, int a, int b, int c) {
    widest_m = std::max(widest_m, glm::length(spec_.position(o[0] + a, o[1] + b, o[2] + c) - p));
  };
  for (int a = 0; a <= size[0]; a += h[0])
    for (int b = 0; b <= size[1]; b += h[1])
      for (int c = 0; c <= depth; c += h[2]) {
        const Vec3 p = spec_.position(o[0] + a, o[1] + b, o[2] + c);
        if (a + h[0] <= size[0]) gap(p, a + h[0], b, c);
        if (b + h[1] <= size[1]) gap(p, a, b + h[1], c);
        if (c + h[2] <= depth) gap(p, a, b, c + h[2]);
      }
  return widest_m;
}

// The convex hull of a radial lattice's block is a frustum of a pyramid with its apex at the
// centre, so every point of it lies in a ball about its corners.
std::array<Vec3, 8> BlockGeometry::corners(const Index3& o, const BlockSize& size) const {
  std::array<Vec3, 8> c{};
  for (int q = 0; q < 8; ++q) {
    c[static_cast<std::size_t>(q)] = spec_.position(
        o[0] + ((q >> 2) & 1) * size[0], o[1] + ((q >> 1) & 1) * size[1], o[2] + (q & 1) * size[2]);
  }
  return c;
}

// A plane over a surface: the block's points lie in the box of its square and the range of
// their offsets, so the ball about that box holds them.
std::array<double, 2> BlockGeometry::offsetRange(const Index3& o, const BlockSize& size) const {
  return spec_.surface->range(o[0], o[1], o[0] + size[0], o[1] + size[1]);
}

Vec3 BlockGeometry::surfaceCentre(const Index3& o, const BlockSize& size) const {
  const std::array<double, 2> r = offsetRange(o, size);
  const std::array<Vec3, 3>& e = spec_.axes;
  return spec_.min_m +
         spec_.voxel_m * ((o[0] + 0.5 * size[0]) * e[0] + (o[1] + 0.5 * size[1]) * e[1]) +
         0.5 * (r[0] + r[1]) * e[2];
}

double BlockGeometry::surfaceRadius(const Index3& o, const BlockSize& size) const {
  const std::array<double, 2> r = offsetRange(o, size);
  const double u = spec_.voxel_m * size[0], v = spec_.voxel_m * size[1], w = r[1] - r[0];
  return 0.5 * std::sqrt(u * u + v * v + w * w) * (1.0 + 1e-12);
}

}  // namespace glint::field
