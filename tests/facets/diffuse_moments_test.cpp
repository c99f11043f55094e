// A coarse facet's diffuse light from its moments (facets/detail/diffuse_moments.h) against the
// same integral summed point by point over the exact surface.
#include "facets/detail/diffuse_moments.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "facets/patch.h"
#include "facets/tessellate.h"
#include "facets/triangle_rule.h"

namespace glint::detail {
namespace {

// ∫ ρd E cos θi cos θr / (π d²) dA over the whole facet: 64 pieces, a degree-11 rule on each.
double bruteForce(const Target& t, const SurfaceMap& map, const Beam& beam, double rho_d,
                  const Vec3& observer_m) {
  std::vector<SubFacet> pieces{coarseSubFacet(t, map.facet())};
  for (int level = 0; level < 3; ++level) {
    std::vector<SubFacet> next;
    for (const SubFacet& f : pieces) {
      for (const SubFacet& c : map.split(f)) next.push_back(c);
    }
    pieces = std::move(next);
  }
  const double area_uv = 0.5 / static_cast<double>(pieces.size());
  double sum = 0.0;
  for (const SubFacet& f : pieces) {
    const std::array<Vec3, 3>& c = f.bary;
    for (const TriangleNode& node : conicalProductRule(6)) {
      const SurfacePoint p =
          map.at(node.bary[0] * c[0] + node.bary[1] * c[1] + node.bary[2] * c[2]);
      const Beam::Sample b = beam.at(p.position_m);
      const Vec3 to = observer_m - p.position_m;
      const double d = glm::length(to);
      const double cos_i = glm::dot(p.normal, b.toward_laser);
      const double cos_r = glm::dot(p.normal, to) / d;
      sum += area_uv * node.weight * p.jacobian_m2 * rho_d / kPi * b.irradiance_w_m2 *
             std::max(cos_i, 0.0) * std::max(cos_r, 0.0) / (d * d);
    }
  }
  return sum;
}

// The target of both tests: a 0.3 m sphere of 16 segments, its facets about 0.1 m across.
Target sphere() {
  Target t;
  t.addMaterial({});
  addSphere(t, {Vec3(0.0), 0.3}, 0, 16, Vec3(0.0, -1.0, 0.0));
  return t;
}

// Every lit facet of a sphere under a Gaussian beam, seen from 3 to 300 facet radii along
// several directions: the moments' estimate stays within the error it reports, and that error
// falls as the cube of radius / distance (a first-order expansion alone would miss by the
// square: the test fails if the second-order term is dropped).
TEST(DiffuseMoments, AFacetsGlowFromItsMomentsIsWithinItsReportedErrorAtEveryDistance) {
  const Target t = sphere();
  Beam beam;
  beam.origin_m = Vec3(0.1, 0.0, 20.0);
  beam.direction = glm::normalize(Vec3(-0.02, 0.0, -1.0));
  beam.power_w = 1000.0;
  beam.profile = BeamProfile::Gaussian;
  beam.radius_m = 0.4;
  beam.divergence_rad = 0.01;  // ωi varies over a facet
  Material material{0.0, 0.3, Beckmann{0.1}};
  int usable = 0, compared = 0;
  double worst_share = 0.0;  // of the reported error, by the true one
  double worst_far = 0.0;    // the reported error at 300 radii, relative
  for (std::uint32_t k = 0; k < t.facetCount(); ++k) {
    const SurfaceMap map(t, k);
    const PatchGeometry g = map.geometry(t, coarseSubFacet(t, k));
    std::int64_t evaluations = 0;
    const DiffuseMoments m = diffuseMoments(map, g, beam, material, evaluations);
    if (!m.usable) continue;
    ++usable;
    EXPECT_EQ(evaluations, 4 * 25 + 4 * 16) << "facet " << k;
    for (const Vec3& dir : {Vec3(0, 0, 1), glm::normalize(Vec3(1, 0, 1)),
                            glm::normalize(Vec3(-1, 2, 2)), glm::normalize(g.normal)}) {
      for (const double radii : {3.0, 10.0, 30.0, 300.0}) {
        const Vec3 observer = g.centre_m + radii * g.radius_m * dir;
        const std::optional<DiffuseEstimate> e = diffuseFromMoments(m, g, observer);
        if (!e) continue;  // some normal of the facet faces away from this observer
        ++compared;
        const double truth = bruteForce(t, map, beam, material.diffuse_reflectance, observer);
        const double miss = std::abs(e->irradiance_w_m2 - truth);
        EXPECT_LE(miss, e->error_w_m2)
            << "facet " << k << " at " << radii << " radii: estimate " << e->irradiance_w_m2
            << ", truth " << truth << ", reported error " << e->error_w_m2;
        worst_share = std::max(worst_share, miss / e->error_w_m2);
        // The remainder bound is (24 / 6) R³ G / (D − R)⁵: relative to the glow G cos θ / D²,
        // about 4 (R / D)³ / cos θ, 1.5e-7 / cos θ at 300 radii (where the second-order term
        // alone is ~3 (R / D)², 3e-5), plus the moments' quadrature error.
        if (radii >= 300.0) {
          worst_far = std::max(worst_far, e->error_w_m2 / e->irradiance_w_m2);
          EXPECT_LT(e->error_w_m2, 2e-6 * e->irradiance_w_m2)
              << "facet " << k << " at " << radii << " radii";
        }
      }
    }
  }
  EXPECT_GT(usable, 4) << "the beam lights several facets whole";
  EXPECT_GT(compared, 40);
  std::cout << "[ moments ] " << usable << " facets, " << compared
            << " observers: the largest miss is " << worst_share
            << " of the reported error; at 300 radii the error is at most " << worst_far
            << " of the glow\n";
}

TEST(DiffuseMoments, AFacetCutByTheTerminatorOrSeenPastItsHorizonHasNone) {
  const Target t = sphere();
  Beam beam;
  beam.origin_m = Vec3(0.0, 0.0, 20.0);
  beam.direction = Vec3(0.0, 0.0, -1.0);
  beam.radius_m = 2.0;  // a flat top over the whole sphere: the terminator is its equator
  Material material{0.0, 0.3, Beckmann{0.1}};
  int cut = 0, whole = 0;
  for (std::uint32_t k = 0; k < t.facetCount(); ++k) {
    const SurfaceMap map(t, k);
    const PatchGeometry g = map.geometry(t, coarseSubFacet(t, k));
    std::int64_t evaluations = 0;
    const DiffuseMoments m = diffuseMoments(map, g, beam, material, evaluations);
    // A facet whose normals reach the equator is cut by the terminator (or dark): none.
    const bool reaches_equator =
        std::abs(g.normal.z) <= std::sin(g.cone_rad) + 1e-12 || g.normal.z < 0.0;
    if (reaches_equator) {
      EXPECT_FALSE(m.usable) << "facet " << k << " normal z " << g.normal.z;
      ++cut;
      continue;
    }
    if (!m.usable) continue;
    ++whole;
    // Seen from below its own horizon: no estimate.
    const Vec3 behind = g.centre_m - 10.0 * g.radius_m * g.normal;
    EXPECT_FALSE(diffuseFromMoments(m, g, behind).has_value()) << "facet " << k;
    // Too near: no estimate.
    const Vec3 near = g.centre_m + 1.5 * g.radius_m * g.normal;
    EXPECT_FALSE(diffuseFromMoments(m, g, near).has_value()) << "facet " << k;
  }
  EXPECT_GT(cut, 0);
  EXPECT_GT(whole, 0);
}

}  // namespace
}  // namespace glint::detail
