#include "facets/reflection.h"

#include <gtest/gtest.h>

#include <functional>
#include <random>

#include "facets/surface_map.h"
#include "facets/tessellate.h"
#include "support/scenes.h"

namespace glint {
namespace {

void forEachDescendant(const Target& t, const SubFacet& f, int levels,
                       const std::function<void(const SubFacet&)>& visit) {
  if (levels == 0) {
    visit(f);
    return;
  }
  for (const SubFacet& c : split(t, f)) forEachDescendant(t, c, levels - 1, visit);
}

// A target with every surface model: quadric cylinder, sphere and disk, and a PN-triangle
// sphere built from exact vertex normals.
Target mixedTarget(const Vec3& toward_laser) {
  Target t;
  t.addMaterial(test::mirror(0.9, 0.02, 0.05));
  addCylinder(t, {Vec3(0, 0, 0), Vec3(0, 0, 1), 0.5, 1.5}, 0, 12, toward_laser);
  addSphere(t, {Vec3(0, 2, 0), 0.4}, 0, 12, toward_laser);
  addDisk(t, {Vec3(0, -2, 0), glm::normalize(Vec3(-1, 0, 0.3)), 0.5}, 0, 12, toward_laser);
  // PN sphere: the UV sphere's vertices with their exact normals.
  Target uv;
  uv.addMaterial({});
  addSphere(uv, {Vec3(0), 0.4}, 0, 8, toward_laser);
  std::vector<Vec3> pos, nrm;
  std::vector<std::array<std::uint32_t, 3>> tris;
  for (const auto& c : uv.corners_m) {
    std::array<std::uint32_t, 3> tri;
    for (int k = 0; k < 3; ++k) {
      tri[k] = static_cast<std::uint32_t>(pos.size());
      pos.push_back(c[k]);
      nrm.push_back(glm::normalize(c[k]));
    }
    tris.push_back(tri);
  }
  addMesh(t, Vec3(0, 0, 2), 0, pos, nrm, tris, MeshSurface::PN);
  return t;
}

// A cylinder's vertices with their exact normals as a mesh of the surface model @p surface
// (each facet's fitted quadric, or its PN triangle).
void addCylinderMesh(Target& t, const Vec3& origin_m, MeshSurface surface,
                     const Vec3& toward_laser) {
  Target shape;
  shape.addMaterial({});
  addCylinder(shape, {Vec3(0), Vec3(0, 0, 1), 0.4, 1.0}, 0, 12, toward_laser);
  std::vector<Vec3> pos, nrm;
  std::vector<std::array<std::uint32_t, 3>> tris;
  for (std::uint32_t i = 0; i < shape.facetCount(); ++i) {
    if (shape.model[i] != SurfaceModel::Quadric) continue;
    const Quadric& q = shape.quadrics[shape.model_index[i]];
    if (q.gradientLipschitz() == 0.0) continue;  // the caps
    std::array<std::uint32_t, 3> tri;
    for (int k = 0; k < 3; ++k) {
      tri[k] = static_cast<std::uint32_t>(pos.size());
      pos.push_back(shape.corners_m[i][k]);
      nrm.push_back(glm::normalize(q.gradient(shape.corners_m[i][k])));
    }
    tris.push_back(tri);
  }
  addMesh(t, origin_m, 0, pos, nrm, tris, surface);
}

// The lobe's bound (minHalfVectorAngle) against the lobe itself, sampled densely over pieces of
// every surface model. Observers are drawn both all round and near the mirror direction of a
// random point of the piece, turned about the band's axis too, so that the lobe peaks on, just
// beside and along the piece: where the band, not the cone, makes the bound.
TEST(MinHalfVectorAngle, NeverExceedsTheAngleOfAnyNormalOfThePiece) {
  const Beam beam = test::flatTop(Vec3(0), Vec3(1, 0.2, -0.1), 50.0, 5.0);
  Target t = mixedTarget(-beam.direction);
  addCylinderMesh(t, Vec3(2, 0, 0), MeshSurface::QuadricFit, -beam.direction);
  addCylinderMesh(t, Vec3(2, 2, 0), MeshSurface::PN, -beam.direction);
  const Beckmann lobe{0.01};
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  constexpr int kGrid = 16;  // 153 samples a piece, its corners and edges included
  std::size_t checked = 0, band_tighter = 0, fitted = 0, pn = 0;
  for (std::uint32_t i = 0; i < t.facetCount(); i += 2) {
    const Beam local = beam.relativeTo(t.objects[t.object[i]].origin_m);
    const SurfaceMap map(t, i);
    for (int depth = 0; depth <= 5; ++depth) {
      SubFacet f = coarseSubFacet(t, i);
      for (int d = 0; d < depth; ++d) f = map.split(f)[static_cast<std::size_t>(rng() % 4)];
      const PatchGeometry g = map.geometry(t, f);
      if (!(g.area_m2 > 0.0)) continue;
      PatchGeometry cone_only = g;
      cone_only.band = {};
      std::vector<SurfacePoint> samples;
      for (int a = 0; a <= kGrid; ++a) {
        for (int b = 0; a + b <= kGrid; ++b) {
          const double wa = double(a) / kGrid, wb = double(b) / kGrid;
          const SurfacePoint p =
              map.at((1.0 - wa - wb) * f.bary[0] + wa * f.bary[1] + wb * f.bary[2]);
          if (p.valid) samples.push_back(p);
        }
      }
      for (int trial = 0; trial < 6; ++trial) {
        Vec3 obs;
        const double dist = g.radius_m + std::pow(10.0, -1.5 + 3.0 * (u(rng) + 1.0) / 2.0);
        if (trial < 2 || samples.empty()) {
          obs = g.centre_m + dist * glm::normalize(Vec3(u(rng), u(rng), u(rng)));
        } else {
          // The mirror direction of a sample's normal tilted by up to a few cone widths, half
          // the time about the band's axis only.
          const SurfacePoint& p = samples[rng() % samples.size()];
          const Vec3 axis = g.band.axis != Vec3(0.0) && trial % 2 == 0
                                ? g.band.axis
                                : glm::normalize(Vec3(u(rng), u(rng), u(rng)));
          const Vec3 across = tryNormalize(axis - glm::dot(axis, p.normal) * p.normal)
                                  .value_or(anyPerpendicular(p.normal));
          const Vec3 n = glm::normalize(p.normal + 2.0 * u(rng) * (g.cone_rad + 0.05) * across);
          const Vec3 wi = local.at(p.position_m).toward_laser;
          obs = p.position_m + dist * glm::normalize(2.0 * glm::dot(n, wi) * n - wi);
        }
        const double bound_rad = minHalfVectorAngle(g, obs, local);
        if (bound_rad > minHalfVectorAngle(cone_only, obs, local) + 1e-6) ++band_tighter;
        const double xi_bound =
            lobe.maxXiBeyond(bound_rad < 0.5 * kPi ? std::pow(std::tan(bound_rad), 2)
                                                   : std::numeric_limits<double>::infinity());
        for (const SurfacePoint& p : samples) {
          const Vec3 to_obs = obs - p.position_m;
          const Vec3 h = local.at(p.position_m).toward_laser + glm::normalize(to_obs);
          ++checked;
          fitted += t.model[i] == SurfaceModel::Quadric && t.object[i] == 4 ? 1 : 0;
          pn += t.model[i] == SurfaceModel::PN ? 1 : 0;
          ASSERT_GE(angleBetween(p.normal, h), bound_rad - 1e-12)
              << "facet " << i << " depth " << depth << " observer " << obs.x << "," << obs.y << ","
              << obs.z;
          ASSERT_LE(lobe.xi(p.normal, h), xi_bound * (1.0 + 1e-9) + 1e-300)
              << "facet " << i << " depth " << depth;
        }
      }
    }
  }
  EXPECT_GT(checked, 100000u) << "the property was exercised";
  EXPECT_GT(fitted, 10000u) << "fitted quadric pieces were sampled";
  EXPECT_GT(pn, 10000u) << "PN pieces were sampled";
  EXPECT_GT(band_tighter, 100u) << "cases where the band, not the cone, made the bound";
}

TEST(ContributionBound, CylinderPieceAlongItsAxisIsBoundByItsBandNotItsCone) {
  // A coarse facet of a cylinder facing the laser, and a far observer whose half vector
  // at the facet's centre is its normal turned along the axis by α = 2σ. Every normal of the
  // facet is normal to the axis, so θN ≥ α less the half vector's turn over the facet (here
  // 1e-4); the cone (about 0.26 rad wide) allows θN = 0 and the lobe's peak.
  constexpr double kSigma = 0.02, kAlpha = 2.0 * kSigma;
  Target t;
  t.addMaterial(test::mirror(1.0, kSigma));
  const Beam beam = test::flatTop(Vec3(0), Vec3(1, 0, 0), 10.0, 5.0);
  addCylinder(t, {Vec3(0), Vec3(0, 0, 1), 0.5, 1.0}, 0, 12, -beam.direction);
  std::uint32_t facing = 0;
  double best = -1.0;
  for (std::uint32_t i = 0; i < t.facetCount(); ++i) {
    const PatchGeometry g = patchGeometry(t, coarseSubFacet(t, i), NormalModel::Surface);
    if (t.quadrics[t.model_index[i]].gradientLipschitz() > 0.0 &&
        -glm::dot(g.normal, beam.direction) > best) {
      best = -glm::dot(g.normal, beam.direction);
      facing = i;
    }
  }
  const PatchGeometry g = patchGeometry(t, coarseSubFacet(t, facing), NormalModel::Surface);
  ASSERT_GT(g.cone_rad, 3.0 * kAlpha) << "a cone wide against the tilt";
  const Vec3 wi = -beam.direction;
  const Vec3 h = std::cos(kAlpha) * g.normal + std::sin(kAlpha) * Vec3(0, 0, 1);
  const Vec3 obs = g.centre_m + 1e4 * (2.0 * glm::dot(h, wi) * h - wi);
  PatchGeometry cone_only = g;
  cone_only.band = {};
  EXPECT_EQ(minHalfVectorAngle(cone_only, obs, beam), 0.0) << "the cone allows the peak";
  const double theta = minHalfVectorAngle(g, obs, beam);
  EXPECT_NEAR(theta, kAlpha, 1e-4) << "the band bounds θN by the tilt along the axis";
  // The specular bound falls with the lobe, Ξ(α)/Ξ(0) = exp(−tan²α/2σ²)(1 + tan²α)², 0.1356:
  // to within what the 1e-4 turn changes it (0.3 %).
  const ContributionBound with_band =
      contributionBound(g, obs, beam, t.materials[0], ResolutionLimits{});
  const ContributionBound with_cone =
      contributionBound(cone_only, obs, beam, t.materials[0], ResolutionLimits{});
  const double tan2 = std::pow(std::tan(kAlpha), 2);
  const double expected = std::exp(-tan2 / (2.0 * kSigma * kSigma)) * (1.0 + tan2) * (1.0 + tan2);
  EXPECT_NEAR(with_band.specular_w_m2 / with_cone.specular_w_m2, expected, 0.01 * expected)
      << "band " << with_band.specular_w_m2 << " W/m², cone " << with_cone.specular_w_m2;
}

TEST(ContributionBound, BoundsThePointwiseIntegrandOfEveryDescendant) {
  const Beam beam = test::flatTop(Vec3(0), Vec3(1, 0.2, -0.1), 50.0, 5.0);
  const Target t = mixedTarget(-beam.direction);
  const Material& m = t.materials[0];
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::size_t checked = 0;
  for (std::uint32_t i = 0; i < t.facetCount(); i += 3) {
    const Beam local = beam.relativeTo(t.objects[t.object[i]].origin_m);
    for (int depth = 0; depth <= 2; ++depth) {
      SubFacet f = coarseSubFacet(t, i);
      for (int d = 0; d < depth; ++d) f = split(t, f)[static_cast<std::size_t>(rng() % 4)];
      const PatchGeometry g = patchGeometry(t, f, NormalModel::Surface);
      for (int trial = 0; trial < 4; ++trial) {
        // Observers from 2 cm to 20 m away, all around.
        const Vec3 dir = glm::normalize(Vec3(u(rng), u(rng), u(rng)));
        const double dist = g.radius_m + std::pow(10.0, -1.7 + 3.0 * (u(rng) + 1.0) / 2.0);
        const Vec3 obs = g.centre_m + dist * dir;
        const ContributionBound b = contributionBound(g, obs, local, m, ResolutionLimits{});
        const bool faces = mayFaceObserver(g, obs);
        const bool lit = lightVerdict(g, local) == LightVerdict::MayBeLit;
        forEachDescendant(t, f, 3, [&](const SubFacet& leaf) {
          const PatchGeometry lg = patchGeometry(t, leaf, NormalModel::Surface);
          const double e = facetIrradiance(lg, obs, local, m);
          if (e == 0.0) return;
          ++checked;
          // The integrand at the leaf's centre times the whole patch's area bound may not
          // exceed the patch bound, and a patch ruled out may not contribute at all.
          ASSERT_LE(e / lg.area_m2 * g.area_bound_m2, b.upper_w_m2 * (1 + 1e-9))
              << "facet " << i << " depth " << depth << " observer at " << dist << " m";
          ASSERT_TRUE(faces) << "facet " << i << " was said to face away";
          ASSERT_TRUE(lit) << "facet " << i << " was said to be unlit";
        });
      }
    }
  }
  EXPECT_GT(checked, 1000u) << "the property was exercised";
}

TEST(PatchGeometry, BallConeAndAreaBoundHoldForEveryDescendant) {
  const Target t = mixedTarget(glm::normalize(Vec3(-1, -0.2, 0.1)));
  std::size_t checked = 0;
  for (std::uint32_t i = 0; i < t.facetCount(); ++i) {
    for (NormalModel normals : {NormalModel::Surface, NormalModel::Flat}) {
      SubFacet f = coarseSubFacet(t, i);
      for (int depth = 0; depth <= 2; ++depth) {
        const PatchGeometry g = patchGeometry(t, f, normals);
        double area = 0.0;
        forEachDescendant(t, f, 4, [&](const SubFacet& leaf) {
          const PatchGeometry lg = patchGeometry(t, leaf, normals);
          area += lg.area_m2;
          ++checked;
          for (const Vec3& p : {lg.centre_m, lg.corner_m[0], lg.corner_m[1], lg.corner_m[2]}) {
            ASSERT_LE(glm::length(p - g.centre_m), g.radius_m * (1 + 1e-12)) << "facet " << i;
          }
          for (const Vec3& n :
               {lg.normal, lg.corner_normal[0], lg.corner_normal[1], lg.corner_normal[2]}) {
            ASSERT_LE(angleBetween(n, g.normal), g.cone_rad + 1e-12)
                << "facet " << i << " normals " << static_cast<int>(normals) << " depth " << depth;
          }
        });
        EXPECT_LE(area, g.area_bound_m2 * (1 + 1e-12)) << "facet " << i << " depth " << depth;
        f = split(t, f)[static_cast<std::size_t>(depth) % 4];
      }
    }
  }
  EXPECT_GT(checked, 10000u);
}

TEST(ClipTriangle, KeepsWhereBothLinearFunctionsArePositive) {
  // Reference by sampling the triangle on a fine barycentric grid.
  auto reference = [](const std::array<double, 3>& a, const std::array<double, 3>& b) {
    const int n = 600;
    double inside = 0.0, total = 0.0;
    Vec3 centroid(0.0);
    for (int i = 0; i < n; ++i) {
      for (int j = 0; i + j < n; ++j) {
        const Vec3 w(1.0 - (i + j + 2.0 / 3.0) / n, (i + 1.0 / 3.0) / n, (j + 1.0 / 3.0) / n);
        total += 1.0;
        if (glm::dot(w, Vec3(a[0], a[1], a[2])) > 0.0 &&
            glm::dot(w, Vec3(b[0], b[1], b[2])) > 0.0) {
          inside += 1.0;
          centroid += w;
        }
      }
    }
    return ClippedTriangle{inside / total, inside > 0 ? centroid / inside : Vec3(1.0 / 3.0)};
  };
  const std::vector<std::pair<std::array<double, 3>, std::array<double, 3>>> cases = {
      {{1, 1, 1}, {1, 2, 3}},
      {{1, -1, -1}, {1, 1, 1}},
      {{1, 1, -1}, {1, -1, 1}},
      {{-0.2, 0.5, 0.9}, {0.7, 0.3, -0.4}},
      {{-1, -1, -1}, {1, 1, 1}}};
  for (const auto& [a, b] : cases) {
    const ClippedTriangle got = clipTriangle(a, b);
    const ClippedTriangle ref = reference(a, b);
    // The grid reference is exact to O(1/n) near the cut lines.
    EXPECT_NEAR(got.fraction, ref.fraction, 5e-3) << a[0] << "," << a[1] << "," << a[2];
    if (ref.fraction > 0.0) {
      EXPECT_NEAR(glm::length(got.centroid_bary - ref.centroid_bary), 0.0, 5e-3) << a[0];
    }
  }
  // Exact cases: a corner quarter, and nothing.
  const ClippedTriangle corner = clipTriangle({1, -1, -1}, {1, 1, 1});
  EXPECT_NEAR(corner.fraction, 0.25, 1e-15);
  EXPECT_NEAR(glm::length(corner.centroid_bary - Vec3(2.0 / 3, 1.0 / 6, 1.0 / 6)), 0.0, 1e-15);
  EXPECT_EQ(clipTriangle({-1, -1, -1}, {1, 1, 1}).fraction, 0.0);
}

TEST(ContributionBound, IsTightOnceTheLobeIsResolved) {
  // A small flat patch at the glint of a far observer: the bound may only exceed the value by
  // what the lobe can change over the patch (a few σ), not by orders of magnitude.
  Target t;
  t.addMaterial(test::mirror(1.0, 0.05));
  addDisk(t, {Vec3(0), Vec3(0, 0, 1), 0.01}, 0, 8, Vec3(1, 0, 0));
  const Beam beam = test::flatTop(Vec3(0), Vec3(0, 0, -1), 10.0, 1.0);
  const Vec3 obs(0.0, 0.0, 100.0);
  for (std::uint32_t i = 0; i < t.facetCount(); ++i) {
    const PatchGeometry g = patchGeometry(t, coarseSubFacet(t, i), NormalModel::Surface);
    const ContributionBound b = contributionBound(g, obs, beam, t.materials[0], ResolutionLimits{});
    const double e = facetIrradiance(g, obs, beam, t.materials[0]);
    EXPECT_TRUE(b.resolved()) << "facet " << i;
    EXPECT_LT(b.upper_w_m2, 1.01 * e) << "facet " << i;
  }
}

}  // namespace
}  // namespace glint
