#include "pipeline/setup/surface_check.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "pipeline/setup/target_builder.h"

namespace glint {

std::vector<MeshSurface> alternativeSurfaces(MeshSurface surface) {
  switch (surface) {
    case MeshSurface::PN:
    case MeshSurface::PNVlachos:
      return {MeshSurface::QuadricFit, MeshSurface::Nagata};
    case MeshSurface::Nagata:
      return {MeshSurface::PN, MeshSurface::QuadricFit};
    case MeshSurface::QuadricFit:
      return {MeshSurface::PN, MeshSurface::Nagata};
    case MeshSurface::Flat:
      break;
  }
  return {MeshSurface::PN};
}

double SurfaceProbe::relativeChange() const {
  if (alternative.empty()) return 0.0;
  if (irradiance_w_m2 > 0.0) return std::abs(alternative_w_m2 / irradiance_w_m2 - 1.0);
  return alternative_w_m2 > 0.0 ? std::numeric_limits<double>::infinity() : 0.0;
}

SurfaceModelCheck checkSurfaceModel(const Scene& scene, const FacetIntegrator& integrator,
                                    const std::vector<std::pair<std::string, Vec3>>& probes) {
  SurfaceModelCheck check;
  std::size_t triangles = 0, alternatives = 0;
  for (const ObjectSpec& o : scene.objects) {
    if (!o.mesh()) continue;
    triangles += o.mesh()->mesh->triangles.size();
    alternatives = std::max(alternatives, alternativeSurfaces(o.mesh()->surface).size());
  }
  if (triangles == 0) {
    check.skipped = "no mesh";
    return check;
  }
  if (triangles > kSurfaceCheckMaxTriangles) {
    check.skipped = std::to_string(triangles) + " triangles: over the check's " +
                    std::to_string(kSurfaceCheckMaxTriangles) +
                    " (each other surface's target would double the run's largest allocation)";
    return check;
  }
  IntegratorWorkspace ws;
  for (const auto& [where, at_m] : probes) {
    SurfaceProbe p{where, at_m, integrator.adaptive(at_m, ws).irradiance_w_m2, 0.0, ""};
    // At most the floor, a total is not resolved (the refinement stops there with whatever
    // pieces it had settled): no relative change of it means anything.
    if (p.irradiance_w_m2 > integrator.options().floor_w_m2) check.probes.push_back(p);
  }
  if (check.probes.empty()) {
    check.skipped = "no observer of the run sees the target";
    return check;
  }
  for (std::size_t k = 0; k < alternatives; ++k) {
    Scene other = scene;  // the meshes themselves are shared, not copied
    std::string name;
    for (ObjectSpec& o : other.objects) {
      if (!o.mesh()) continue;
      const std::vector<MeshSurface> list = alternativeSurfaces(o.mesh()->surface);
      o.mesh()->surface = list[std::min(k, list.size() - 1)];
      if (name.empty()) name = toString(o.mesh()->surface);
    }
    const FacetIntegrator alternative(buildTarget(other), integrator.beam(), integrator.options());
    for (SurfaceProbe& p : check.probes) {
      const ObserverResult r = alternative.adaptive(p.at_m, ws);
      if (!r.converged) continue;  // its answer is not one: no estimate of the mesh's error
      const SurfaceProbe candidate{p.where, p.at_m, p.irradiance_w_m2, r.irradiance_w_m2, name};
      if (p.alternative.empty() || candidate.relativeChange() > p.relativeChange()) p = candidate;
    }
  }
  for (const SurfaceProbe& p : check.probes) {
    check.max_relative_change = std::max(check.max_relative_change, p.relativeChange());
  }
  return check;
}

}  // namespace glint
