#include "facets/tessellate.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <type_traits>
#include <unordered_map>

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

// Vertices welded by exact position: an id per distinct position, the same for every copy of
// a vertex split at a crease. Keyed on the bits, with -0 folded into +0.
std::vector<std::uint32_t> weldByPosition(const std::vector<Vec3>& positions) {
  struct Key {
    std::array<std::uint64_t, 3> bits;
    bool operator==(const Key&) const = default;
  };
  struct Hash {
    std::size_t operator()(const Key& k) const {
      std::uint64_t h = 1469598103934665603ull;
      for (std::uint64_t b : k.bits) h = (h ^ b) * 1099511628211ull;
      return static_cast<std::size_t>(h);
    }
  };
  std::unordered_map<Key, std::uint32_t, Hash> ids;
  std::vector<std::uint32_t> weld(positions.size());
  for (std::size_t i = 0; i < positions.size(); ++i) {
    Key key{};
    for (int c = 0; c < 3; ++c) {
      const double x = positions[i][c] + 0.0;  // -0 + 0 = +0
      std::memcpy(&key.bits[c], &x, sizeof x);
    }
    weld[i] = ids.emplace(key, static_cast<std::uint32_t>(ids.size())).first->second;
  }
  return weld;
}

// The side surface about @p axis from −length/2 to +length/2, radius r0 there growing linearly
// to r1 at the far end (a cylinder: r1 = r0), as @p rings rings of @p segments quadrilaterals,
// two facets each on quadric @p q; @p reference fixes the azimuth.
void addSideSurface(Target& target, std::uint32_t obj, std::uint32_t q, const Vec3& axis,
                    const Vec3& reference, int segments, int rings, double length_m, double r0_m,
                    double r1_m) {
  const Vec3 u = perpendicularToward(axis, reference);
  const Vec3 v = glm::cross(axis, u);
  auto point = [&](int k, int j) {
    const double phi = k * twoPiOver(segments);
    const double z = -0.5 * length_m + length_m * j / rings;
    const double r = r0_m + (r1_m - r0_m) * j / rings;
    return r * (std::cos(phi) * u + std::sin(phi) * v) + z * axis;
  };
  for (int j = 0; j < rings; ++j) {
    for (int k = 0; k < segments; ++k) {
      // Around (+φ) then along (+axis) is counter-clockwise seen from outside.
      const Vec3 a = point(k, j), b = point(k + 1, j), c = point(k + 1, j + 1), d = point(k, j + 1);
      target.addFacet(obj, {a, b, c}, SurfaceModel::Quadric, q);
      target.addFacet(obj, {a, c, d}, SurfaceModel::Quadric, q);
    }
  }
}

// A unit direction turned by a unit quaternion is a unit vector to rounding, never zero; it is
// normalised again, as a scene file's is read.
Vec3 turned(const glm::dquat& turn, const Vec3& unit) { return *tryNormalize(turn * unit); }

}  // namespace

double CylinderShape::rings(int segments) const {
  return std::max(1.0, std::round(length_m / (radius_m * twoPiOver(segments))));
}

bool CylinderShape::nearOrInside(const Vec3& x_m, double margin_m) const {
  const Vec3 v = x_m - centre_m;
  const double along = glm::dot(v, axis);
  const double across = glm::length(v - along * axis);
  return std::abs(along) < 0.5 * length_m + margin_m && across < radius_m + margin_m;
}

bool SphereShape::nearOrInside(const Vec3& x_m, double margin_m) const {
  return glm::length(x_m - centre_m) < radius_m + margin_m;
}

double DiskShape::rings(int segments) { return std::max(1.0, std::round(segments / (2.0 * kPi))); }

bool DiskShape::nearOrInside(const Vec3& x_m, double margin_m) const {
  const Vec3 v = x_m - centre_m;
  const double along = glm::dot(v, normal);
  const double across = glm::length(v - along * normal);
  return std::abs(along) < margin_m && across < radius_m + margin_m;
}

double ConeShape::slantLengthM() const {
  const double dr = top_radius_m - radius_m;
  return std::sqrt(length_m * length_m + dr * dr);
}

