#pragma once
/// @file
/// @brief From a validated Scene to what the facet integrator works on.

#include "facets/integrator.h"
#include "facets/tessellate.h"
#include "observers/far_field.h"
#include "observers/field.h"
#include "pipeline/scene.h"

namespace glint {

/// @brief The scene's laser as a Beam.
Beam beamOf(const Scene& scene);

/// @brief The scene's objects tessellated into coarse facets. Tessellations are oriented by the
/// direction toward the laser, so rotating a whole scene rotates its facets with it. What
/// became of each mesh's triangles is appended to @p mesh_stats, in object order.
Target buildTarget(const Scene& scene, std::vector<MeshStats>* mesh_stats = nullptr);

/// @brief The scene's accuracy settings; the floor defaults to 1e-9 × the beam's peak
/// irradiance, far below any exposure limit yet scaled to the scene.
IntegratorOptions integratorOptions(const Scene& scene);

/// @brief The observer box of the scene's `observers` section; the floor defaults to
/// HazardSpec::negligibleW_m2().
/// @throw InputError when the scene has no `observers` section.
FieldSpec fieldSpec(const Scene& scene);

/// @brief The lattice of one of the scene's observer planes (axes u, v, u × v; one layer);
/// the floor defaults to HazardSpec::negligibleW_m2().
FieldSpec planeFieldSpec(const Scene& scene, const PlaneSpec& plane);

/// @brief The far field of the scene's `far_field` key for the target @p integrator lights:
/// the far radius from its lit ball, the narrowest lobe of the scene's materials and the
/// tolerance (farRadius()); the face lattice samples directions at most that lobe's σ apart
/// unless the scene says otherwise; the floor defaults to the intensity that gives
/// HazardSpec::negligibleW_m2() at the far radius.
FarFieldSpec farFieldSpec(const Scene& scene, const FacetIntegrator& integrator);

/// @brief Integrator settings for the points of an observer field: the scene's accuracy
/// settings, with the tolerance and floor a quarter of the field's, so that the integration
/// error stays a small part of the field's error budget.
IntegratorOptions fieldIntegratorOptions(const Scene& scene, const FieldSpec& field);

/// @brief Observer positions inside an object or within @p margin_m of its surface: inside a
/// sphere or a cylinder (its open ends closed), or on a disk. No eye can be there, and the
/// point-source model needs ever finer facets as an observer nears the surface.
ExcludedFn excludedRegion(const Scene& scene, double margin_m);

/// @brief What computing the scene's observer field takes besides its FieldSpec: the
/// integrator with fieldIntegratorOptions(), and the observers excluded within half a voxel
/// of the target (excludedRegion()).
struct FieldProblem {
  FacetIntegrator integrator;
  ExcludedFn excluded;
  std::vector<MeshStats> mesh_stats;  ///< what buildTarget() made of each mesh
};
FieldProblem fieldProblem(const Scene& scene, const FieldSpec& field);

/// @brief The scene's target built and culled once, its integrator at the accuracy of the
/// lattice @p first (fieldIntegratorOptions()): the observer box and every plane derive their
/// FieldProblem from it.
struct SceneTarget {
  FacetIntegrator integrator;
  std::vector<MeshStats> mesh_stats;  ///< what buildTarget() made of each mesh
};
SceneTarget sceneTarget(const Scene& scene, const FieldSpec& first);

/// @brief As fieldProblem(scene, field), the target, its culling and occluder taken from
/// @p shared instead of built again (FacetIntegrator::withAccuracy()).
FieldProblem fieldProblem(const SceneTarget& shared, const Scene& scene, const FieldSpec& field);

}  // namespace glint
