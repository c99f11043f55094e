#include "pipeline/surface_check.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "pipeline/target_builder.h"

namespace glint {

MeshSurface alternativeSurface(MeshSurface surface) {
  switch (surface) {
    case MeshSurface::PN:
    case MeshSurface::Nagata:
    case MeshSurface::PNVlachos:
      return MeshSurface::QuadricFit;
    case MeshSurface::QuadricFit:
    case MeshSurface::Flat:
      break;
  }
  return MeshSurface::PN;
}

double SurfaceProbe::relativeChange() const {
  if (irradiance_w_m2 > 0.0) return std::abs(alternative_w_m2 / irradiance_w_m2 - 1.0);
  return alternative_w_m2 > 0.0 ? std::numeric_limits<double>::infinity() : 0.0;
}

SurfaceModelCheck checkSurfaceModel(const Scene& scene, const FacetIntegrator& integrator,
                                    const std::vector<std::pair<std::string, Vec3>>& probes) {
  SurfaceModelCheck check;
  Scene alternative = scene;  // the meshes themselves are shared, not copied
  std::size_t triangles = 0;
  for (ObjectSpec& o : alternative.objects) {
    if (!o.mesh) continue;
    o.mesh->surface = alternativeSurface(o.mesh->surface);
    triangles += o.mesh->mesh->triangles.size();
  }
  if (triangles == 0) {
    check.skipped = "no mesh";
    return check;
  }
  if (triangles > kSurfaceCheckMaxTriangles) {
    check.skipped = std::to_string(triangles) + " triangles: over the check's " +
                    std::to_string(kSurfaceCheckMaxTriangles) +
                    " (a second target would double the run's largest allocation)";
    return check;
  }
  IntegratorWorkspace ws;
  for (const auto& [where, at_m] : probes) {
    SurfaceProbe p{where, at_m, integrator.adaptive(at_m, ws).irradiance_w_m2, 0.0};
    if (p.irradiance_w_m2 > 0.0) check.probes.push_back(p);
  }
  if (check.probes.empty()) {
    check.skipped = "no observer of the run sees the target";
    return check;
  }
  const FacetIntegrator other(buildTarget(alternative), integrator.beam(), integrator.options());
  for (SurfaceProbe& p : check.probes) {
    p.alternative_w_m2 = other.adaptive(p.at_m, ws).irradiance_w_m2;
    check.max_relative_change = std::max(check.max_relative_change, p.relativeChange());
  }
  return check;
}

}  // namespace glint
