#include "pipeline/input/scene_memory.h"

#include <algorithm>

#include "facets/surface_map.h"
#include "pipeline/base/memory_model.h"

namespace glint {

using memory_model::saturated;

std::uint64_t coarseFacetCount(const ObjectSpec& o) {
  const AnalyticShape* shape = o.analytic();
  return shape ? saturated(coarseFacets(*shape, o.segments)) : 0;
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
    bytes += memory_model::meshBytes(static_cast<double>(mesh.positions_m.size()), t) +
             t * memory_model::surfaceBytesPerFacet(spec->surface);
  }
  // Per facet: its arrays, its surface map (the cubature and lobe schemes), its share of the
  // occluder.
  bytes += facets * (memory_model::targetBytesPerFacet() +
                     (options.scheme != IntegrationScheme::Paper ? sizeof(SurfaceMap) : 0.0) +
                     (m.occlusion ? memory_model::occluderBytesPerFacet() : 0.0));
  m.facets = saturated(facets);
  m.floor_bytes = saturated(bytes);
  m.lit_facet_bytes =
      saturated(memory_model::litBytesPerFacet(options.scheme == IntegrationScheme::Lobe));
  return m;
}

}  // namespace glint
