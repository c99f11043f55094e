/// @file
/// @brief make_targets: writes the example target meshes capsule.glb, finned_missile.glb and
/// car_body.glb (binary glTF 2.0, through tinygltf) into a directory.
///
/// The three models are the kinds of file a glTF reader meets from real exporters: a smooth
/// surface with analytic normals (capsule); crease vertices, flat-shaded parts and one mesh
/// instanced by rotated child nodes (missile); a mesh without normals under TRS and matrix
/// node transforms (car). Conventions: metres, +Y up, counter-clockwise triangles seen from
/// outside. Each mesh is checked before it is written (closed, outward, no degenerate triangle,
/// normals on the faces' side) and each file is read back, so a broken model fails here and not
/// in a test that uses it. Nothing depends on time, addresses or evaluation order: a rerun gives
/// the same bytes (GCC and Clang builds agree too).
///
/// Usage: make_targets OUT_DIR

#include <tiny_gltf.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <limits>
#include <map>
#include <numbers>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace {

using glm::dvec2;
using glm::dvec3;
using Index = std::uint32_t;
constexpr double kPi = std::numbers::pi;

static_assert(std::endian::native == std::endian::little, "glTF buffers are little-endian");
static_assert(sizeof(glm::vec3) == 3 * sizeof(float), "vertex arrays are copied as raw floats");

/// @brief An indexed triangle mesh as it is stored: float, as glTF holds it.
struct Mesh {
  std::vector<glm::vec3> positions;
  std::vector<glm::vec3> normals;  ///< empty: written without a NORMAL attribute
  std::vector<Index> indices;

  Index vertex(const dvec3& p) {
    positions.push_back(toFloat(p));
    return Index(positions.size() - 1);
  }
  Index vertex(const dvec3& p, const dvec3& n) {
    normals.push_back(toFloat(n));
    return vertex(p);
  }
  void triangle(Index a, Index b, Index c) { indices.insert(indices.end(), {a, b, c}); }
  /// Quad a b c d, counter-clockwise seen from outside.
  void quad(Index a, Index b, Index c, Index d) {
    triangle(a, b, c);
    triangle(a, c, d);
  }
  /// Planar quad with its own four vertices carrying the face normal (a flat-shaded face).
  void flatQuad(const dvec3& a, const dvec3& b, const dvec3& c, const dvec3& d) {
    const dvec3 n = glm::normalize(glm::cross(c - a, d - b));
    const Index first = vertex(a, n);  // one call per statement: argument order is unspecified
    vertex(b, n);
    vertex(c, n);
    vertex(d, n);
    quad(first, first + 1, first + 2, first + 3);
  }
  std::size_t triangleCount() const { return indices.size() / 3; }

 private:
  // Adding +0 turns -0 into +0: points meant to coincide (poles, crease copies) then have one
  // bit pattern, and a reader that welds by exact value sees them as one point.
  static glm::vec3 toFloat(const dvec3& v) { return glm::vec3(v) + glm::vec3(0.0f); }
};

/// @brief Fails unless @p m is closed and consistently oriented outward, without degenerate
/// triangles, its normals (if any) unit and on the outer side of every face they touch.
/// Vertices are welded by exact position, so crease and flat-shading copies are one point.
/// @return the enclosed volume (m³).
double checkMesh(const Mesh& m, const std::string& name) {
  const auto fail = [&](const std::string& what) { throw std::runtime_error(name + ": " + what); };
  std::map<std::array<float, 3>, Index> ids;
  std::vector<Index> weld(m.positions.size());
  for (std::size_t i = 0; i < m.positions.size(); ++i) {
    const glm::vec3& p = m.positions[i];
    weld[i] = ids.emplace(std::array{p.x, p.y, p.z}, Index(ids.size())).first->second;
  }
  // Closed and consistently wound: each directed edge once, and its reverse once.
  std::map<std::pair<Index, Index>, int> edges;
  double volume = 0.0;
  for (std::size_t t = 0; t < m.indices.size(); t += 3) {
    const Index v[3] = {m.indices[t], m.indices[t + 1], m.indices[t + 2]};
    const dvec3 a(m.positions[v[0]]), b(m.positions[v[1]]), c(m.positions[v[2]]);
    const dvec3 face = glm::cross(b - a, c - a);
    if (0.5 * glm::length(face) < 1e-8) fail("degenerate triangle " + std::to_string(t / 3));
    volume += glm::dot(a, glm::cross(b, c)) / 6.0;
    for (int k = 0; k < 3; ++k) ++edges[{weld[v[k]], weld[v[(k + 1) % 3]]}];
    for (int k = 0; !m.normals.empty() && k < 3; ++k) {
      const dvec3 n(m.normals[v[k]]);
      if (std::abs(glm::length(n) - 1.0) > 1e-6) fail("normal not of unit length");
      if (glm::dot(n, face) <= 0.0) fail("normal 90 degrees or more off its face");
    }
  }
  for (const auto& [edge, count] : edges) {
    const auto reverse = edges.find({edge.second, edge.first});
    if (count != 1 || reverse == edges.end() || reverse->second != 1) fail("not closed");
  }
  if (!(volume > 0.0)) fail("wound inward");
  return volume;
}