double ConeShape::rings(int segments) const {
  return std::max(
      1.0, std::round(slantLengthM() / (std::max(radius_m, top_radius_m) * twoPiOver(segments))));
}

bool ConeShape::nearOrInside(const Vec3& x_m, double margin_m) const {
  const Vec3 v = x_m - centre_m;
  const double along = glm::dot(v, axis);
  const double across = glm::length(v - along * axis);
  return std::abs(along) < 0.5 * length_m + margin_m &&
         across < std::max(radius_m, top_radius_m) + margin_m;
}

CylinderShape CylinderShape::placed(const Vec3& centre, const glm::dquat& turn) const {
  return {centre, turned(turn, axis), radius_m, length_m};
}
SphereShape SphereShape::placed(const Vec3& centre, const glm::dquat&) const {
  return {centre, radius_m};
}
DiskShape DiskShape::placed(const Vec3& centre, const glm::dquat& turn) const {
  return {centre, turned(turn, normal), radius_m};
}
ConeShape ConeShape::placed(const Vec3& centre, const glm::dquat& turn) const {
  return {centre, turned(turn, axis), radius_m, top_radius_m, length_m};
}

std::uint32_t CylinderShape::addTo(Target& target, std::uint32_t material, int segments,
                                   const Vec3& reference) const {
  return addCylinder(target, *this, material, segments, reference);
}
std::uint32_t SphereShape::addTo(Target& target, std::uint32_t material, int segments,
                                 const Vec3& reference) const {
  return addSphere(target, *this, material, segments, reference);
}
std::uint32_t DiskShape::addTo(Target& target, std::uint32_t material, int segments,
                               const Vec3& reference) const {
  return addDisk(target, *this, material, segments, reference);
}
std::uint32_t ConeShape::addTo(Target& target, std::uint32_t material, int segments,
                               const Vec3& reference) const {
  return addCone(target, *this, material, segments, reference);
}

std::uint32_t addShape(Target& target, const AnalyticShape& shape, std::uint32_t material,
                       int segments, const Vec3& reference) {
  return std::visit([&](const auto& s) { return s.addTo(target, material, segments, reference); },
                    shape);
}

double coarseFacets(const AnalyticShape& shape, int segments) {
  return std::visit([&](const auto& s) { return s.coarseFacets(segments); }, shape);
}

bool nearOrInside(const AnalyticShape& shape, const Vec3& x_m, double margin_m) {
  return std::visit([&](const auto& s) { return s.nearOrInside(x_m, margin_m); }, shape);
}

bool isConvex(const AnalyticShape& shape) {
  return std::visit([](const auto& s) { return s.kConvex; }, shape);
}

Vec3 centreOf(const AnalyticShape& shape) {
  return std::visit([](const auto& s) { return s.centre_m; }, shape);
}

std::optional<Vec3> axisOf(const AnalyticShape& shape) {
  return std::visit([](const auto& s) { return s.orientation(); }, shape);
}

const char* axisNameOf(const AnalyticShape& shape) {
  return std::visit([](const auto& s) -> const char* { return s.kOrientationName; }, shape);
}

const char* nameOf(const AnalyticShape& shape) {
  return std::visit([](const auto& s) -> const char* { return s.kName; }, shape);
}

AnalyticShape placed(const AnalyticShape& shape, const Vec3& centre_m, const glm::dquat& turn) {
  return std::visit([&](const auto& s) -> AnalyticShape { return s.placed(centre_m, turn); },
                    shape);
}

std::uint32_t addCylinder(Target& target, const CylinderShape& s, std::uint32_t material,
                          int segments, const Vec3& reference) {
  const std::uint32_t obj =
      target.addObject({s.centre_m, material, std::nullopt, CylinderShape::kConvex});
  const std::uint32_t q = target.addQuadric(Quadric::cylinder(Vec3(0.0), s.axis, s.radius_m));
  addSideSurface(target, obj, q, s.axis, reference, segments, static_cast<int>(s.rings(segments)),
                 s.length_m, s.radius_m, s.radius_m);
  return obj;
}

