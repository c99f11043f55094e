#pragma once
/// @file
/// @brief The 3-vector of glint's geometry (GLM's double-precision vector) and the few helpers
/// the physics needs beyond GLM: normalisation that cannot produce NaN, and robust angles.

#include <cmath>
#include <glm/geometric.hpp>
#include <glm/vec3.hpp>
#include <optional>

namespace glint {

/// @brief A position (m) or direction in 3-D, double precision throughout.
using Vec3 = glm::dvec3;

inline constexpr double kPi = 3.14159265358979323846;

/// @brief Unit vector along @p v, or nothing when @p v is zero or not finite.
/// GLM's normalize divides by the length unchecked; this is the form that never yields NaN.
inline std::optional<Vec3> tryNormalize(const Vec3& v) {
  const double len = glm::length(v);
  if (!(len > 0.0) || !std::isfinite(len)) return std::nullopt;
  return v / len;
}

/// @brief Angle in radians between two vectors of any non-zero length.
/// The atan2 form keeps full precision near 0 and π, where acos of a dot product loses it.
inline double angleBetween(const Vec3& a, const Vec3& b) {
  return std::atan2(glm::length(glm::cross(a, b)), glm::dot(a, b));
}

/// @brief A unit vector perpendicular to the unit vector @p n (any one; deterministic).
inline Vec3 anyPerpendicular(const Vec3& n) {
  // Cross with the coordinate axis least aligned with n, so the result is never short.
  const Vec3 a = std::abs(n.x) <= std::abs(n.y) && std::abs(n.x) <= std::abs(n.z) ? Vec3(1, 0, 0)
                 : std::abs(n.y) <= std::abs(n.z)                                 ? Vec3(0, 1, 0)
                                                                                  : Vec3(0, 0, 1);
  return glm::normalize(glm::cross(n, a));
}

}  // namespace glint