// ---- Surfaces of revolution ----------------------------------------------------------------

/// @brief One point of a lathe profile: axial position a, radius r, and the outward unit
/// normal there (na along the axis, nr along the radius).
struct ProfilePoint {
  double a, r, na, nr;
};

/// @brief Unit circle at @p n equal steps from angle 0; quarter turns are exact, so seams on
/// the coordinate planes have exact zeros and the missile's fins sit on vertex lines.
std::vector<dvec2> circle(int n) {
  std::vector<dvec2> c(n);
  for (int j = 0; j < n; ++j) {
    const double phi = 2.0 * kPi * j / n;
    c[j] = {std::cos(phi), std::sin(phi)};
    if (4 * j % n == 0) c[j] = glm::round(c[j]);
  }
  return c;
}

/// @brief Adds the surface of revolution of @p profile about @p axis (through the origin),
/// @p n segments around, angle 0 along @p u; u × v must equal the axis. The profile runs with
/// the solid on its right in the (a, r) plane (its normal is (da, dr) turned counter-clockwise),
/// so that ∂/∂angle × ∂/∂profile points out, which fixes the winding below.
/// Two consecutive points at the same (a, r) make a crease: the ring is repeated with the second
/// normal and no band joins them. A point with r = 0 is a pole: one vertex if its normal is
/// along the axis, else one per segment with the normal of the segment's middle, so a pointed
/// tip is shaded like the cone it is.
void lathe(Mesh& m, const std::vector<ProfilePoint>& profile, const dvec3& axis, const dvec3& u,
           const dvec3& v, int n) {
  const std::vector<dvec2> ring = circle(n);
  std::vector<Index> prev, cur(n);
  for (std::size_t i = 0; i < profile.size(); ++i) {
    const ProfilePoint& p = profile[i];
    const bool pole = p.r == 0.0;
    for (int j = 0; j < n; ++j) {
      if (pole && p.nr == 0.0 && j > 0) {
        cur[j] = cur[0];
        continue;
      }
      const double mid = 2.0 * kPi * (j + 0.5) / n;  // a pointed tip's vertex j: segment j's middle
      const dvec2 c = pole ? dvec2(std::cos(mid), std::sin(mid)) : ring[j];
      const dvec3 radial = c.x * u + c.y * v;
      cur[j] = m.vertex(p.a * axis + p.r * radial, p.na * axis + p.nr * radial);
    }
    const bool crease = i > 0 && profile[i - 1].a == p.a && profile[i - 1].r == p.r;
    for (int j = 0; i > 0 && !crease && j < n; ++j) {
      const int k = (j + 1) % n;
      if (profile[i - 1].r == 0.0) {
        m.triangle(prev[j], cur[k], cur[j]);
      } else if (pole) {
        m.triangle(prev[j], prev[k], cur[j]);
      } else {
        m.quad(prev[j], prev[k], cur[k], cur[j]);
      }
    }
    prev = cur;
  }
}

// ---- Capsule ---------------------------------------------------------------------------------

