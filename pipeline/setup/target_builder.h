#pragma once
/// @file
/// @brief From a validated Scene to what the facet integrator works on.

#include <cstdint>
#include <string>
#include <vector>

#include "facets/integrator.h"
#include "facets/tessellate.h"
#include "observers/far_field.h"
#include "observers/field.h"
#include "observers/reach.h"
#include "pipeline/input/scene.h"
#include "pipeline/input/scene_memory.h"

namespace glint {

/// @brief The scene's objects tessellated into coarse facets. Tessellations are oriented by the
/// direction toward the laser, so rotating a whole scene rotates its facets with it. What
/// became of each mesh's triangles is appended to @p mesh_stats, in object order.
Target buildTarget(const Scene& scene, std::vector<MeshStats>* mesh_stats = nullptr);

/// @brief The memory budget buildIntegrator() holds a target to.
struct TargetBudget {
  std::uint64_t budget_bytes = 0;   ///< 0: not checked
  std::uint64_t besides_bytes = 0;  ///< held at the same time by the rest of the command
  std::string besides;              ///< what that is, for the message (e.g. "the far field")
};

/// @brief Refuses a target whose floor, @p lit_facets lit facets and the budget's besides_bytes
/// exceed the budget, before it is built.
/// @throw InputError "the target (N coarse facets[, with …]) needs at least … of memory, more than
/// the budget of … (--memory); lower the objects' segments, decimate the meshes, or raise
/// --memory".
void requireTargetWithinBudget(const TargetMemory& memory, const TargetBudget& budget,
                               std::uint64_t lit_facets = 0);

/// @brief The scene's target, built and culled (buildTarget(), FacetIntegrator), refused by
/// requireTargetWithinBudget() before its facets are made, and where the target cannot shadow
/// itself once more, its lit facets counted, before they are stored.
FacetIntegrator buildIntegrator(const Scene& scene, const IntegratorOptions& options,
                                const TargetBudget& budget = {},
                                std::vector<MeshStats>* mesh_stats = nullptr);

/// @brief The observer box of the scene's `observers` section; the floor defaults to
/// HazardSpec::negligibleW_m2().
/// @throw InputError when the scene has no `observers` section.
FieldSpec fieldSpec(const Scene& scene);

/// @brief The lattice of one of the scene's observer planes (axes u, v, u × v; one layer);
/// the floor defaults to HazardSpec::negligibleW_m2().
FieldSpec planeFieldSpec(const Scene& scene, const PlaneSpec& plane);

/// @brief The far field of the scene's `far_field` key for the target @p integrator lights:
/// the far radius from its lit ball, the target's narrowest lobe and the tolerance
/// (farRadius()); the face lattice samples directions at most that lobe's width apart unless
/// the scene says otherwise; the floor defaults to the intensity that gives
/// HazardSpec::negligibleW_m2() at the far radius.
FarFieldSpec farFieldSpec(const Scene& scene, const FacetIntegrator& integrator);

/// @brief farFieldSpec() with the floor lowered to 1e-3 × the lowest hazardous irradiance × the
/// innermost sphere² (16 lit radii), so that the far radius check may come in that far: the far
/// field that speaks as near as it can (the settling benchmark; the hazard reach).
FarFieldSpec checkedFarFieldSpec(const Scene& scene, const FacetIntegrator& integrator);

/// @brief The accuracy the hazard reach's lattices are computed to (the tolerance and floor of
/// reachSpec()), as a field the target is built for when the scene has no box or plane.
FieldSpec reachAccuracy(const Scene& scene);

/// @brief The hazard reach of the scene's `reach` key about the lit ball of @p far, from its
/// radius out to the far radius: for the MPE and, with an optical aid, the aided MPE.
ReachSpec reachSpec(const Scene& scene, const FarField& far);

/// @brief What farFieldSpec() says of the faces' lattices (face_pixels, block_pixels) and the
/// tolerance, from the scene alone (the narrowest lobe of its materials, which the target
/// will have): known before the target is built.
FarFieldSpec farFieldLattice(const Scene& scene);

/// @brief Integrator settings for the points of an observer field: the scene's accuracy
/// settings, with the tolerance and floor a quarter of the field's, so that the integration
/// error stays a small part of the field's error budget.
IntegratorOptions fieldIntegratorOptions(const Scene& scene, const FieldSpec& field);

/// @brief Observer positions inside an object or within @p margin_m of its surface: inside a
/// sphere or a cylinder (its open ends closed), or on a disk. No eye can be there, and the
/// point-source model needs ever finer facets as an observer nears the surface.
ExcludedFn excludedRegion(const Scene& scene, double margin_m);

/// @brief What computing the scene's observer field takes besides its FieldSpec: the
/// integrator with fieldIntegratorOptions(), and the observers excluded (excludedRegion()):
/// within half a voxel of the target for a box or plane, only inside it for a radial lattice.
struct FieldProblem {
  FacetIntegrator integrator;
  ExcludedFn excluded;
  std::vector<MeshStats> mesh_stats;  ///< what buildTarget() made of each mesh
};
FieldProblem fieldProblem(const Scene& scene, const FieldSpec& field);

/// @brief The scene's target built and culled once, its integrator at the accuracy of the
/// lattice @p first (fieldIntegratorOptions()): the observer box and every plane derive their
/// FieldProblem from it. Held to @p budget as buildIntegrator() does.
struct SceneTarget {
  FacetIntegrator integrator;
  std::vector<MeshStats> mesh_stats;  ///< what buildTarget() made of each mesh
};
SceneTarget sceneTarget(const Scene& scene, const FieldSpec& first,
                        const TargetBudget& budget = {});

/// @brief As fieldProblem(scene, field), the target, its culling and occluder taken from
/// @p shared instead of built again (FacetIntegrator::withAccuracy()).
FieldProblem fieldProblem(const SceneTarget& shared, const Scene& scene, const FieldSpec& field);

}  // namespace glint
