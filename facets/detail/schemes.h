#pragma once
// The integration schemes (IntegrationScheme, integrator.h), each a rule of the refinement
// engine (refine.h) in a file of its own: paper_scheme.cpp, cubature_scheme.cpp,
// lobe_scheme.cpp. FacetIntegrator::adaptive() picks one once per observer; each entry point
// compiles the engine with its rule, so nothing is dispatched per piece.

#include <cstdint>
#include <span>
#include <vector>

#include "facets/beam.h"
#include "facets/detail/culling.h"
#include "facets/detail/diffuse_moments.h"
#include "facets/detail/workspace.h"
#include "facets/integrator.h"
#include "facets/material.h"
#include "facets/reflection.h"
#include "facets/surface_map.h"
#include "facets/target.h"

namespace glint::detail {

// The observer and the beam in one object's frame, and the object's material.
struct Frame {
  const Vec3& observer_m;
  const Beam& beam;
  const Material& material;
};

// What a scheme sees of the integrator for one observer: views of the FacetIntegrator's culled
// target and of the workspace (FacetIntegrator::prepareObserver()), for one term of the
// materials (Material::terms()): a material of several lobes is integrated a lobe at a time.
struct ObserverSetting {
  const Target& target;
  const IntegratorOptions& options;
  // Per material of the target, its terms; and the term this integration takes of each (a
  // material with fewer terms reflects nothing in it).
  std::span<const std::vector<Material>> material_terms;
  std::size_t term;
  std::span<const Beam> object_beams;      // the beam in each object's frame
  std::span<const SurfaceMap> maps;        // per coarse facet (empty for the paper scheme)
  std::span<const Vec3> observer_local_m;  // the observer in each object's frame
  Vec3 observer_m;                         // world coordinates
  const Occluder* occluder;                // null where the target cannot shadow itself
  std::span<const Candidate> lit;          // every lit coarse facet
  const LitClusters* clusters;             // bounds over runs of `lit`, or null
  // Coarse facets' diffuse moments, for the lobe scheme where a material has a diffuse term;
  // null otherwise.
  const DiffuseMomentCache* diffuse_moments;

  [[nodiscard]] Frame frame(std::uint32_t object) const {
    static const Material kDark{};  // reflects nothing: every bound of it is 0
    const std::vector<Material>& terms = material_terms[target.objects[object].material];
    return {observer_local_m[object], object_beams[object],
            term < terms.size() ? terms[term] : kDark};
  }
  // Whether the observer sees the candidate's centre past the rest of the target.
  [[nodiscard]] bool visible(const Candidate& c) const {
    return detail::visible(occluder, target, c, observer_m);
  }
};

// Calls fn(candidate, frame) for each of @p candidates that may face the observer and that it
// sees, in their order.
template <class Fn>
void forEachSeen(const ObserverSetting& s, std::span<const Candidate> candidates, Fn&& fn) {
  for (const Candidate& c : candidates) {
    if (!mayFaceObserver(c.geometry, s.observer_local_m[c.object]) || !s.visible(c)) continue;
    fn(c, s.frame(c.object));
  }
}

// One observer's integration over @p candidates (ObserverSetting::lit, or those a ball bound
// kept) by each scheme.
ObserverResult integratePaper(const ObserverSetting& s, std::span<const Candidate> candidates,
                              Workspace& ws);
ObserverResult integrateCubature(const ObserverSetting& s, std::span<const Candidate> candidates,
                                 Workspace& ws);
ObserverResult integrateLobe(const ObserverSetting& s, std::span<const Candidate> candidates,
                             Workspace& ws);

}  // namespace glint::detail