/// Axis +Y, radius 0.3 m, cylinder 1.2 m (y = ±0.6), hemispherical ends, centred; smooth.
Mesh capsule() {
  constexpr double kR = 0.3, kHalfCylinder = 0.6;
  constexpr int kSegments = 32, kCapRings = 8, kCylinderBands = 4;
  const auto sphere = [&](double centre, double latitude) {
    const double s = std::sin(latitude), c = std::cos(latitude);
    return ProfilePoint{centre + kR * s, kR * c, s, c};
  };
  std::vector<ProfilePoint> profile{{-kHalfCylinder - kR, 0.0, -1.0, 0.0}};
  for (int k = 1; k <= kCapRings; ++k) {
    profile.push_back(sphere(-kHalfCylinder, kPi / 2 * (k - kCapRings) / kCapRings));
  }
  for (int k = 1; k < kCylinderBands; ++k) {
    const double y = std::lerp(-kHalfCylinder, kHalfCylinder, double(k) / kCylinderBands);
    profile.push_back({y, kR, 0.0, 1.0});
  }
  for (int k = 0; k < kCapRings; ++k) {
    profile.push_back(sphere(kHalfCylinder, kPi / 2 * k / kCapRings));
  }
  profile.push_back({kHalfCylinder + kR, 0.0, 1.0, 0.0});

  Mesh m;
  lathe(m, profile, {0, 1, 0}, {0, 0, 1}, {1, 0, 0}, kSegments);
  return m;
}

// ---- Finned missile --------------------------------------------------------------------------

constexpr double kBodyRadius = 0.15, kTailX = -1.2, kNoseX = 1.0, kTipX = 1.5;
constexpr int kBodySegments = 48;

/// Axis +X: flat tail disc at x = -1.2, cylinder to x = 1.0, secant-ogive nose to the tip at
/// x = 1.5. A secant ogive (arc radius 1.5 m, larger than the 0.908 m of the tangent ogive) meets
/// the cylinder at an angle of about 6.7°, so the junction is a real crease, as is the tail rim.
Mesh missileBody() {
  constexpr int kCylinderBands = 11, kNoseBands = 10;
  constexpr double kOgiveRadius = 1.5;
  std::vector<ProfilePoint> profile{{kTailX, 0.0, -1.0, 0.0}, {kTailX, kBodyRadius, -1.0, 0.0}};
  for (int k = 0; k <= kCylinderBands; ++k) {
    const double x = std::lerp(kTailX, kNoseX, double(k) / kCylinderBands);
    profile.push_back({x, kBodyRadius, 0.0, 1.0});
  }
  // Ogive arc through base B and tip T; its centre lies on the chord's bisector, inside.
  const dvec2 base(kNoseX, kBodyRadius), tip(kTipX, 0.0);
  const double chord = glm::length(tip - base);
  const dvec2 out = dvec2(base.y - tip.y, tip.x - base.x) / chord;  // chord normal, outward
  const dvec2 centre =
      0.5 * (base + tip) - std::sqrt(kOgiveRadius * kOgiveRadius - chord * chord / 4) * out;
  const double from = std::atan2(base.y - centre.y, base.x - centre.x);
  const double to = std::atan2(tip.y - centre.y, tip.x - centre.x);
  for (int k = 0; k <= kNoseBands; ++k) {
    const double angle = std::lerp(from, to, double(k) / kNoseBands);
    const dvec2 n(std::cos(angle), std::sin(angle));
    // The ends are set exactly: the base must weld with the cylinder's last ring, the tip is r = 0.
    const dvec2 p = k == 0 ? base : k == kNoseBands ? tip : centre + kOgiveRadius * n;
    profile.push_back({p.x, p.y, n.x, n.y});
  }
  Mesh m;
  lathe(m, profile, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, kBodySegments);
  return m;
}

/// The fin of the 0° node: a trapezoid in the plane z = 0 reaching out along +Y, as a slab
/// 0.01 m thick whose six faces each have their own vertices and flat normal. The root sits
/// where the faceted body's surface is at the slab's faces (a fraction of a millimetre below the
/// true radius), so no slit shows between fin and body.
Mesh fin() {
  constexpr double kHalfThickness = 0.005, kSpan = 0.25;
  const double root = kBodyRadius - kHalfThickness * std::tan(kPi / kBodySegments);
  const double tip = kBodyRadius + kSpan;
  // Outline counter-clockwise seen from +Z: root trailing, root leading, tip leading, tip trailing.
  const dvec2 outline[4] = {{kTailX, root}, {-0.8, root}, {-0.95, tip}, {-1.15, tip}};
  const auto at = [&](int i, double z) { return dvec3(outline[i % 4], z); };
  const double h = kHalfThickness;
  Mesh m;
  m.flatQuad(at(0, h), at(1, h), at(2, h), at(3, h));
  m.flatQuad(at(3, -h), at(2, -h), at(1, -h), at(0, -h));
  for (int i = 0; i < 4; ++i) m.flatQuad(at(i, -h), at(i + 1, -h), at(i + 1, h), at(i, h));
  return m;
}