std::uint32_t addCone(Target& target, const ConeShape& s, std::uint32_t material, int segments,
                      const Vec3& reference) {
  const std::uint32_t obj =
      target.addObject({s.centre_m, material, std::nullopt, ConeShape::kConvex});
  // The apex, where the radius along the axis r(z) = r₀ + (r₁ − r₀)(z + L/2)/L meets 0; the
  // quadric is |x − p|² − (1 + k²)((x − p)·a)², k = |r₁ − r₀|/L, whose gradient points away
  // from the axis on both nappes.
  const double slope = (s.top_radius_m - s.radius_m) / s.length_m;
  const Vec3 apex = (-0.5 * s.length_m - s.radius_m / slope) * s.axis;
  const std::uint32_t q = target.addQuadric(Quadric::cone(apex, s.axis, std::abs(slope)));
  addSideSurface(target, obj, q, s.axis, reference, segments, static_cast<int>(s.rings(segments)),
                 s.length_m, s.radius_m, s.top_radius_m);
  return obj;
}

std::uint32_t addSphere(Target& target, const SphereShape& s, std::uint32_t material, int segments,
                        const Vec3& reference) {
  const std::uint32_t obj =
      target.addObject({s.centre_m, material, std::nullopt, SphereShape::kConvex});
  const std::uint32_t q = target.addQuadric(Quadric::sphere(Vec3(0.0), s.radius_m));
  const Vec3 pole = reference;
  const Vec3 e1 = anyPerpendicular(pole);
  const Vec3 e2 = glm::cross(pole, e1);
  const int bands = SphereShape::bands(segments);
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
  const std::uint32_t obj = target.addObject({s.centre_m, material, rim, DiskShape::kConvex});
  const std::uint32_t q = target.addQuadric(Quadric::plane(Vec3(0.0), s.normal));
  const Vec3 u = perpendicularToward(s.normal, reference);
  const Vec3 v = glm::cross(s.normal, u);
  const int rings = static_cast<int>(DiskShape::rings(segments));
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

const char* toString(MeshSurface surface) {
  switch (surface) {
    case MeshSurface::Flat:
      return "flat";
    case MeshSurface::PN:
      return "pn";
    case MeshSurface::QuadricFit:
      return "quadric_fit";
    case MeshSurface::Nagata:
      return "nagata";
    case MeshSurface::PNVlachos:
      return "pn_published";
  }
  return "unknown";
}

std::size_t fillNormals(TriangleMesh& mesh, double crease_angle_rad) {
  const std::vector<std::uint32_t> weld = weldByPosition(mesh.positions_m);
  const std::size_t welded = weld.empty() ? 0 : *std::max_element(weld.begin(), weld.end()) + 1;
  std::vector<Vec3> unit_normal(mesh.triangles.size());
  std::vector<bool> has_normal(mesh.triangles.size(), false);
  // The faces around each welded position, as one array with offsets (compressed rows): a
  // vector per vertex would cost 24 bytes for each of millions of unused vertex copies.
  std::vector<std::uint32_t> first(welded + 1, 0);
  for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto& tri = mesh.triangles[t];
    const Vec3& a = mesh.positions_m[tri[0]];
    const auto unit =
        tryNormalize(glm::cross(mesh.positions_m[tri[1]] - a, mesh.positions_m[tri[2]] - a));
    if (!unit) continue;  // no direction to lend its neighbours
    unit_normal[t] = *unit;
    has_normal[t] = true;
    for (std::uint32_t v : tri) ++first[weld[v] + 1];
  }
  for (std::size_t w = 0; w < welded; ++w) first[w + 1] += first[w];
  // Beside each face around a position, its normal weighted by sin(corner angle) / (|e₁| |e₂|),
  // e₁ and e₂ its edges from that corner (Max, "Weights for computing vertex normals from facet
  // normals", JGT 1999): exact at vertices of a sphere, and second order on smooth surfaces,
  // where area weights are first order on uneven meshes. A glint's irradiance follows the
  // derivative of the normals, so their error reaches it one order lower.
  std::vector<std::uint32_t> faces(first[welded]);
  std::vector<Vec3> corner_weighted(first[welded]);
  {
    std::vector<std::uint32_t> next(first.begin(), first.end() - 1);
    for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t) {
      if (!has_normal[t]) continue;
      const auto& tri = mesh.triangles[t];
      for (std::size_t k = 0; k < 3; ++k) {
        const Vec3& p = mesh.positions_m[tri[k]];
        const Vec3 e1 = mesh.positions_m[tri[(k + 1) % 3]] - p;
        const Vec3 e2 = mesh.positions_m[tri[(k + 2) % 3]] - p;
        const double scale = glm::dot(e1, e1) * glm::dot(e2, e2);
        const std::uint32_t slot = next[weld[tri[k]]]++;
        faces[slot] = t;
        corner_weighted[slot] = scale > 0.0 ? glm::cross(e1, e2) / scale : Vec3(0.0);
      }
    }
  }
  // Each corner compares its face with every face around its vertex: corners × valence in all.
  // A 128-segment pole or fan is within the cap; a hostile file that puts a thousand faces at
  // every vertex of two million triangles would otherwise take minutes.
  constexpr std::uint32_t kMaxValence = 128;
  const double cos_crease = std::cos(crease_angle_rad);
  // Corners at one position given the same normal share one new vertex: on a smooth surface
  // that is every corner there, so the mesh grows by its positions, not by its corners.
  struct Key {
    std::uint32_t weld;
    std::array<std::uint64_t, 3> normal_bits;
    bool operator==(const Key&) const = default;
  };
  struct Hash {
    std::size_t operator()(const Key& k) const {
      std::uint64_t h = 1469598103934665603ull ^ k.weld;
      for (std::uint64_t b : k.normal_bits) h = (h ^ (b >> 32) ^ b) * 1099511628211ull;
      return static_cast<std::size_t>(h ^ (h >> 29));
    }
  };
  std::unordered_map<Key, std::uint32_t, Hash> shared;
  std::size_t filled = 0;
  for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t) {
    if (!has_normal[t]) continue;
    const Vec3& own = unit_normal[t];
    for (std::uint32_t& v : mesh.triangles[t]) {
      if (mesh.normals[v] != Vec3(0.0)) continue;
      const std::uint32_t w = weld[v];
      Vec3 sum = own;  // beyond the valence limit, the face's own normal
      if (first[w + 1] - first[w] <= kMaxValence) {
        sum = Vec3(0.0);
        for (std::uint32_t i = first[w]; i < first[w + 1]; ++i) {
          if (glm::dot(unit_normal[faces[i]], own) >= cos_crease) sum += corner_weighted[i];
        }
      }
      const Vec3 normal = tryNormalize(sum).value_or(own);
      Key key{w, {}};
      std::memcpy(key.normal_bits.data(), &normal, sizeof normal);
      const auto [it, added] =
          shared.emplace(key, static_cast<std::uint32_t>(mesh.positions_m.size()));
      if (added) {
        const Vec3 position = mesh.positions_m[v];
        mesh.positions_m.push_back(position);
        mesh.normals.push_back(normal);
      }
      v = it->second;
      ++filled;
    }
  }
  return filled;
}

