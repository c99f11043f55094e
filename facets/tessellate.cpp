#include "facets/tessellate.h"

#include <algorithm>
#include <cmath>

#include "facets/quadric_fit.h"

namespace glint {
namespace {

// A unit vector perpendicular to unit @p n, taken from @p reference where it can be.
Vec3 perpendicularToward(const Vec3& n, const Vec3& reference) {
  if (auto u = tryNormalize(reference - glm::dot(reference, n) * n)) {
    // A reference within ~1e-6 rad of n leaves only rounding noise: no usable azimuth.
    if (glm::length(reference - glm::dot(reference, n) * n) > 1e-6) return *u;
  }
  return anyPerpendicular(n);
}

double twoPiOver(int n) { return 2.0 * kPi / n; }

}  // namespace

std::uint32_t addCylinder(Target& target, const CylinderShape& s, std::uint32_t material,
                          int segments, const Vec3& reference) {
  const std::uint32_t obj = target.addObject({s.center_m, material, std::nullopt});
  const std::uint32_t q = target.addQuadric(Quadric::cylinder(Vec3(0.0), s.axis, s.radius_m));
  const Vec3 u = perpendicularToward(s.axis, reference);
  const Vec3 v = glm::cross(s.axis, u);
  const double arc = s.radius_m * twoPiOver(segments);
  const int rings = std::max(1, static_cast<int>(std::lround(s.length_m / arc)));
  auto point = [&](int k, int j) {
    const double phi = k * twoPiOver(segments);
    const double z = -0.5 * s.length_m + s.length_m * j / rings;
    return s.radius_m * (std::cos(phi) * u + std::sin(phi) * v) + z * s.axis;
  };
  for (int j = 0; j < rings; ++j) {
    for (int k = 0; k < segments; ++k) {
      // Around (+φ) then along (+axis) is counter-clockwise seen from outside.
      const Vec3 a = point(k, j), b = point(k + 1, j), c = point(k + 1, j + 1), d = point(k, j + 1);
      target.addFacet(obj, {a, b, c}, SurfaceModel::Quadric, q);
      target.addFacet(obj, {a, c, d}, SurfaceModel::Quadric, q);
    }
  }
  return obj;
}

std::uint32_t addSphere(Target& target, const SphereShape& s, std::uint32_t material, int segments,
                        const Vec3& reference) {
  const std::uint32_t obj = target.addObject({s.center_m, material, std::nullopt});
  const std::uint32_t q = target.addQuadric(Quadric::sphere(Vec3(0.0), s.radius_m));
  const Vec3 pole = reference;
  const Vec3 e1 = anyPerpendicular(pole);
  const Vec3 e2 = glm::cross(pole, e1);
  const int bands = std::max(2, segments / 2);
  auto point = [&](int j, int k) {
    const double theta = kPi * j / bands;
    const double phi = k * twoPiOver(segments);
    if (j == 0) return s.radius_m * pole;
    if (j == bands) return -s.radius_m * pole;
    return s.radius_m *
           (std::sin(theta) * (std::cos(phi) * e1 + std::sin(phi) * e2) + std::cos(theta) * pole);
  };
  for (int j = 0; j < bands; ++j) {
    for (int k = 0; k < segments; ++k) {
      // Away from the pole (+θ) then around (+φ) is counter-clockwise seen from outside.
      const Vec3 a = point(j, k), b = point(j + 1, k), c = point(j + 1, k + 1), d = point(j, k + 1);
      // At the poles one of the two triangles collapses (b = c at the south, a = d at the north).
      if (j + 1 < bands) target.addFacet(obj, {a, b, c}, SurfaceModel::Quadric, q);
      if (j > 0) target.addFacet(obj, {a, c, d}, SurfaceModel::Quadric, q);
    }
  }
  return obj;
}

std::uint32_t addDisk(Target& target, const DiskShape& s, std::uint32_t material, int segments,
                      const Vec3& reference) {
  const RimCircle rim{Vec3(0.0), s.normal, s.radius_m};
  const std::uint32_t obj = target.addObject({s.center_m, material, rim});
  const std::uint32_t q = target.addQuadric(Quadric::plane(Vec3(0.0), s.normal));
  const Vec3 u = perpendicularToward(s.normal, reference);
  const Vec3 v = glm::cross(s.normal, u);
  // Rings about as wide as the outer facets are long.
  const int rings = std::max(1, static_cast<int>(std::lround(segments / (2.0 * kPi))));
  auto point = [&](int j, int k) {
    const double r = s.radius_m * j / rings;
    const double phi = k * twoPiOver(segments);
    return r * (std::cos(phi) * u + std::sin(phi) * v);
  };
  for (int j = 0; j < rings; ++j) {
    const bool outer = j + 1 == rings;
    for (int k = 0; k < segments; ++k) {
      // Outward (+r) then around (+φ) is counter-clockwise seen from the normal's side; the
      // edge from corner 1 to corner 2 of the first triangle runs along the ring at j + 1.
      const Vec3 a = point(j, k), b = point(j + 1, k), c = point(j + 1, k + 1), d = point(j, k + 1);
      const std::uint8_t rim_bits = outer ? 0b010 : 0;
      target.addFacet(obj, {a, b, c}, SurfaceModel::Quadric, q, rim_bits);
      if (j > 0) target.addFacet(obj, {a, c, d}, SurfaceModel::Quadric, q);
    }
  }
  return obj;
}

MeshStats addMesh(Target& target, const Vec3& origin_m, std::uint32_t material,
                  const std::vector<Vec3>& positions, const std::vector<Vec3>& normals,
                  const std::vector<std::array<std::uint32_t, 3>>& triangles, MeshSurface surface) {
  MeshStats stats;
  stats.triangles = triangles.size();
  const std::uint32_t obj = target.addObject({origin_m, material, std::nullopt});
  for (const auto& tri : triangles) {
    std::array<Vec3, 3> p;
    std::array<Vec3, 3> n;
    bool finite = true;
    for (int i = 0; i < 3; ++i) {
      p[i] = positions.at(tri[i]);
      n[i] = normals.at(tri[i]);
      finite = finite && std::isfinite(p[i].x) && std::isfinite(p[i].y) && std::isfinite(p[i].z);
    }
    const auto face = finite ? tryNormalize(glm::cross(p[1] - p[0], p[2] - p[0])) : std::nullopt;
    if (!face) {
      ++stats.degenerate_dropped;
      continue;
    }
    for (Vec3& ni : n) {
      const auto unit = tryNormalize(ni);
      if (!unit || glm::dot(*unit, *face) <= 0.0) {
        ni = *face;
        ++stats.normals_repaired;
      } else {
        ni = *unit;
      }
    }
    ++stats.facets;
    if (surface == MeshSurface::Flat) {
      target.addFacet(obj, p, SurfaceModel::Flat, 0);
      continue;
    }
    if (surface == MeshSurface::QuadricFit) {
      const QuadricFit fit = fitQuadric(p, n);
      if (fit.status == QuadricFitStatus::Ok) {
        target.addFacet(obj, p, SurfaceModel::Quadric, target.addQuadric(*fit.quadric));
        ++stats.quadric_fits;
        continue;
      }
      ++stats.fit_fallbacks;
    }
    target.addFacet(obj, p, SurfaceModel::PN, target.addPNTriangle(PNTriangle(p, n)));
  }
  return stats;
}

}  // namespace glint