// ---- Car body --------------------------------------------------------------------------------

/// Value at @p x of the polyline through @p knots (ascending x), held constant outside them.
double polyline(const std::vector<dvec2>& knots, double x) {
  if (x <= knots.front().x) return knots.front().y;
  for (std::size_t i = 1; i < knots.size(); ++i) {
    if (x <= knots[i].x) {
      return std::lerp(knots[i - 1].y, knots[i].y,
                       (x - knots[i - 1].x) / (knots[i].x - knots[i - 1].x));
    }
  }
  return knots.back().y;
}

// World frame: front at +X, x in [-2.1, 2.1], z in [-0.9, 0.9], y in [0.15, 1.55]. The mesh is
// stored shifted by -kCarShift along x and its node's matrix moves it back.
constexpr double kCarHalfLength = 2.1, kCarHalfWidth = 0.9, kCarBottom = 0.15;
constexpr double kCarCorner = 0.12;    // radius of the hull's long edges
constexpr double kCarEndRound = 0.15;  // radius of the edges round the front and rear faces
constexpr double kCarShift = 0.1;
// Hull top (belt line): level trunk and cabin base, bonnet sloping down to the front.
const std::vector<dvec2> kHullTop{{0.75, 0.95}, {2.1, 0.80}};
// Cabin height over the belt line: rear window, roof, windscreen.
const std::vector<dvec2> kCabin{{-1.6, 0.0}, {-1.05, 0.6}, {-0.05, 0.6}, {0.75, 0.0}};

/// Closed cross-section at @p x, counter-clockwise about +X (top towards +Z). A rounded
/// rectangle whose flat top carries the greenhouse; every section has the same points, the
/// greenhouse being flat where the cabin height is 0. @p inset shrinks it to round the ends.
std::vector<dvec3> carSection(double x, double inset) {
  constexpr int kArc = 4;  // segments per rounded edge
  // Points across the flat top, as fractions of its half-width, and the share of the cabin
  // height each gets: shoulder, greenhouse side leaning in (tumblehome), crowned roof.
  constexpr double kTopAt[] = {-0.85, -0.68, -0.34, 0.0, 0.34, 0.68, 0.85};
  constexpr double kTopShare[] = {0.0, 0.92, 0.98, 1.0, 0.98, 0.92, 0.0};
  const double w = kCarHalfWidth - inset - kCarCorner;  // half-width of the flat top and bottom
  const double bottom = kCarBottom + inset + kCarCorner, top = polyline(kHullTop, x) - inset;
  const double cabin = polyline(kCabin, x);
  std::vector<dvec3> s;
  // Arc round the centre (zc, yc) from angle a0 to a1, both ends included.
  const auto arc = [&](double zc, double yc, double a0, double a1) {
    for (int k = 0; k <= kArc; ++k) {
      const double a = std::lerp(a0, a1, double(k) / kArc);
      s.emplace_back(x, yc + kCarCorner * std::sin(a), zc + kCarCorner * std::cos(a));
    }
  };
  arc(-w, top - kCarCorner, kPi, kPi / 2);
  for (int i = 0; i < 7; ++i) s.emplace_back(x, top + cabin * kTopShare[i], w * kTopAt[i]);
  arc(w, top - kCarCorner, kPi / 2, 0.0);
  arc(w, bottom, 0.0, -kPi / 2);
  arc(-w, bottom, -kPi / 2, -kPi);
  return s;
}

