#pragma once
/// @file
/// @brief What a scene's target will take in memory, reckoned from the scene alone before any
/// of it is built (the per-item figures: base/memory_model.h).

#include <cstdint>

#include "facets/integrator.h"
#include "pipeline/input/scene.h"

namespace glint {

/// @brief What the scene's target takes in memory, reckoned from the scene alone before any of
/// it is built: a floor, each term an allocation buildTarget() and FacetIntegrator make
/// whatever the beam and the observers (README "Reliability", Memory).
struct TargetMemory {
  std::uint64_t facets = 0;           ///< coarse facets the objects make (a mesh: one a triangle)
  std::uint64_t floor_bytes = 0;      ///< held once built and culled, the lit facets aside
  std::uint64_t lit_facet_bytes = 0;  ///< held besides for each lit facet (candidate, bounds)
  bool occlusion = false;             ///< shadow rays decide which facets are lit (Occluder)
};

/// @brief The memory of the target of @p scene under @p options (its scheme and occlusion).
TargetMemory targetMemory(const Scene& scene, const IntegratorOptions& options);

/// @brief The coarse facets an analytic object makes (addCylinder(), addSphere(), addDisk());
/// 0 for a mesh.
std::uint64_t coarseFacetCount(const ObjectSpec& object);

}  // namespace glint
