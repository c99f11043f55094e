#include "pipeline/target_builder.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "facets/tessellate.h"
#include "pipeline/input_error.h"
#include "pipeline/limits.h"

namespace glint {

Beam beamOf(const Scene& scene) {
  const LaserSpec& l = scene.laser;
  Beam beam;
  beam.origin_m = l.position_m;
  beam.direction = l.direction;
  beam.power_w = l.power_w;
  beam.profile = l.profile;
  beam.radius_m = l.radius_m;
  beam.divergence_rad = l.divergence_rad;
  beam.extinction_per_m = scene.hazard.atmosphere.extinction_per_m;
  beam.return_extinction_per_m = scene.hazard.atmosphere.extinction_per_m;
  return beam;
}

Target buildTarget(const Scene& scene, std::vector<MeshStats>* mesh_stats) {
  Target target;
  for (const MaterialSpec& m : scene.materials) {
    target.addMaterial({m.specular_reflectance, m.diffuse_reflectance, Beckmann{m.sigma}});
  }
  const Vec3 toward_laser = -scene.laser.direction;
  for (const ObjectSpec& o : scene.objects) {
    switch (o.shape) {
      case ShapeKind::Cylinder:
        addCylinder(target, {o.center_m, o.axis, o.radius_m, o.length_m}, o.material, o.segments,
                    toward_laser);
        break;
      case ShapeKind::Sphere:
        addSphere(target, {o.center_m, o.radius_m}, o.material, o.segments, toward_laser);
        break;
      case ShapeKind::Disk:
        addDisk(target, {o.center_m, o.axis, o.radius_m}, o.material, o.segments, toward_laser);
        break;
      case ShapeKind::Mesh: {
        const MeshStats stats =
            addMesh(target, o.center_m, o.material, *o.mesh->mesh, o.mesh->surface);
        if (mesh_stats) mesh_stats->push_back(stats);
        break;
      }
    }
  }
  return target;
}

IntegratorOptions integratorOptions(const Scene& scene) {
  const AccuracySpec& a = scene.accuracy;
  IntegratorOptions o;
  o.tolerance = a.tolerance;
  o.floor_w_m2 = a.floor_w_m2 ? *a.floor_w_m2 : 1e-9 * beamOf(scene).peakIrradiance();
  o.max_depth = a.max_depth;
  o.max_evaluations = a.max_evaluations;
  o.normals = a.normals;
  o.occlusion = a.occlusion;
  o.scheme = a.scheme;
  return o;
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
  FieldSpec f;
  f.plane = true;
  f.axes = {plane.u_axis, plane.v_axis, glm::cross(plane.u_axis, plane.v_axis)};
  f.min_m = plane.origin_m;
  f.max_m = plane.origin_m + plane.width_m * plane.u_axis + plane.height_m * plane.v_axis;
  f.voxel_m = plane.pixel_m;
  f.block_voxels = static_cast<int>(std::lround(plane.block_m / plane.pixel_m));
  f.tolerance = plane.tolerance;
  f.floor_w_m2 = plane.floor_w_m2.value_or(scene.hazard.negligibleW_m2());
  f.hazard_threshold_w_m2 = scene.hazard.lowestHazardousW_m2();
  return f;
}

FarFieldSpec farFieldSpec(const Scene& scene, const FacetIntegrator& integrator) {
  const FarFieldSettings& settings = scene.far_field;
  double sigma = std::numeric_limits<double>::infinity();
  for (const MaterialSpec& m : scene.materials) {
    if (m.specular_reflectance > 0.0) sigma = std::min(sigma, m.sigma);
  }
  FarFieldSpec f;
  f.tolerance = settings.tolerance;
  // Nothing lit: any radius will do, the map is dark.
  const double lit_radius_m = std::max(litBall(integrator).radius_m, limits::kMinLengthM);
  f.far_radius_m = farRadius(lit_radius_m, sigma, f.tolerance);
  f.lit_radius_m = lit_radius_m;
  f.narrowest_sigma = sigma;
  f.beam_direction = beamOf(scene).direction;
  if (settings.face_pixels) {
    f.face_pixels = *settings.face_pixels;
  } else {
    // At a face's centre directions are 2/N rad apart: at most σ.
    f.face_pixels = 64;
    while (f.face_pixels < 4096 && 2.0 / f.face_pixels > sigma) f.face_pixels *= 2;
  }
  f.block_pixels = std::max(1, f.face_pixels / 16);
  f.floor_w_sr =
      settings.floor_w_sr.value_or(scene.hazard.negligibleW_m2() * f.far_radius_m * f.far_radius_m);
  return f;
}

IntegratorOptions fieldIntegratorOptions(const Scene& scene, const FieldSpec& field) {
  IntegratorOptions o = integratorOptions(scene);
  o.tolerance = 0.25 * field.tolerance;
  o.floor_w_m2 = 0.25 * field.floor_w_m2;
  return o;
}

SceneTarget sceneTarget(const Scene& scene, const FieldSpec& first) {
  std::vector<MeshStats> mesh_stats;
  FacetIntegrator integrator(buildTarget(scene, &mesh_stats), beamOf(scene),
                             fieldIntegratorOptions(scene, first));
  return {std::move(integrator), std::move(mesh_stats)};
}

FieldProblem fieldProblem(const SceneTarget& shared, const Scene& scene, const FieldSpec& field) {
  const IntegratorOptions o = fieldIntegratorOptions(scene, field);
  return {shared.integrator.withAccuracy(o.tolerance, o.floor_w_m2),
          excludedRegion(scene, 0.5 * field.voxel_m), shared.mesh_stats};
}

FieldProblem fieldProblem(const Scene& scene, const FieldSpec& field) {
  return fieldProblem(sceneTarget(scene, field), scene, field);
}

ExcludedFn excludedRegion(const Scene& scene, double margin_m) {
  return [objects = scene.objects, margin_m](const Vec3& x) {
    for (const ObjectSpec& o : objects) {
      const Vec3 v = x - o.center_m;
      switch (o.shape) {
        case ShapeKind::Sphere:
          if (glm::length(v) < o.radius_m + margin_m) return true;
          break;
        case ShapeKind::Cylinder: {
          const double along = glm::dot(v, o.axis);
          const double across = glm::length(v - along * o.axis);
          if (std::abs(along) < 0.5 * o.length_m + margin_m && across < o.radius_m + margin_m)
            return true;
          break;
        }
        case ShapeKind::Disk: {
          const double along = glm::dot(v, o.axis);
          const double across = glm::length(v - along * o.axis);
          if (std::abs(along) < margin_m && across < o.radius_m + margin_m) return true;
          break;
        }
        case ShapeKind::Mesh:
          // Observers near a mesh are computed: its inside is not known in closed form.
          break;
      }
    }
    return false;
  };
}

}  // namespace glint
