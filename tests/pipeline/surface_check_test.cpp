// The meshes' surface check (pipeline/setup/surface_check.h): what it compares, and that on meshes
// of a sphere its figure is at least the mesh's true error and falls with the tessellation.
#include "pipeline/setup/surface_check.h"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>

#include "pipeline/setup/target_builder.h"
#include "support/test_meshes.h"

namespace glint {
namespace {

// A unit sphere as an icosphere mesh (or analytic) in a Gaussian beam, σ = 0.01.
Scene sphereScene(int level, bool analytic) {
  Scene scene;
  scene.source = "in memory";
  scene.laser.direction = glm::normalize(Vec3(1.0, 0.2, -0.1));
  scene.laser.origin_m = Vec3(0.0, 0.05, 0.03) - 100.0 * scene.laser.direction;
  scene.laser.power_w = 1000.0;
  scene.laser.profile = BeamProfile::Gaussian;
  scene.laser.radius_m = 0.5;
  scene.materials.push_back({0.95, 0.0, Beckmann{0.01}});
  scene.material_names.push_back("polished");
  ObjectSpec o;
  if (analytic) {
    o.shape = AnalyticShape(SphereShape{Vec3(0.0), 1.0});
  } else {
    MeshSpec mesh;
    mesh.mesh = std::make_shared<const TriangleMesh>(test::unitIcosphere(level));
    o.shape = std::move(mesh);
  }
  scene.objects.push_back(o);
  scene.accuracy.tolerance = 1e-5;  // the integration's error far below the surfaces'
  scene.accuracy.floor_w_m2 = 1e-9 * scene.laser.peakIrradiance();  // as the scene file's
  return scene;
}

TEST(SurfaceCheck, ComparesEachSurfaceWithAnotherBuiltFromTheSameVertices) {
  using S = std::vector<MeshSurface>;
  EXPECT_EQ(alternativeSurfaces(MeshSurface::PN),
            (S{MeshSurface::QuadricFit, MeshSurface::Nagata}));
  EXPECT_EQ(alternativeSurfaces(MeshSurface::Nagata),
            (S{MeshSurface::PN, MeshSurface::QuadricFit}));
  EXPECT_EQ(alternativeSurfaces(MeshSurface::QuadricFit),
            (S{MeshSurface::PN, MeshSurface::Nagata}));
  EXPECT_EQ(alternativeSurfaces(MeshSurface::Flat), S{MeshSurface::PN});
}

TEST(SurfaceCheck, SaysWhyItWasNotMade) {
  const Scene analytic = sphereScene(0, true);
  const FacetIntegrator a(buildTarget(analytic), analytic.laser, analytic.accuracy);
  EXPECT_EQ(checkSurfaceModel(analytic, a, {{"anywhere", Vec3(5, 0, 0)}}).skipped, "no mesh");
  const Scene mesh = sphereScene(2, false);
  const FacetIntegrator m(buildTarget(mesh), mesh.laser, mesh.accuracy);
  // Behind the sphere, in its shadow: no observer sees the target.
  const SurfaceModelCheck dark = checkSurfaceModel(mesh, m, {{"behind", Vec3(5, 1, -0.5)}});
  EXPECT_EQ(dark.skipped, "no observer of the run sees the target");
  EXPECT_TRUE(dark.probes.empty());
}

TEST(SurfaceCheck, IsAtLeastTheMeshErrorOnASphereAndFallsWithTheTessellation) {
  // Observers in the glint's own directions. The default surface (PN) is the most accurate of
  // the three on a sphere, so the change to the others is mostly their own error: at least
  // PN's, and falling with the edge length as all do.
  const Scene analytic = sphereScene(0, true);
  const FacetIntegrator exact(buildTarget(analytic), analytic.laser, analytic.accuracy);
  const std::vector<Vec3> observers =
      test::glintObservers(test::unitIcosphere(4), analytic.laser, 0.01, 2.0, 45.0, 6);
  std::vector<std::pair<std::string, Vec3>> probes;
  for (std::size_t i = 0; i < observers.size(); ++i)
    probes.emplace_back("observer " + std::to_string(i), observers[i]);
  IntegratorWorkspace ws;
  double previous = std::numeric_limits<double>::infinity();
  for (const int level : {2, 3, 4}) {
    const Scene scene = sphereScene(level, false);
    const FacetIntegrator mesh(buildTarget(scene), scene.laser, scene.accuracy);
    const SurfaceModelCheck check = checkSurfaceModel(scene, mesh, probes);
    ASSERT_TRUE(check.skipped.empty()) << check.skipped;
    ASSERT_EQ(check.probes.size(), probes.size()) << "every observer sees the glint";
    double worst_error = 0.0;
    for (const SurfaceProbe& p : check.probes) {
      const double truth = exact.adaptive(p.at_m, ws).irradiance_w_m2;
      worst_error = std::max(worst_error, std::abs(p.irradiance_w_m2 / truth - 1.0));
    }
    EXPECT_GE(check.max_relative_change, worst_error)
        << "level " << level << ": the check must not under-state the mesh's error";
    // Second order in h: a factor 4 a level, less a margin for these coarse tessellations.
    EXPECT_LT(check.max_relative_change, previous / 2.5) << "level " << level;
    previous = check.max_relative_change;
  }
}

}  // namespace
}  // namespace glint
