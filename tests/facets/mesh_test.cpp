// Meshes: normals from a crease angle, and PN facets that stay closed across creases.
#include <gtest/gtest.h>

#include <cmath>

#include "facets/tessellate.h"

namespace glint {
namespace {

// Two triangles sharing the edge (0,0,0)–(0,1,0), bent by `bend_rad` about it: a roof.
TriangleMesh roof(double bend_rad, bool with_normals) {
  const double h = 0.5 * bend_rad;
  TriangleMesh m;
  // Left half slopes down to −x, right half down to +x; each face tilted by h from +z.
  m.positions_m = {{0, 0, 0}, {0, 1, 0}, {-std::cos(h), 0, -std::sin(h)},
                   {0, 0, 0}, {0, 1, 0}, {std::cos(h), 0, -std::sin(h)}};
  m.triangles = {{0, 1, 2}, {3, 5, 4}};
  const Vec3 left(-std::sin(h), 0, std::cos(h)), right(std::sin(h), 0, std::cos(h));
  m.normals = with_normals ? std::vector<Vec3>{left, left, left, right, right, right}
                           : std::vector<Vec3>(6, Vec3(0.0));
  return m;
}

TEST(MeshNormals, SmoothBelowTheCreaseAngleSharpAbove) {
  const double bend = 20.0 * kPi / 180.0;
  TriangleMesh smooth = roof(bend, false);
  EXPECT_EQ(fillNormals(smooth, 30.0 * kPi / 180.0), 6u) << "every corner lacked a normal";
  // The two faces have equal areas: on the shared edge both get the bisector, +z.
  for (int t = 0; t < 2; ++t) {
    for (int k = 0; k < 2; ++k) {
      const Vec3 n = smooth.normals[smooth.triangles[t][k == 0 ? 0 : (t == 0 ? 1 : 2)]];
      EXPECT_NEAR(n.z, 1.0, 1e-15) << "triangle " << t << " corner " << k;
    }
  }
  TriangleMesh sharp = roof(bend, false);
  fillNormals(sharp, 10.0 * kPi / 180.0);
  const Vec3 n = sharp.normals[sharp.triangles[0][0]];
  EXPECT_NEAR(n.x, -std::sin(0.5 * bend), 1e-15) << "a crease keeps the face's own normal";
  EXPECT_NEAR(n.z, std::cos(0.5 * bend), 1e-15);
}

// A flat n × n grid of unindexed triangles (every corner its own vertex, no normals), stacked
// `copies` times at the same place: the valence of an inner vertex is 6 × copies.
TriangleMesh stackedGrid(int n, int copies) {
  TriangleMesh m;
  for (int c = 0; c < copies; ++c) {
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < n; ++j) {
        const Vec3 a(i, j, 0), b(i + 1, j, 0), d(i, j + 1, 0), e(i + 1, j + 1, 0);
        for (const auto& tri : {std::array<Vec3, 3>{a, b, e}, std::array<Vec3, 3>{a, e, d}}) {
          const auto first = static_cast<std::uint32_t>(m.positions_m.size());
          m.positions_m.insert(m.positions_m.end(), tri.begin(), tri.end());
          m.triangles.push_back({first, first + 1, first + 2});
        }
      }
    }
  }
  m.normals.assign(m.positions_m.size(), Vec3(0.0));
  return m;
}

TEST(MeshNormals, CornersThatAgreeShareOneVertexAtAnyValence) {
  // 1 and 1024 stacked copies: below and far beyond the 128-face valence cap. Every corner
  // gets +z, and the mesh grows by one vertex per distinct position, not one per corner.
  for (const int copies : {1, 1024}) {
    const int n = 8;
    TriangleMesh m = stackedGrid(n, copies);
    const std::size_t before = m.positions_m.size();
    EXPECT_EQ(fillNormals(m, 30.0 * kPi / 180.0), before) << copies << " copies";
    EXPECT_EQ(m.positions_m.size() - before, static_cast<std::size_t>((n + 1) * (n + 1)))
        << copies << " copies: corners at one position with one normal share a vertex";
    for (const auto& tri : m.triangles) {
      for (std::uint32_t v : tri) {
        ASSERT_GE(v, before) << "a corner kept its normal-less vertex";
        ASSERT_EQ(m.normals[v], Vec3(0.0, 0.0, 1.0)) << copies << " copies";
      }
    }
  }
}

TEST(MeshNormals, GivenNormalsAreKept) {
  TriangleMesh m = roof(0.3, true);
  const std::vector<Vec3> before = m.normals;
  EXPECT_EQ(fillNormals(m, 0.5), 0u);
  EXPECT_EQ(m.normals, before);
}

