#pragma once
// Triangle meshes of shapes whose surface is known exactly, with their exact vertex normals:
// what a CAD exporter writes for a sphere, an open cylinder, an ellipsoid or a torus. The mesh
// convergence tests and bench/surface_convergence.cpp measure glint's mesh surfaces on them.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <random>
#include <utility>
#include <vector>

#include "facets/beam.h"
#include "facets/tessellate.h"

namespace glint::test {

// The icosahedron split 1→4 `level` times, every vertex pushed onto the unit sphere: 20·4^level
// triangles, counter-clockwise from outside, normals exact (the positions).
inline TriangleMesh unitIcosphere(int level) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Vec3> v = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                         {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  for (Vec3& p : v) p = glm::normalize(p);
  std::vector<std::array<std::uint32_t, 3>> f = {
      {0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
      {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
      {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (int l = 0; l < level; ++l) {
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> midpoint;
    auto mid = [&](std::uint32_t a, std::uint32_t b) {
      const auto key = std::minmax(a, b);
      if (const auto it = midpoint.find(key); it != midpoint.end()) return it->second;
      v.push_back(glm::normalize(v[a] + v[b]));
      return midpoint[key] = static_cast<std::uint32_t>(v.size() - 1);
    };
    std::vector<std::array<std::uint32_t, 3>> finer;
    finer.reserve(4 * f.size());
    for (const auto& tri : f) {
      const std::uint32_t a = mid(tri[0], tri[1]), b = mid(tri[1], tri[2]), c = mid(tri[2], tri[0]);
      finer.push_back({tri[0], a, c});
      finer.push_back({tri[1], b, a});
      finer.push_back({tri[2], c, b});
      finer.push_back({a, b, c});
    }
    f = std::move(finer);
  }
  TriangleMesh mesh;
  mesh.positions_m = v;
  mesh.normals = v;
  mesh.triangles = std::move(f);
  return mesh;
}

// The ellipsoid x²/a² + y²/b² + z²/c² = 1 as the icosphere stretched along the axes, its normals
// exact: ∝ (x/a², y/b², z/c²).
inline TriangleMesh ellipsoid(int level, const Vec3& semi_axes_m) {
  TriangleMesh mesh = unitIcosphere(level);
  for (std::size_t i = 0; i < mesh.positions_m.size(); ++i) {
    const Vec3 p = mesh.positions_m[i] * semi_axes_m;
    mesh.positions_m[i] = p;
    mesh.normals[i] = glm::normalize(p / (semi_axes_m * semi_axes_m));
  }
  return mesh;
}

// The exact ellipsoid of ellipsoid(level, semi_axes_m) as one object of `target`: its facets
// carry the quadric x²/a² + y²/b² + z²/c² = 1, as glint's analytic shapes do, so refinement
// converges to the true surface (the reference for meshes of it). Returns the object index.
inline std::uint32_t addExactEllipsoid(Target& target, int level, const Vec3& semi_axes_m,
                                       std::uint32_t material) {
  const Vec3 inv2 = 1.0 / (semi_axes_m * semi_axes_m);
  const std::uint32_t obj = target.addObject({Vec3(0.0), material, std::nullopt, true});
  const std::uint32_t q = target.addQuadric(
      Quadric(glm::dmat3(inv2.x, 0, 0, 0, inv2.y, 0, 0, 0, inv2.z), Vec3(0.0), -1.0));
  const TriangleMesh mesh = ellipsoid(level, semi_axes_m);
  for (const auto& tri : mesh.triangles) {
    target.addFacet(obj,
                    {mesh.positions_m[tri[0]], mesh.positions_m[tri[1]], mesh.positions_m[tri[2]]},
                    SurfaceModel::Quadric, q);
  }
  return obj;
}

// The open side of a cylinder about z through the origin, `segments` around and rings about as
// long as they are wide, normals exact (radial).
inline TriangleMesh openCylinder(int segments, double radius_m, double length_m) {
  const int rings =
      std::max(1, static_cast<int>(std::lround(length_m * segments / (2.0 * kPi * radius_m))));
  TriangleMesh mesh;
  for (int j = 0; j <= rings; ++j) {
    for (int k = 0; k < segments; ++k) {
      const double phi = 2.0 * kPi * k / segments;
      const Vec3 radial(std::cos(phi), std::sin(phi), 0.0);
      mesh.positions_m.push_back(radius_m * radial +
                                 Vec3(0, 0, length_m * (j / double(rings) - 0.5)));
      mesh.normals.push_back(radial);
    }
  }
  auto at = [&](int k, int j) { return static_cast<std::uint32_t>(j * segments + k % segments); };
  for (int j = 0; j < rings; ++j) {
    for (int k = 0; k < segments; ++k) {
      mesh.triangles.push_back({at(k, j), at(k + 1, j), at(k + 1, j + 1)});
      mesh.triangles.push_back({at(k, j), at(k + 1, j + 1), at(k, j + 1)});
    }
  }
  return mesh;
}

// A flat disk about z through the origin as a fan of `segments` triangles around its centre and
// rings about as wide as the rim's edges are long (as glint tessellates its analytic disk),
// normals +z: its outline is the inscribed polygon, short of the circle by (2π/N)²/6 of its
// area.
inline TriangleMesh flatDisk(int segments, double radius_m) {
  const int rings = std::max(1, static_cast<int>(std::lround(segments / (2.0 * kPi))));
  TriangleMesh mesh;
  mesh.positions_m.push_back(Vec3(0.0));
  for (int j = 1; j <= rings; ++j) {
    for (int k = 0; k < segments; ++k) {
      const double phi = 2.0 * kPi * k / segments, r = radius_m * j / rings;
      mesh.positions_m.push_back(Vec3(r * std::cos(phi), r * std::sin(phi), 0.0));
    }
  }
  mesh.normals.assign(mesh.positions_m.size(), Vec3(0.0, 0.0, 1.0));
  auto at = [&](int j, int k) {  // ring j ≥ 1, k around
    return static_cast<std::uint32_t>(1 + (j - 1) * segments + k % segments);
  };
  for (int k = 0; k < segments; ++k) mesh.triangles.push_back({0, at(1, k), at(1, k + 1)});
  for (int j = 1; j < rings; ++j) {
    for (int k = 0; k < segments; ++k) {
      mesh.triangles.push_back({at(j, k), at(j + 1, k), at(j + 1, k + 1)});
      mesh.triangles.push_back({at(j, k), at(j + 1, k + 1), at(j, k + 1)});
    }
  }
  return mesh;
}

// A torus about z: ring radius `major_m`, tube radius `minor_m`, `segments` around the ring and
// segments·minor/major around the tube (facets about square), normals exact.
inline TriangleMesh torus(int segments, double major_m, double minor_m) {
  const int tube = std::max(3, static_cast<int>(std::lround(segments * minor_m / major_m)));
  TriangleMesh mesh;
  for (int j = 0; j < tube; ++j) {
    const double theta = 2.0 * kPi * j / tube;
    for (int k = 0; k < segments; ++k) {
      const double phi = 2.0 * kPi * k / segments;
      const Vec3 radial(std::cos(phi), std::sin(phi), 0.0);
      const Vec3 normal = std::cos(theta) * radial + Vec3(0, 0, std::sin(theta));
      mesh.positions_m.push_back(major_m * radial + minor_m * normal);
      mesh.normals.push_back(normal);
    }
  }
  auto at = [&](int k, int j) {
    return static_cast<std::uint32_t>((j % tube) * segments + k % segments);
  };
  for (int j = 0; j < tube; ++j) {
    for (int k = 0; k < segments; ++k) {
      mesh.triangles.push_back({at(k, j), at(k + 1, j), at(k + 1, j + 1)});
      mesh.triangles.push_back({at(k, j), at(k + 1, j + 1), at(k, j + 1)});
    }
  }
  return mesh;
}

// The mesh's mean edge length (m): the h of its convergence order.
inline double meanEdgeLength(const TriangleMesh& mesh) {
  double sum = 0.0;
  for (const auto& tri : mesh.triangles) {
    for (int e = 0; e < 3; ++e) {
      sum += glm::length(mesh.positions_m[tri[e]] - mesh.positions_m[tri[(e + 1) % 3]]);
    }
  }
  return sum / (3.0 * static_cast<double>(mesh.triangles.size()));
}

// `count` observers where random lit vertices of `surface` send their specular reflection,
// turned by a normal deviate of 1.5 σ per axis (on the lobe's flank as well as its top), at a
// log-uniform distance in [near_m, far_m]; only directions within acos(min_cos) of the way
// back to the laser (−1: any). Seeded: the same observers every call.
inline std::vector<Vec3> glintObservers(const TriangleMesh& surface, const Beam& beam, double sigma,
                                        double near_m, double far_m, int count,
                                        double min_cos = -1.0) {
  std::mt19937_64 rng(11);
  std::uniform_int_distribution<std::size_t> vertex(0, surface.positions_m.size() - 1);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> turn(0.0, 1.5 * sigma);
  std::vector<Vec3> out;
  const Vec3 wi = -beam.direction;
  while (static_cast<int>(out.size()) < count) {
    const std::size_t v = vertex(rng);
    const Vec3 p = surface.positions_m[v], n = surface.normals[v];
    if (glm::dot(n, wi) < 0.1 || beam.at(p).irradiance_w_m2 < 0.1 * beam.peakIrradiance()) continue;
    Vec3 wo = 2.0 * glm::dot(n, wi) * n - wi;
    const Vec3 e1 = anyPerpendicular(wo), e2 = glm::cross(wo, e1);
    wo = glm::normalize(wo + turn(rng) * e1 + turn(rng) * e2);
    if (glm::dot(wo, n) < 0.05 || glm::dot(wo, wi) < min_cos) continue;
    out.push_back(p + near_m * std::pow(far_m / near_m, unit(rng)) * wo);
  }
  return out;
}

// Every vertex normal turned by `angle_rad` toward a pseudo-random tangent direction (seeded by
// `seed`, the same for every call): what an estimate of the normals accurate to that angle does.
inline void perturbNormals(TriangleMesh& mesh, double angle_rad, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> turn(0.0, 2.0 * kPi);
  for (Vec3& n : mesh.normals) {
    const Vec3 e1 = anyPerpendicular(n);
    const Vec3 e2 = glm::cross(n, e1);
    const double psi = turn(rng);
    n = glm::normalize(std::cos(angle_rad) * n +
                       std::sin(angle_rad) * (std::cos(psi) * e1 + std::sin(psi) * e2));
  }
}

}  // namespace glint::test