std::optional<Vec3> usableTriangleNormal(const std::array<Vec3, 3>& corners_m) {
  for (const Vec3& p : corners_m) {
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) return std::nullopt;
  }
  return tryNormalize(glm::cross(corners_m[1] - corners_m[0], corners_m[2] - corners_m[0]));
}

std::size_t usableTriangles(const TriangleMesh& mesh) {
  std::size_t usable = 0;
  for (const auto& tri : mesh.triangles) {
    const std::array<Vec3, 3> p = {mesh.positions_m.at(tri[0]), mesh.positions_m.at(tri[1]),
                                   mesh.positions_m.at(tri[2])};
    if (usableTriangleNormal(p)) ++usable;
  }
  return usable;
}

MeshStats addMesh(Target& target, const Vec3& origin_m, std::uint32_t material,
                  const std::vector<Vec3>& positions, const std::vector<Vec3>& normals,
                  const std::vector<std::array<std::uint32_t, 3>>& triangles, MeshSurface surface) {
  return addMesh(target, origin_m, material, TriangleMesh{positions, normals, triangles}, surface);
}

MeshStats addMesh(Target& target, const Vec3& origin_m, std::uint32_t material,
                  const TriangleMesh& mesh, MeshSurface surface) {
  MeshStats stats;
  stats.triangles = mesh.triangles.size();
  const std::uint32_t obj = target.addObject({origin_m, material, std::nullopt});

  // The usable triangles with their checked unit normals.
  struct Face {
    std::array<std::uint32_t, 3> vertex;
    std::array<Vec3, 3> p, n;
  };
  std::vector<Face> faces;
  faces.reserve(mesh.triangles.size());
  for (const auto& tri : mesh.triangles) {
    Face f{tri, {}, {}};
    for (int i = 0; i < 3; ++i) {
      f.p[i] = mesh.positions_m.at(tri[i]);
      f.n[i] = mesh.normals.at(tri[i]);
    }
    const auto face = usableTriangleNormal(f.p);
    if (!face) {
      ++stats.degenerate_dropped;
      continue;
    }
    for (Vec3& ni : f.n) {
      const auto unit = tryNormalize(ni);
      if (!unit || glm::dot(*unit, *face) <= 0.0) {
        ni = *face;
        ++stats.normals_repaired;
      } else {
        ni = *unit;
      }
    }
    faces.push_back(f);
  }

  // Each directed edge (welded a → b) of a face meets its neighbour as b → a.
  const std::vector<std::uint32_t> weld = weldByPosition(mesh.positions_m);
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::vector<std::uint32_t>> edges;
  auto edgeKey = [&](const Face& f, int e) {
    return std::pair(weld[f.vertex[e]], weld[f.vertex[(e + 1) % 3]]);
  };
  for (std::uint32_t k = 0; k < faces.size(); ++k) {
    for (int e = 0; e < 3; ++e) edges[edgeKey(faces[k], e)].push_back(k);
  }
  // The neighbour's normals at edge e's vertices, or this face's own where there is no single
  // neighbour.
  auto across = [&](const Face& f, int e) -> std::array<Vec3, 2> {
    const std::array<Vec3, 2> own = {f.n[e], f.n[(e + 1) % 3]};
    const auto [a, b] = edgeKey(f, e);
    const auto back = edges.find({b, a});
    if (back == edges.end() || back->second.size() != 1 || edges.at({a, b}).size() != 1) {
      ++stats.open_edges;
      return own;
    }
    const Face& g = faces[back->second.front()];
    std::array<Vec3, 2> other = own;
    for (int i = 0; i < 3; ++i) {
      if (weld[g.vertex[i]] == a) other[0] = g.n[i];
      if (weld[g.vertex[i]] == b) other[1] = g.n[i];
    }
    if (other != own) ++stats.crease_edges;
    return other;
  };

  for (const Face& f : faces) {
    ++stats.facets;
    const std::array<std::array<Vec3, 2>, 3> neighbours = {across(f, 0), across(f, 1),
                                                           across(f, 2)};
    if (surface == MeshSurface::Flat) {
      target.addFacet(obj, f.p, SurfaceModel::Flat, 0);
      continue;
    }
    if (surface == MeshSurface::QuadricFit) {
      const QuadricFit fit = fitQuadric(f.p, f.n);
      if (fit.status == QuadricFitStatus::Ok) {
        target.addFacet(obj, f.p, SurfaceModel::Quadric, target.addQuadric(*fit.quadric));
        ++stats.quadric_fits;
        continue;
      }
      ++stats.fit_fallbacks;
    }
    const PNTriangle patch = surface == MeshSurface::Nagata
                                 ? PNTriangle::nagata(f.p, f.n, neighbours)
                             : surface == MeshSurface::PNVlachos
                                 ? PNTriangle(f.p, f.n, neighbours, PNNormalField::Vlachos)
                                 : PNTriangle(f.p, f.n, neighbours);
    target.addFacet(obj, f.p, SurfaceModel::PN, target.addPNTriangle(patch));
  }
  // Each interior edge was seen from both sides.
  stats.crease_edges /= 2;
  return stats;
}

}  // namespace glint
