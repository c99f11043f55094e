#include "pipeline/target_builder.h"

#include "facets/tessellate.h"

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
  return beam;
}

Target buildTarget(const Scene& scene) {
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
  return o;
}

}  // namespace glint
