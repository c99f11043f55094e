#include "pipeline/target_builder.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>

#include "facets/reflection.h"
#include "facets/surface_map.h"
#include "facets/tessellate.h"
#include "pipeline/input_error.h"
#include "pipeline/limits.h"
#include "pipeline/memory_budget.h"

namespace glint {

Target buildTarget(const Scene& scene, std::vector<MeshStats>* mesh_stats) {
  Target target;
  for (const Material& m : scene.materials) target.addMaterial(m);
  const Vec3 toward_laser = -scene.laser.direction;
  for (const ObjectSpec& o : scene.objects) {
    if (const AnalyticShape* shape = o.analytic()) {
      addShape(target, *shape, o.material, o.segments, toward_laser);
      continue;
    }
    const MeshSpec& mesh = *o.mesh();
    const MeshStats stats =
        addMesh(target, mesh.transform.translation_m, o.material, *mesh.mesh, mesh.surface);
    if (mesh_stats) mesh_stats->push_back(stats);
  }
  return target;
}

namespace {

// What each coarse facet holds, whatever its shape (Target's per-facet arrays): corners, object,
// surface model and its index, rim bits. Measured: 84 to 93 bytes a facet resident after
// buildTarget() on disks of 1 024 to 4 096 segments (glint_memory_bench).
constexpr double kTargetBytesPerFacet = sizeof(std::array<Vec3, 3>) + 2 * sizeof(std::uint32_t) +
                                        sizeof(SurfaceModel) + sizeof(std::uint8_t);
// The occluder's Embree scene (each coarse facet split to level 2: 16 triangles) and its
// lift per facet. Measured: 1 672 bytes a facet resident (a 250 000-triangle sphere mesh) and
// 1 791 (two disks, 665 600 facets), 2 100 to 2 830 at the peak of its build.
constexpr double kOccluderBytesPerFacet = 1500.0;
// A lit facet's candidate, and in the lobe scheme its share of the bounds over runs of 8 lit
// facets (LitClusters: a PatchGeometry a node at the lowest level, as many again above).
// Measured: 457 bytes a lit facet (disks of 2 048 segments, all lit against 2 % lit); counted
// here, the candidate and the lowest level, 428. Both before PatchGeometry gained its normal
// band (40 bytes, in the candidate and the cluster alike), which sizeof follows.
constexpr double kLitBytesPerFacet = sizeof(Candidate);
constexpr double kLitClusterBytesPerFacet = sizeof(PatchGeometry) / 8.0;
// A decoded mesh as the scene keeps it (TriangleMesh): a position and a normal a vertex, three
// indices a triangle.
constexpr double kMeshBytesPerVertex = 2 * sizeof(Vec3);
constexpr double kMeshBytesPerTriangle = sizeof(std::array<std::uint32_t, 3>);

// What a facet's surface model adds to the target: a mesh's PN (or Nagata) patch, a fitted
// quadric where the fit holds (a PN patch where it does not: the smaller counts). An analytic
// object's facets share its one quadric.
double surfaceBytesPerFacet(MeshSurface surface) {
  switch (surface) {
    case MeshSurface::Flat:
      return 0.0;
    case MeshSurface::QuadricFit:
      return static_cast<double>(std::min(sizeof(Quadric), sizeof(PNTriangle)));
    case MeshSurface::PN:
    case MeshSurface::Nagata:
    case MeshSurface::PNVlachos:
      break;
  }
  return sizeof(PNTriangle);
}

std::uint64_t saturated(double bytes) {
  return bytes >= 1.8e19 ? std::numeric_limits<std::uint64_t>::max()
                         : static_cast<std::uint64_t>(bytes);
}

// The facets the integrator keeps as lit where no shadow ray decides (no occluder): its own
// culling, the facets stored nowhere.
std::uint64_t litFacetCount(const Target& target, const Beam& beam, NormalModel normals) {
  std::vector<Beam> beams;
  beams.reserve(target.objects.size());
  for (const TargetObject& o : target.objects) beams.push_back(beam.relativeTo(o.origin_m));
  return tbb::parallel_reduce(
      tbb::blocked_range<std::uint32_t>(0, static_cast<std::uint32_t>(target.facetCount())),
      std::uint64_t{0},
      [&](const tbb::blocked_range<std::uint32_t>& range, std::uint64_t lit) {
        for (std::uint32_t i = range.begin(); i != range.end(); ++i) {
          const PatchGeometry g = patchGeometry(target, coarseSubFacet(target, i), normals);
          if (g.area_m2 > 0.0 && lightVerdict(g, beams[target.object[i]]) == LightVerdict::MayBeLit)
            ++lit;
        }
        return lit;
      },
      std::plus<>());
}

}  // namespace

std::uint64_t coarseFacetCount(const ObjectSpec& o) {
  const AnalyticShape* shape = o.analytic();
  return shape ? saturated(coarseFacets(*shape, o.segments)) : 0;
}

std::uint64_t meshMemoryFloorBytes(std::uint64_t triangles, std::uint64_t vertices,
                                   MeshSurface surface, bool occlusion) {
  const auto t = static_cast<double>(triangles);
  return saturated(kMeshBytesPerVertex * static_cast<double>(vertices) +
                   t * (kMeshBytesPerTriangle + kTargetBytesPerFacet +
                        surfaceBytesPerFacet(surface) +
                        (occlusion ? kOccluderBytesPerFacet : 0.0)));
}

TargetMemory targetMemory(const Scene& scene, const IntegratorOptions& options) {
  TargetMemory m;
  double facets = 0.0, bytes = 0.0;
  // As needsOcclusion(): more than one object, or one that is not convex (a mesh never is).
  const bool concave =
      std::any_of(scene.objects.begin(), scene.objects.end(),
                  [](const ObjectSpec& o) { return !o.analytic() || !isConvex(*o.analytic()); });
  m.occlusion = options.occlusion && (scene.objects.size() > 1 || concave);
  for (const ObjectSpec& o : scene.objects) {
    const MeshSpec* spec = o.mesh();
    if (!spec) {
      facets += static_cast<double>(coarseFacetCount(o));
      continue;
    }
    // Every triangle a facet: addMesh() drops only degenerate ones, which no real model is
    // made of.
    const TriangleMesh& mesh = *spec->mesh;
    const auto t = static_cast<double>(mesh.triangles.size());
    facets += t;
    bytes += kMeshBytesPerVertex * static_cast<double>(mesh.positions_m.size()) +
             t * (kMeshBytesPerTriangle + surfaceBytesPerFacet(spec->surface));
  }
  // Per facet: its arrays, its surface map (the cubature and lobe schemes), its share of the
  // occluder.
  bytes += facets * (kTargetBytesPerFacet +
                     (options.scheme != IntegrationScheme::Paper ? sizeof(SurfaceMap) : 0.0) +
                     (m.occlusion ? kOccluderBytesPerFacet : 0.0));
  m.facets = saturated(facets);
  m.floor_bytes = saturated(bytes);
  m.lit_facet_bytes =
      saturated(kLitBytesPerFacet +
                (options.scheme == IntegrationScheme::Lobe ? kLitClusterBytesPerFacet : 0.0));
  return m;
}

void requireTargetWithinBudget(const TargetMemory& memory, const TargetBudget& budget,
                               std::uint64_t lit_facets) {
  if (budget.budget_bytes == 0) return;
  const double bytes =
      static_cast<double>(memory.floor_bytes) +
      static_cast<double>(lit_facets) * static_cast<double>(memory.lit_facet_bytes) +
      static_cast<double>(budget.besides_bytes);
  std::string what = "the target (" + std::to_string(memory.facets) + " coarse facets";
  if (lit_facets > 0) what += ", " + std::to_string(lit_facets) + " of them lit";
  if (!budget.besides.empty()) what += ", with " + budget.besides;
  requireWithinBudget(what + ")", saturated(bytes), budget.budget_bytes,
                      "lower the objects' segments, decimate the meshes, or raise --memory");
}

FacetIntegrator buildIntegrator(const Scene& scene, const IntegratorOptions& options,
                                const TargetBudget& budget, std::vector<MeshStats>* mesh_stats) {
  const TargetMemory memory = targetMemory(scene, options);
  requireTargetWithinBudget(memory, budget);
  Target target = buildTarget(scene, mesh_stats);
  const Beam& beam = scene.laser;
  // The lit facets are counted only where storing them all might not fit, and only where no
  // shadow ray can take any of them away (then the count is the integrator's own).
  const double all_lit =
      static_cast<double>(memory.floor_bytes) +
      static_cast<double>(memory.facets) * static_cast<double>(memory.lit_facet_bytes) +
      static_cast<double>(budget.besides_bytes);
  if (budget.budget_bytes > 0 && !memory.occlusion &&
      all_lit > static_cast<double>(budget.budget_bytes)) {
    requireTargetWithinBudget(memory, budget, litFacetCount(target, beam, options.normals));
  }
  return FacetIntegrator(std::move(target), beam, options);
}

FieldSpec fieldSpec(const Scene& scene) {
  if (!scene.observers) {
    throw InputError(scene.source + ": /observers: missing (glint run needs an observer box)");
  }
  const ObserversSpec& o = *scene.observers;
  FieldSpec f;
  f.min_m = o.min_m;
  f.max_m = o.max_m;
  f.voxel_m = o.voxel_m;
  f.block_voxels = static_cast<int>(std::lround(o.block_m / o.voxel_m));
  f.tolerance = o.tolerance;
  f.floor_w_m2 = o.floor_w_m2.value_or(scene.hazard.negligibleW_m2());
  f.hazard_threshold_w_m2 = scene.hazard.lowestHazardousW_m2();
  return f;
}

FieldSpec planeFieldSpec(const Scene& scene, const PlaneSpec& plane) {
  FieldSpec f = planeLattice(plane);
  f.tolerance = plane.tolerance;
  f.floor_w_m2 = plane.floor_w_m2.value_or(scene.hazard.negligibleW_m2());
  f.hazard_threshold_w_m2 = scene.hazard.lowestHazardousW_m2();
  return f;
}

namespace {

// The lattice of the far field of @p settings for light whose narrowest lobe is @p narrowest.
FarFieldSpec farFieldLattice(const FarFieldSettings& settings,
                             const std::optional<Beckmann>& narrowest) {
  FarFieldSpec f;
  f.tolerance = settings.tolerance;
  if (settings.face_pixels) {
    f.face_pixels = *settings.face_pixels;
  } else {
    // At a face's centre directions are 2/N rad apart: at most the lobe's width.
    const double width_rad =
        narrowest ? narrowest->widthRad() : std::numeric_limits<double>::infinity();
    f.face_pixels = 64;
    while (f.face_pixels < 4096 && 2.0 / f.face_pixels > width_rad) f.face_pixels *= 2;
  }
  f.block_pixels = std::max(1, f.face_pixels / 16);
  return f;
}

}  // namespace

FarFieldSpec farFieldLattice(const Scene& scene) {
  // The target is not built yet: its materials are the scene's (buildTarget()).
  return farFieldLattice(scene.far_field, narrowestLobe(scene.materials));
}

// The innermost sphere the far radius check may reach (FarFieldSpec::innermost_far_radius_m),
// in lit radii: nearer, the parallax is a sizeable share of the lobe everywhere.
constexpr double kInnermostFarRadiusInLitRadii = 16.0;

FarFieldSpec farFieldSpec(const Scene& scene, const FacetIntegrator& integrator) {
  const FarFieldSettings& settings = scene.far_field;
  const std::optional<Beckmann> narrowest = integrator.target().narrowestLobe();
  const double sigma = narrowest ? narrowest->widthRad() : std::numeric_limits<double>::infinity();
  FarFieldSpec f = farFieldLattice(settings, narrowest);
  // Nothing lit: any radius will do, the map is dark.
  const double lit_radius_m = std::max(litBall(integrator).radius_m, limits::kMinLengthM);
  f.far_radius_m = farRadius(lit_radius_m, sigma, f.tolerance);
  f.first_order_far_radius_m = f.far_radius_m;
  f.lit_radius_m = lit_radius_m;
  f.narrowest_sigma = sigma;
  f.beam_direction = scene.laser.direction;
  f.hazard_threshold_w_m2 = scene.hazard.lowestHazardousW_m2();
  // The floor says how near the far field can speak: a direction below it is hazardous no
  // farther than a thirtieth of √(floor / negligible). By default that is the first-order
  // radius, and nothing is checked; a lower floor lets verifyFarRadius() bring the radius in
  // as far as it allows, but never nearer than a few lit radii.
  const double negligible_w_m2 = scene.hazard.negligibleW_m2();
  f.floor_w_sr = settings.floor_w_sr.value_or(negligible_w_m2 * f.far_radius_m * f.far_radius_m);
  f.innermost_far_radius_m = std::max(kInnermostFarRadiusInLitRadii * lit_radius_m,
                                      std::sqrt(f.floor_w_sr / negligible_w_m2));
  return f;
}

FarFieldSpec checkedFarFieldSpec(const Scene& scene, const FacetIntegrator& integrator) {
  FarFieldSpec f = farFieldSpec(scene, integrator);
  f.innermost_far_radius_m = kInnermostFarRadiusInLitRadii * f.lit_radius_m;
  f.floor_w_sr =
      scene.hazard.negligibleW_m2() * f.innermost_far_radius_m * f.innermost_far_radius_m;
  return f;
}

FieldSpec reachAccuracy(const Scene& scene) {
  FieldSpec f;  // its default tolerance
  f.floor_w_m2 = scene.hazard.negligibleW_m2();
  f.hazard_threshold_w_m2 = scene.hazard.lowestHazardousW_m2();
  return f;
}

ReachSpec reachSpec(const Scene& scene, const FarField& far) {
  const FieldSpec accuracy = reachAccuracy(scene);
  ReachSpec r;
  r.centre_m = far.ball().centre_m;
  r.near_m = std::max(far.ball().radius_m, limits::kMinLengthM);
  r.far_m = far.spec().far_radius_m;
  r.ratio = scene.reach.layer_ratio;
  r.face_cells = scene.reach.face_cells;
  r.thresholds_w_m2 = {scene.hazard.mpe_w_m2};
  if (scene.hazard.aid) r.thresholds_w_m2.push_back(scene.hazard.aidedMpeW_m2());
  r.tolerance = accuracy.tolerance;
  r.floor_w_m2 = accuracy.floor_w_m2;
  return r;
}

IntegratorOptions fieldIntegratorOptions(const Scene& scene, const FieldSpec& field) {
  IntegratorOptions o = scene.accuracy;
  o.tolerance = 0.25 * field.tolerance;
  o.floor_w_m2 = 0.25 * field.floor_w_m2;
  return o;
}

SceneTarget sceneTarget(const Scene& scene, const FieldSpec& first, const TargetBudget& budget) {
  std::vector<MeshStats> mesh_stats;
  FacetIntegrator integrator =
      buildIntegrator(scene, fieldIntegratorOptions(scene, first), budget, &mesh_stats);
  return {std::move(integrator), std::move(mesh_stats)};
}

FieldProblem fieldProblem(const SceneTarget& shared, const Scene& scene, const FieldSpec& field) {
  const IntegratorOptions o = fieldIntegratorOptions(scene, field);
  // A box's lattice leaves out half a voxel about the target, which its cells cannot resolve;
  // the reach's radial lattice only the target's inside: it classifies the rest.
  return {shared.integrator.withAccuracy(o.tolerance, o.floor_w_m2),
          excludedRegion(scene, field.radial ? 0.0 : 0.5 * field.voxel_m), shared.mesh_stats};
}

FieldProblem fieldProblem(const Scene& scene, const FieldSpec& field) {
  return fieldProblem(sceneTarget(scene, field), scene, field);
}

ExcludedFn excludedRegion(const Scene& scene, double margin_m) {
  // Observers near a mesh are computed: its inside is not known in closed form.
  std::vector<AnalyticShape> shapes;
  for (const ObjectSpec& o : scene.objects) {
    if (const AnalyticShape* shape = o.analytic()) shapes.push_back(*shape);
  }
  return [shapes = std::move(shapes), margin_m](const Vec3& x) {
    return std::any_of(shapes.begin(), shapes.end(),
                       [&](const AnalyticShape& s) { return nearOrInside(s, x, margin_m); });
  };
}

}  // namespace glint
