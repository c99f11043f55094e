#include "facets/surface_map.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "facets/detail/surface_cache.h"
#include "facets/tessellate.h"
#include "facets/triangle_rule.h"

namespace glint {
namespace {

// ∫_T u^a v^b du dv over the unit triangle = a! b! / (a + b + 2)!.
double monomialIntegral(int a, int b) {
  return std::tgamma(a + 1.0) * std::tgamma(b + 1.0) / std::tgamma(a + b + 3.0);
}

TEST(TriangleRule, ConicalProductIsExactToDegreeTwoNMinusOne) {
  for (int n = 1; n <= 6; ++n) {
    const auto rule = conicalProductRule(n);
    ASSERT_EQ(rule.size(), static_cast<std::size_t>(n * n));
    double weights = 0.0;
    for (const TriangleNode& node : rule) {
      EXPECT_GT(node.weight, 0.0) << "n " << n;
      for (int k = 0; k < 3; ++k) EXPECT_GT(node.bary[k], 0.0) << "n " << n;
      weights += node.weight;
    }
    EXPECT_NEAR(weights, 1.0, 1e-14) << "n " << n;
    // Exact to degree 2n − 1; degree 2n is where it must first fail (for some monomial).
    double worst_beyond = 0.0;
    for (int degree = 0; degree <= 2 * n; ++degree) {
      for (int a = 0; a <= degree; ++a) {
        const int b = degree - a;
        double q = 0.0;
        for (const TriangleNode& node : rule) {
          q += 0.5 * node.weight * std::pow(node.bary[1], a) * std::pow(node.bary[2], b);
        }
        const double exact = monomialIntegral(a, b);
        if (degree < 2 * n) {
          EXPECT_NEAR(q, exact, 1e-14 * exact + 1e-16) << "n " << n << " u^" << a << " v^" << b;
        } else {
          worst_beyond = std::max(worst_beyond, std::abs(q - exact) / exact);
        }
      }
    }
    EXPECT_GT(worst_beyond, 1e-12) << "n " << n << " is exact beyond degree 2n-1";
  }
}

// The pieces that `level` 1→4 splits of `pieces` make, placed by the map.
std::vector<SubFacet> splitTimes(const SurfaceMap& map, std::vector<SubFacet> pieces, int level) {
  for (int k = 0; k < level; ++k) {
    std::vector<SubFacet> next;
    for (const SubFacet& f : pieces) {
      for (const SubFacet& c : map.split(f)) next.push_back(c);
    }
    pieces = std::move(next);
  }
  return pieces;
}

// ∫ dA over the piece `f` by the n × n conical product rule in the map's parameters; `visit`
// sees the surface at each node.
template <class Visit>
double ruleArea(const SurfaceMap& map, const SubFacet& f, int n, Visit&& visit) {
  const Vec3 e1 = f.bary[1] - f.bary[0], e2 = f.bary[2] - f.bary[0];
  const double area_uv = 0.5 * std::abs(e1[1] * e2[2] - e1[2] * e2[1]);
  double area = 0.0;
  for (const TriangleNode& node : conicalProductRule(n)) {
    const SurfacePoint p =
        map.at(node.bary[0] * f.bary[0] + node.bary[1] * f.bary[1] + node.bary[2] * f.bary[2]);
    visit(p);
    area += area_uv * node.weight * p.jacobian_m2;
  }
  return area;
}

// The area of every facet of a shape, by the rule over its surface map on the pieces of
// `level` 1→4 splits, summed.
double mappedArea(const Target& t, int n, int level) {
  double area = 0.0;
  for (std::uint32_t i = 0; i < t.facetCount(); ++i) {
    const SurfaceMap map(t, i);
    const SubFacet whole =
        map.subFacet({Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)}, 0, t.rim_edges[i]);
    for (const SubFacet& f : splitTimes(map, {whole}, level)) {
      area += ruleArea(map, f, n,
                       [&](const SurfacePoint& p) { EXPECT_TRUE(p.valid) << "facet " << i; });
    }
  }
  return area;
}

TEST(SurfaceMap, CoarseFacetsTileTheExactSurfaceArea) {
  const Vec3 ref(0.0, -1.0, 0.0);
  Target cyl, sphere, disk;
  for (Target* t : {&cyl, &sphere, &disk}) t->addMaterial({});
  addCylinder(cyl, {Vec3(0.3, -0.2, 1.0), glm::normalize(Vec3(1, 2, 3)), 0.5, 2.0}, 0, 16, ref);
  addSphere(sphere, {Vec3(3, 0, 0), 0.7}, 0, 16, ref);
  addDisk(disk, {Vec3(-3, 0, 0), glm::normalize(Vec3(0, 1, 1)), 0.5}, 0, 16, ref);
  // Gaps or overlaps between facets would show at any resolution; the rule's own error falls
  // from ~1e-7 (one 8 × 8 rule per facet: the disk's rim blend is not a polynomial near the
  // corner opposite the rim) to ~1e-10 on 64 pieces.
  EXPECT_NEAR(mappedArea(cyl, 8, 0), 2.0 * kPi * 0.5 * 2.0, 1e-10) << "cylinder side";
  EXPECT_NEAR(mappedArea(sphere, 8, 1), 4.0 * kPi * 0.49, 1e-10) << "sphere";
  EXPECT_NEAR(mappedArea(disk, 8, 0), kPi * 0.25, 1e-6) << "disk, one rule per facet";
  EXPECT_NEAR(mappedArea(disk, 8, 3), kPi * 0.25, 1e-9) << "disk, 64 pieces per facet";
}

// The bounds the lobe and cubature schemes trust must hold the map's pieces as the map places
// them. A disk's rim blend bends the inner edges of its rim facets' pieces too (a 1→4 split's
// are straight): each piece's area, measured by the rule on 16 sub-pieces, must stay below its
// area bound, and its points inside its ball. The rule's error is 4e-9 of the area (measured
// on the coarse facets, whose bound is their exact area); unbent, the bounds were low by 4 %.
TEST(SurfaceMap, PieceBoundsHoldTheRimFacetsPiecesAsTheMapPlacesThem) {
  const Vec3 ref(0.0, -1.0, 0.0);
  struct Case {
    DiskShape disk;
    int segments;
  };
  // 16 segments: three rings, rim facets with a corner inside; 7: a fan, every facet on the
  // rim with its opposite corner at the centre, arcs of 51°.
  for (const Case& c : {Case{{Vec3(0.0), Vec3(0.0, 0.0, 1.0), 0.05}, 16},
                        Case{{Vec3(1, 2, 3), glm::normalize(Vec3(1, -2, 2)), 0.5}, 7}}) {
    Target t;
    t.addMaterial({});
    addDisk(t, c.disk, 0, c.segments, ref);
    double worst_area = 0.0, worst_ball = 0.0;  // largest ratios of truth to bound
    int rim_facets = 0;
    for (std::uint32_t i = 0; i < t.facetCount(); ++i) {
      if (t.rim_edges[i] == 0) continue;
      ++rim_facets;
      const SurfaceMap map(t, i);
      std::vector<SubFacet> pieces{map.subFacet(coarseSubFacet(t, i).bary, 0, t.rim_edges[i])};
      for (std::size_t k = 0; k < pieces.size(); ++k) {
        const SubFacet f = pieces[k];
        const PatchGeometry g = map.geometry(t, f);
        double area = 0.0;
        for (const SubFacet& s : splitTimes(map, {f}, 2)) {
          area += ruleArea(map, s, 8, [&](const SurfacePoint& p) {
            ASSERT_TRUE(p.valid) << "facet " << i;
            worst_ball = std::max(worst_ball, glm::length(p.position_m - g.centre_m) / g.radius_m);
          });
        }
        worst_area = std::max(worst_area, area / g.area_bound_m2);
        EXPECT_LE(area, g.area_bound_m2 * (1.0 + 1e-7))
            << "facet " << i << " depth " << int(f.depth) << ": bound low by "
            << area / g.area_bound_m2 - 1.0;
        if (f.depth < 5) {
          for (const SubFacet& child : map.split(f)) pieces.push_back(child);
        }
      }
    }
    EXPECT_EQ(rim_facets, c.segments);
    EXPECT_LE(worst_ball, 1.0) << c.segments << " segments";
    // Bounds that hold by a wide margin everywhere would not see a piece lost: the largest
    // piece must come within a few per cent.
    EXPECT_GT(worst_area, 0.9) << c.segments << " segments";
  }
}

TEST(SurfaceMap, PointsLieOnTheQuadricWithItsGradientNormal) {
  Target t;
  t.addMaterial({});
  addSphere(t, {Vec3(0.1, 0.2, 0.3), 0.7}, 0, 8, Vec3(0.0, -1.0, 0.0));
  for (std::uint32_t i = 0; i < t.facetCount(); ++i) {
    const SurfaceMap map(t, i);
    for (const TriangleNode& node : conicalProductRule(3)) {
      const SurfacePoint p = map.at(node.bary);
      ASSERT_TRUE(p.valid);
      const Vec3 rel = p.position_m - Vec3(0.1, 0.2, 0.3) + t.objects[0].origin_m;
      EXPECT_NEAR(glm::length(rel), 0.7, 1e-12) << "facet " << i;
      EXPECT_NEAR(glm::dot(p.normal, glm::normalize(rel)), 1.0, 1e-12) << "facet " << i;
    }
  }
}

// The memo must be invisible: bit for bit what the map and patchGeometry() compute, asked once
// or again, and never an answer kept from another target.
TEST(SurfaceCache, ReturnsBitForBitWhatItMemoisesAndForgetsOnAnotherTarget) {
  Target cyl, sphere;
  for (Target* t : {&cyl, &sphere}) t->addMaterial({});
  addCylinder(cyl, {Vec3(0.0), Vec3(0.0, 0.0, 1.0), 0.5, 2.0}, 0, 16, Vec3(0.0, -1.0, 0.0));
  addSphere(sphere, {Vec3(0.0), 0.7}, 0, 16, Vec3(0.0, -1.0, 0.0));
  detail::SurfaceCache cache;
  auto same_point = [](const SurfacePoint& a, const SurfacePoint& b) {
    return a.valid == b.valid && a.position_m == b.position_m && a.normal == b.normal &&
           a.jacobian_m2 == b.jacobian_m2;
  };
  cache.bind(1);
  for (int pass = 0; pass < 2; ++pass) {  // the second pass is answered from the memo
    for (std::uint32_t i = 0; i < cyl.facetCount(); i += 7) {
      const SurfaceMap map(cyl, i);
      std::vector<SubFacet> pieces{
          map.subFacet(coarseSubFacet(cyl, i).bary, 0, coarseSubFacet(cyl, i).rim_edges)};
      for (std::size_t k = 0; k < pieces.size(); ++k) {
        const SubFacet f = pieces[k];
        const PatchGeometry want = map.geometry(cyl, f);
        const PatchGeometry got = cache.geometry(cyl, map, f);
        EXPECT_TRUE(got.centre_m == want.centre_m && got.radius_m == want.radius_m &&
                    got.cone_rad == want.cone_rad && got.area_bound_m2 == want.area_bound_m2 &&
                    got.normal == want.normal)
            << "facet " << i << " depth " << int(f.depth) << " pass " << pass;
        if (f.depth == 4) continue;
        const auto want_children = map.split(f);
        const auto children = cache.split(map, f);
        for (int c = 0; c < 4; ++c) {
          for (int j = 0; j < 3; ++j) {
            EXPECT_EQ(children[c].corner_m[j], want_children[c].corner_m[j])
                << "facet " << i << " depth " << int(f.depth) << " child " << c;
            EXPECT_TRUE(
                same_point(cache.at(map, children[c].bary[j]), map.at(children[c].bary[j])));
          }
          pieces.push_back(children[c]);
        }
      }
    }
  }
  // A point off the dyadic lattice is computed, not memoised under a neighbour's key.
  const SurfaceMap cyl0(cyl, 0), sphere0(sphere, 0);
  const Vec3 third(1.0 / 3.0);
  EXPECT_TRUE(same_point(cache.at(cyl0, third), cyl0.at(third)));
  // Bound to another target, the same facet index and node give that target's surface.
  const Vec3 node(0.5, 0.25, 0.25);
  EXPECT_TRUE(same_point(cache.at(cyl0, node), cyl0.at(node)));
  cache.bind(2);
  EXPECT_TRUE(same_point(cache.at(sphere0, node), sphere0.at(node)))
      << "a point of the cylinder was returned for the sphere";
  EXPECT_FALSE(same_point(cyl0.at(node), sphere0.at(node))) << "the test needs distinct surfaces";
}

}  // namespace
}  // namespace glint
