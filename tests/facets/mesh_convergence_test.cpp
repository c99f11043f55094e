// Meshes converge to the surface they sample: a glTF-like mesh of a shape glint knows exactly
// (sphere, cylinder, disk, ellipsoid), tessellated finer and finer, gives the irradiance of the
// exact shape at the order its surface model claims (docs/meshes.md; bench/RESULTS.md has the
// full table, every model side by side).
//
// What the default surface (PN triangles, Bernstein normal field) claims, in the mean edge
// length h: with exact vertex normals, second order where the reflected mean of two vertex
// normals is the surface's own mid-edge normal (spheres, cylinders: the normal curves are
// circles), and first order at least elsewhere (the mid-edge normal is then off by O(h²), its
// derivative, the curvature a glint sees, by O(h)); with vertex normals off by O(h²) (an
// estimate of the normals), first order. Each case checks the observed order between
// successive tessellations, log(e₁/e₂)/log(h₁/h₂), against the claim less a quarter (these
// tessellations are not yet asymptotic: a quarter of an order is the spread measured over the
// bench's tessellations), and the finest error against the targets where it sets one.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <sstream>
#include <string>
#include <vector>

#include "facets/integrator.h"
#include "facets/tessellate.h"
#include "support/test_meshes.h"

namespace glint {
namespace {

// Reference at 1e-7 and meshes at 1e-5: the integration's own error stays two orders below the
// smallest surface error measured here (2e-4).
constexpr double kReferenceTolerance = 1e-7;
constexpr double kMeshTolerance = 1e-5;

struct ConvergenceCase {
  std::string name;
  double sigma = 0.01;
  double diffuse = 0.0;
  double near_m = 2.0, far_m = 45.0;
  std::function<void(Target&)> exact;     // the shape as glint knows it
  std::function<TriangleMesh(int)> mesh;  // its mesh at tessellation n, exact normals
  std::vector<int> tessellations;         // coarse to fine
  double perturbation = 0.0;              // normals turned by this × (h/R)²
  double curvature_radius_m = 1.0;        // the R of the perturbation
  double order = 2.0;                     // what the surface model claims
  double finest_max_error = 1.0;          // the target at the finest tessellation
  Vec3 beam_direction{1.0, 0.2, -0.1};
};

std::ostream& operator<<(std::ostream& os, const ConvergenceCase& c) { return os << c.name; }

Beam gaussianBeam(const Vec3& direction) {
  Beam beam;
  beam.direction = glm::normalize(direction);
  beam.origin_m = Vec3(0.0, 0.05, 0.03) - 100.0 * beam.direction;
  beam.profile = BeamProfile::Gaussian;
  beam.radius_m = 0.5;
  beam.power_w = 1000.0;
  return beam;
}

std::vector<double> irradiance(Target target, const Beam& beam, const std::vector<Vec3>& observers,
                               double tolerance) {
  IntegratorOptions options;
  options.tolerance = tolerance;
  options.floor_w_m2 = 1e-12;
  const FacetIntegrator fi(std::move(target), beam, options);
  IntegratorWorkspace ws;
  std::vector<double> e;
  for (const Vec3& o : observers) e.push_back(fi.adaptive(o, ws).irradiance_w_m2);
  return e;
}

class MeshConvergence : public ::testing::TestWithParam<ConvergenceCase> {};

TEST_P(MeshConvergence, ErrorFallsWithTheEdgeLengthAtTheClaimedOrder) {
  const ConvergenceCase& c = GetParam();
  const Beam beam = gaussianBeam(c.beam_direction);
  const Material material{0.95, c.diffuse, Beckmann{c.sigma}};
  const std::vector<Vec3> observers =
      test::glintObservers(c.mesh(c.tessellations.back()), beam, c.sigma, c.near_m, c.far_m, 24);
  Target exact;
  exact.addMaterial(material);
  c.exact(exact);
  const std::vector<double> reference =
      irradiance(std::move(exact), beam, observers, kReferenceTolerance);
  const double peak = *std::max_element(reference.begin(), reference.end());
  ASSERT_GT(peak, 0.0) << "the observers see the glint";

  std::vector<double> edge_m, max_error;
  std::ostringstream table;
  for (const int n : c.tessellations) {
    TriangleMesh mesh = c.mesh(n);
    const double h = test::meanEdgeLength(mesh);
    if (c.perturbation > 0.0) {
      const double relative = h / c.curvature_radius_m;
      test::perturbNormals(mesh, c.perturbation * relative * relative, 3);
    }
    Target t;
    t.addMaterial(material);
    addMesh(t, Vec3(0.0), 0, mesh, MeshSurface::PN);
    const std::vector<double> e = irradiance(std::move(t), beam, observers, kMeshTolerance);
    double worst = 0.0;
    int counted = 0;
    for (std::size_t i = 0; i < e.size(); ++i) {
      if (reference[i] < 0.01 * peak) continue;  // above 1 % of the peak, as the issue measures
      worst = std::max(worst, std::abs(e[i] / reference[i] - 1.0));
      ++counted;
    }
    ASSERT_GE(counted, 12) << "half the observers or more see the glint";
    edge_m.push_back(h);
    max_error.push_back(worst);
    table << "\n  " << mesh.triangles.size() << " triangles, h " << h << " m: max error " << worst;
  }
  for (std::size_t k = 0; k + 1 < edge_m.size(); ++k) {
    const double observed =
        std::log(max_error[k] / max_error[k + 1]) / std::log(edge_m[k] / edge_m[k + 1]);
    EXPECT_GE(observed, c.order - 0.25)
        << c.name << ": order " << observed << " from step " << k << table.str();
  }
  EXPECT_LE(max_error.back(), c.finest_max_error) << c.name << table.str();
}

// The exact shapes, tessellated as glint does (the toward-laser hint only turns the facets).
void unitSphere(Target& target) { addSphere(target, {Vec3(0.0), 1.0}, 0, 16, Vec3(-1, 0, 0)); }
void cylinder(Target& target) {
  addCylinder(target, {Vec3(0.0), Vec3(0, 0, 1), 0.5, 2.0}, 0, 16, Vec3(-1, 0, 0));
}
void disk(Target& target) {
  addDisk(target, {Vec3(0.0), Vec3(0, 0, 1), 0.5}, 0, 16, Vec3(-1, 0, 0));
}
void ellipsoid(Target& target) { test::addExactEllipsoid(target, 3, Vec3(1.0, 0.7, 0.5), 0); }
TriangleMesh cylinderMesh(int segments) { return test::openCylinder(segments, 0.5, 2.0); }
TriangleMesh diskMesh(int segments) { return test::flatDisk(segments, 0.5); }
TriangleMesh ellipsoidMesh(int level) { return test::ellipsoid(level, Vec3(1.0, 0.7, 0.5)); }
std::string caseName(const ::testing::TestParamInfo<ConvergenceCase>& param) {
  return param.param.name;
}

// The sphere's cases: the unit sphere against its icospheres of 320, 1 280 and 5 120 triangles.
ConvergenceCase sphereCase(std::string name, double sigma, double diffuse, double near_m,
                           double far_m, double perturbation, double order, double finest) {
  return {.name = std::move(name),
          .sigma = sigma,
          .diffuse = diffuse,
          .near_m = near_m,
          .far_m = far_m,
          .exact = unitSphere,
          .mesh = test::unitIcosphere,
          .tessellations = {2, 3, 4},
          .perturbation = perturbation,
          .order = order,
          .finest_max_error = finest};
}

INSTANTIATE_TEST_SUITE_P(
    Shapes, MeshConvergence,
    ::testing::Values(
        // The three sphere scenes and a wide lobe; its targets: ≤ 1 % at 5 120
        // triangles (≤ 3 % at 1 280, a bound the orders and the 5 120 one imply here).
        sphereCase("SphereFar", 0.01, 0.0, 2.0, 45.0, 0.0, 2.0, 0.01),
        sphereCase("SphereDiffuse", 0.02, 0.04, 2.0, 45.0, 0.0, 2.0, 0.01),
        sphereCase("SphereNear", 0.003, 0.0, 0.05, 0.05, 0.0, 2.0, 0.01),
        sphereCase("SphereWide", 0.1, 0.0, 2.0, 45.0, 0.0, 2.0, 0.01),
        // Normals an estimate could give, turned by (h/R)²/2: first order.
        sphereCase("SpherePerturbedNormals", 0.01, 0.0, 2.0, 45.0, 0.5, 1.0, 0.2),
        ConvergenceCase{.name = "Cylinder",
                        .exact = cylinder,
                        .mesh = cylinderMesh,
                        .tessellations = {16, 32, 64},
                        .curvature_radius_m = 0.5,
                        .finest_max_error = 0.01},
        // Flat: the error is the inscribed polygon's missing area, (2π/N)²/6 of the disk's.
        ConvergenceCase{.name = "Disk",
                        .sigma = 0.05,
                        .exact = disk,
                        .mesh = diskMesh,
                        .tessellations = {16, 32, 64},
                        .curvature_radius_m = 0.5,
                        .finest_max_error = 0.01,
                        .beam_direction = Vec3(0.6, 0.1, -1.0)},
        // A quadric that is neither: first order in general, 2 % at 5 120 triangles.
        ConvergenceCase{.name = "Ellipsoid",
                        .exact = ellipsoid,
                        .mesh = ellipsoidMesh,
                        .tessellations = {2, 3, 4},
                        .curvature_radius_m = 0.25,
                        .order = 1.0,
                        .finest_max_error = 0.02}),
    caseName);

}  // namespace
}  // namespace glint
