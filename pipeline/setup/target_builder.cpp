#include "pipeline/setup/target_builder.h"

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
#include "pipeline/base/input_error.h"
#include "pipeline/base/limits.h"
#include "pipeline/base/memory_budget.h"
#include "pipeline/base/memory_model.h"

namespace glint {

using memory_model::saturated;

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
  f.hazard_thresholds_w_m2 = scene.hazard.thresholdsW_m2();
  return f;
}

FieldSpec planeFieldSpec(const Scene& scene, const PlaneSpec& plane) {
  FieldSpec f = planeLattice(plane);
  f.tolerance = plane.tolerance;
  f.floor_w_m2 = plane.floor_w_m2.value_or(scene.hazard.negligibleW_m2());
  f.hazard_thresholds_w_m2 = scene.hazard.thresholdsW_m2();
  return f;
}

namespace {

// The lattice of the far field of @p settings for light whose narrowest directional term is
// @p narrowest_rad wide.
FarFieldSpec farFieldLattice(const FarFieldSettings& settings,
                             const std::optional<double>& narrowest_rad) {
  FarFieldSpec f;
  f.tolerance = settings.tolerance;
  if (settings.face_pixels) {
    f.face_pixels = *settings.face_pixels;
  } else {
    // At a face's centre directions are 2/N rad apart: at most the lobe's width.
    const double width_rad = narrowest_rad.value_or(std::numeric_limits<double>::infinity());
    f.face_pixels = 64;
    while (f.face_pixels < 4096 && 2.0 / f.face_pixels > width_rad) f.face_pixels *= 2;
  }
  f.block_pixels = std::max(1, f.face_pixels / 16);
  return f;
}

}  // namespace

FarFieldSpec farFieldLattice(const Scene& scene) {
  // The target is not built yet: its materials are the scene's (buildTarget()).
  return farFieldLattice(scene.far_field, narrowestWidthRad(scene.materials));
}

// The innermost sphere the far radius check may reach (FarFieldSpec::innermost_far_radius_m),
// in lit radii: nearer, the parallax is a sizeable share of the lobe everywhere.
constexpr double kInnermostFarRadiusInLitRadii = 16.0;

FarFieldSpec farFieldSpec(const Scene& scene, const FacetIntegrator& integrator) {
  const FarFieldSettings& settings = scene.far_field;
  const std::optional<double> narrowest = integrator.target().narrowestWidthRad();
  const double sigma = narrowest.value_or(std::numeric_limits<double>::infinity());
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
  f.hazard_thresholds_w_m2 = scene.hazard.thresholdsW_m2();
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
  r.thresholds_w_m2 = scene.hazard.thresholdsW_m2();
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