/// Lofts cross-sections from the rear (x = -2.1) to the front (x = 2.1) and closes both ends
/// with flat faces. Over the last 0.15 m at each end the inset follows a quarter circle, which
/// gives the front and rear faces rounded edges.
Mesh carBody() {
  struct Station {
    double x, inset;
  };
  constexpr int kEndSteps = 4;
  constexpr double kMaxStep = 0.25;  // station spacing in the middle (m)
  const double flatEnd = kCarHalfLength - kCarEndRound;
  std::vector<Station> stations;
  for (int k = kEndSteps; k > 0; --k) {
    const double a = kPi / 2 * k / kEndSteps;
    stations.push_back({-(flatEnd + kCarEndRound * std::sin(a)), kCarEndRound * (1 - std::cos(a))});
  }
  // Knots where the shape has kinks; stations are filled in between.
  const double knots[] = {-flatEnd, -1.6, -1.05, -0.05, 0.75, flatEnd};
  for (std::size_t i = 0; i + 1 < std::size(knots); ++i) {
    const int steps = int(std::ceil((knots[i + 1] - knots[i]) / kMaxStep));
    for (int k = 0; k < steps; ++k) {
      stations.push_back({std::lerp(knots[i], knots[i + 1], double(k) / steps), 0.0});
    }
  }
  stations.push_back({flatEnd, 0.0});
  for (int k = 1; k <= kEndSteps; ++k) {
    const double a = kPi / 2 * k / kEndSteps;
    stations.push_back({flatEnd + kCarEndRound * std::sin(a), kCarEndRound * (1 - std::cos(a))});
  }

  Mesh m;
  const dvec3 shift(kCarShift, 0.0, 0.0);
  std::vector<Index> prev;
  for (std::size_t i = 0; i < stations.size(); ++i) {
    const std::vector<dvec3> section = carSection(stations[i].x, stations[i].inset);
    const int n = int(section.size());
    std::vector<Index> cur;
    for (const dvec3& p : section) cur.push_back(m.vertex(p - shift));
    for (int j = 0; i > 0 && j < n; ++j) {
      m.quad(prev[j], prev[(j + 1) % n], cur[(j + 1) % n], cur[j]);
    }
    // End faces: a fan from the section's middle (every end section is convex).
    if (i == 0 || i + 1 == stations.size()) {
      dvec3 middle(0.0);
      for (const dvec3& p : section) middle += p / double(n);
      const Index c = m.vertex(middle - shift);
      for (int j = 0; j < n; ++j) {
        const Index a = cur[j], b = cur[(j + 1) % n];
        if (i == 0) {
          m.triangle(c, b, a);
        } else {
          m.triangle(c, a, b);
        }
      }
    }
    prev = std::move(cur);
  }
  return m;
}

// ---- glTF output -----------------------------------------------------------------------------

/// @brief Collects meshes and nodes into one tinygltf model with a single buffer, and writes it.
class GltfBuilder {
 public:
  GltfBuilder() {
    model_.asset.version = "2.0";
    model_.asset.generator = "glint make_targets";
    model_.buffers.resize(1);
  }

  int addMesh(const Mesh& mesh, const std::string& name) {
    tinygltf::Primitive primitive;
    primitive.mode = TINYGLTF_MODE_TRIANGLES;
    const int position = addAccessor(mesh.positions, TINYGLTF_TARGET_ARRAY_BUFFER,
                                     TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3);
    tinygltf::Accessor& bounds = model_.accessors[position];
    bounds.minValues.assign(3, std::numeric_limits<double>::infinity());
    bounds.maxValues.assign(3, -std::numeric_limits<double>::infinity());
    for (const glm::vec3& p : mesh.positions) {
      for (int k = 0; k < 3; ++k) {
        bounds.minValues[k] = std::min(bounds.minValues[k], double(p[k]));
        bounds.maxValues[k] = std::max(bounds.maxValues[k], double(p[k]));
      }
    }
    primitive.attributes["POSITION"] = position;
    if (!mesh.normals.empty()) {
      primitive.attributes["NORMAL"] =
          addAccessor(mesh.normals, TINYGLTF_TARGET_ARRAY_BUFFER, TINYGLTF_COMPONENT_TYPE_FLOAT,
                      TINYGLTF_TYPE_VEC3);
    }
    // 16-bit indices when they fit; glTF forbids the type's maximum (a restart value) as an index.
    if (mesh.positions.size() < 0xFFFF) {
      const std::vector<std::uint16_t> small(mesh.indices.begin(), mesh.indices.end());
      primitive.indices = addAccessor(small, TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER,
                                      TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT, TINYGLTF_TYPE_SCALAR);
    } else {
      primitive.indices = addAccessor(mesh.indices, TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER,
                                      TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT, TINYGLTF_TYPE_SCALAR);
    }
    tinygltf::Mesh m;
    m.name = name;
    m.primitives.push_back(std::move(primitive));
    model_.meshes.push_back(std::move(m));
    return int(model_.meshes.size() - 1);
  }

  int addNode(tinygltf::Node node) {
    model_.nodes.push_back(std::move(node));
    return int(model_.nodes.size() - 1);
  }
  tinygltf::Node& node(int i) { return model_.nodes[i]; }