TEST(MeshPN, BothSidesOfACreaseBuildTheSameEdge) {
  // Split normals at a 60° crease of a surface that also curves along the crease (the normals
  // lean along the edge): plain PN triangles would each bend the shared edge their own way (a
  // crack); PN-AEN gives both the same curve.
  TriangleMesh m = roof(60.0 * kPi / 180.0, true);
  const Vec3 along(0.0, 0.4, 0.0);
  for (int v : {0, 3}) m.normals[v] = glm::normalize(m.normals[v] - along);  // at (0, 0, 0)
  for (int v : {1, 4}) m.normals[v] = glm::normalize(m.normals[v] + along);  // at (0, 1, 0)
  Target t;
  t.addMaterial({});
  const MeshStats stats = addMesh(t, Vec3(0.0), 0, m, MeshSurface::PN);
  EXPECT_EQ(stats.crease_edges, 1u);
  EXPECT_EQ(stats.open_edges, 4u) << "the roof's four outer edges";
  ASSERT_EQ(t.pn_triangles.size(), 2u);
  const PNTriangle& a = t.pn_triangles[0];  // vertices 0 (0,0,0), 1 (0,1,0), 2
  const PNTriangle& b = t.pn_triangles[1];  // vertices 3 (0,0,0), 5, 4 (0,1,0)
  for (double s : {0.1, 0.25, 0.5, 0.8}) {
    const Vec3 pa = a.position({1.0 - s, s, 0.0});  // edge 0 → 1 of a
    const Vec3 pb = b.position({1.0 - s, 0.0, s});  // the same edge in b: vertex 3 → 4
    EXPECT_EQ(pa, pb) << "s = " << s << ": the two sides differ by " << glm::length(pa - pb);
  }
  // Without the neighbour's normals the edges part: the crack the remedy closes.
  const PNTriangle plain_a({m.positions_m[0], m.positions_m[1], m.positions_m[2]},
                           {m.normals[0], m.normals[1], m.normals[2]});
  const PNTriangle plain_b({m.positions_m[3], m.positions_m[5], m.positions_m[4]},
                           {m.normals[3], m.normals[5], m.normals[4]});
  EXPECT_GT(glm::length(plain_a.position({0.5, 0.5, 0.0}) - plain_b.position({0.5, 0.0, 0.5})),
            1e-3);
}

TEST(MeshPN, SmoothEdgesAreThoseOfPlainPN) {
  // Where both sides share the normals, PN-AEN is plain PN to the last bit.
  TriangleMesh m = roof(0.4, false);
  fillNormals(m, 1.0);
  Target t;
  t.addMaterial({});
  const MeshStats stats = addMesh(t, Vec3(0.0), 0, m, MeshSurface::PN);
  EXPECT_EQ(stats.crease_edges, 0u);
  const auto& tri = m.triangles[0];
  const PNTriangle plain({m.positions_m[tri[0]], m.positions_m[tri[1]], m.positions_m[tri[2]]},
                         {m.normals[tri[0]], m.normals[tri[1]], m.normals[tri[2]]});
  EXPECT_EQ(t.pn_triangles[0].controlPoints(), plain.controlPoints());
}

TEST(MeshNormals, ComputedNormalsAreExactAtVerticesOfASphere) {
  // An uneven fan of six triangles around the pole of a unit sphere, its rim at different
  // heights: Max's weights give the pole's normal +z to rounding, where area weights tilt it
  // by the fan's unevenness (a first-order error that the glint's curvature would inherit).
  TriangleMesh m;
  m.positions_m.push_back(Vec3(0, 0, 1));
  const double polar[6] = {0.1, 0.25, 0.15, 0.3, 0.12, 0.2};
  for (int k = 0; k < 6; ++k) {
    const double phi = k * kPi / 3.0 + 0.15 * std::sin(3.0 * k);  // uneven, in order
    m.positions_m.push_back(Vec3(std::sin(polar[k]) * std::cos(phi),
                                 std::sin(polar[k]) * std::sin(phi), std::cos(polar[k])));
  }
  for (std::uint32_t k = 0; k < 6; ++k) m.triangles.push_back({0, 1 + k, 1 + (k + 1) % 6});
  m.normals.assign(m.positions_m.size(), Vec3(0.0));
  fillNormals(m, 1.0);
  const Vec3 pole = m.normals[m.triangles[0][0]];
  EXPECT_NEAR(angleBetween(pole, Vec3(0, 0, 1)), 0.0, 1e-15)
      << "pole normal " << pole.x << ", " << pole.y;
}

}  // namespace
}  // namespace glint
