#pragma once
/// @file
/// @brief The six cube faces over which glint parameterises directions about a centre: the far
/// field's map (observers/far_field.cpp) and the reach's radial lattices (observers/reach.cpp)
/// share them, so that a direction's lattice cell is the same on both. Internal to observers/.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>

#include "facets/vec3.h"

namespace glint::cube {

constexpr int kFaces = 6;

/// Outward normal, u and v of each face (u × v = normal: the plane's lattice axes), in the
/// order +x, −x, +y, −y, +z, −z.
struct FaceFrame {
  Vec3 normal, u, v;
};
inline const std::array<FaceFrame, kFaces> kFaceFrames = {{
    {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}},
    {{-1, 0, 0}, {0, -1, 0}, {0, 0, 1}},
    {{0, 1, 0}, {0, 0, 1}, {1, 0, 0}},
    {{0, -1, 0}, {0, 0, -1}, {1, 0, 0}},
    {{0, 0, 1}, {1, 0, 0}, {0, 1, 0}},
    {{0, 0, -1}, {-1, 0, 0}, {0, 1, 0}},
}};

/// Where direction @p d (n · d > 0) crosses the plane of face @p face, in lattice units of
/// @p face_pixels intervals per edge: 0 .. face_pixels on the face, beyond it on the plane.
struct PlanePoint {
  double x = 0.0, y = 0.0;
};
inline PlanePoint onFacePlane(const Vec3& d, int face, int face_pixels) {
  const FaceFrame& f = kFaceFrames[static_cast<std::size_t>(face)];
  const double t = 1.0 / glm::dot(d, f.normal);
  const double half = 0.5 * face_pixels;
  return {(t * glm::dot(d, f.u) + 1.0) * half, (t * glm::dot(d, f.v) + 1.0) * half};
}

/// The unit direction through point (x, y) of face @p face's plane, in its lattice units.
inline Vec3 planeDirection(int face, double x, double y, int face_pixels) {
  const FaceFrame& f = kFaceFrames[static_cast<std::size_t>(face)];
  const double half = 0.5 * face_pixels;
  return glm::normalize(f.normal + (x / half - 1.0) * f.u + (y / half - 1.0) * f.v);
}

/// The face whose cone holds @p d, and where d crosses it in lattice units (0 .. face_pixels).
struct FaceHit {
  int face = 0;
  double x = 0.0, y = 0.0;
};
inline FaceHit faceHit(const Vec3& d, int face_pixels) {
  int axis = 0;
  for (int a = 1; a < 3; ++a) {
    if (std::abs(d[a]) > std::abs(d[axis])) axis = a;
  }
  const int face = 2 * axis + (d[axis] < 0.0 ? 1 : 0);  // n · d > 0: the dominant axis
  const PlanePoint p = onFacePlane(d, face, face_pixels);
  const auto n = static_cast<double>(face_pixels);
  return {face, std::clamp(p.x, 0.0, n), std::clamp(p.y, 0.0, n)};
}

/// The direction of the centre of pixel @p p of a width × height map in longitude and
/// latitude: column i at azimuth −π + (i + ½) 2π/width from +x toward +y, row j at elevation
/// −π/2 + (j + ½) π/height toward +z.
inline Vec3 latLongDirection(std::size_t p, int width, int height) {
  const auto w = static_cast<std::size_t>(width);
  const double elevation = -0.5 * kPi + (static_cast<double>(p / w) + 0.5) * kPi / height;
  const double azimuth = -kPi + (static_cast<double>(p % w) + 0.5) * 2.0 * kPi / width;
  return {std::cos(elevation) * std::cos(azimuth), std::cos(elevation) * std::sin(azimuth),
          std::sin(elevation)};
}

}  // namespace glint::cube