  /// Writes the scene rooted at @p root as .glb and reads it back; throws on any error.
  void write(const std::filesystem::path& path, int root) {
    model_.scenes.resize(1);
    model_.scenes[0].nodes = {root};
    model_.defaultScene = 0;
    tinygltf::TinyGLTF io;
    // The stream variant, because the file variant does not report a failed write.
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    io.WriteGltfSceneToStream(&model_, out, false, true);
    out.close();
    if (!out) throw std::runtime_error("cannot write " + path.string());

    tinygltf::Model back;
    std::string err, warn;
    if (!io.LoadBinaryFromFile(&back, &err, &warn, path.string()) || !err.empty() ||
        !warn.empty()) {
      throw std::runtime_error(path.string() + " does not read back: " + err + warn);
    }
  }

 private:
  template <class T>
  int addAccessor(const std::vector<T>& data, int target, int componentType, int type) {
    std::vector<unsigned char>& bytes = model_.buffers[0].data;
    bytes.resize((bytes.size() + 3) / 4 * 4);  // every view starts 4-byte aligned
    tinygltf::BufferView view;
    view.buffer = 0;
    view.byteOffset = bytes.size();
    view.byteLength = data.size() * sizeof(T);
    view.target = target;
    bytes.resize(bytes.size() + view.byteLength);
    std::memcpy(bytes.data() + view.byteOffset, data.data(), view.byteLength);
    model_.bufferViews.push_back(view);

    tinygltf::Accessor accessor;
    accessor.bufferView = int(model_.bufferViews.size() - 1);
    accessor.componentType = componentType;
    accessor.type = type;
    accessor.count = data.size();
    model_.accessors.push_back(std::move(accessor));
    return int(model_.accessors.size() - 1);
  }

  tinygltf::Model model_;
};

tinygltf::Node meshNode(const std::string& name, int mesh) {
  tinygltf::Node node;
  node.name = name;
  node.mesh = mesh;
  return node;
}

void report(const std::string& name, const Mesh& m) {
  std::printf("  %-13s %5zu triangles %5zu vertices  volume %.6f m^3\n", name.c_str(),
              m.triangleCount(), m.positions.size(), checkMesh(m, name));
}

void writeCapsule(const std::filesystem::path& path) {
  const Mesh m = capsule();
  report("capsule", m);
  GltfBuilder gltf;
  gltf.write(path, gltf.addNode(meshNode("capsule", gltf.addMesh(m, "capsule"))));
}

void writeMissile(const std::filesystem::path& path) {
  const Mesh body = missileBody(), fins = fin();
  report("missile_body", body);
  report("fin", fins);
  GltfBuilder gltf;
  const int root = gltf.addNode(meshNode("missile", gltf.addMesh(body, "missile_body")));
  const int finMesh = gltf.addMesh(fins, "fin");
  // Quarter turns about +X as quaternions (x, y, z, w) = (sin(θ/2), 0, 0, cos(θ/2)).
  const double h = std::numbers::sqrt2 / 2;
  const std::vector<double> turns[] = {{0, 0, 0, 1}, {h, 0, 0, h}, {1, 0, 0, 0}, {h, 0, 0, -h}};
  for (int k = 0; k < 4; ++k) {
    tinygltf::Node node = meshNode("fin_" + std::to_string(90 * k), finMesh);
    node.rotation = turns[k];
    const int child = gltf.addNode(std::move(node));
    gltf.node(root).children.push_back(child);
  }
  gltf.write(path, root);
}

void writeCar(const std::filesystem::path& path) {
  const Mesh m = carBody();
  report("car_body", m);
  GltfBuilder gltf;
  tinygltf::Node root;
  root.name = "car";
  root.translation = {0, 0, 0};
  root.scale = {1, 1, 1};
  const int rootIndex = gltf.addNode(std::move(root));
  tinygltf::Node body = meshNode("car_body", gltf.addMesh(m, "car_body"));
  body.matrix = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, kCarShift, 0, 0, 1};  // column-major
  const int child = gltf.addNode(std::move(body));
  gltf.node(rootIndex).children.push_back(child);
  gltf.write(path, rootIndex);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s OUT_DIR\n", argv[0]);
    return 2;
  }
  try {
    const std::filesystem::path dir = argv[1];
    std::filesystem::create_directories(dir);
    writeCapsule(dir / "capsule.glb");
    writeMissile(dir / "finned_missile.glb");
    writeCar(dir / "car_body.glb");
  } catch (const std::exception& e) {
    std::fprintf(stderr, "make_targets: %s\n", e.what());
    return 1;
  }
  return 0;
}
