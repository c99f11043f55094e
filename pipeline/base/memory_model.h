#pragma once
/// @file
/// @brief What glint's data take in memory, item by item, known before anything is built: the
/// target's facets, a mesh, the occluder, the lit facets' candidates. The budget checks
/// (memory_budget.h, setup/target_builder.h) add these up; bench/memory_bench.cpp measures them.

#include <cstdint>

#include "facets/tessellate.h"

namespace glint::memory_model {

/// @brief Bytes held by each coarse facet, whatever its shape (Target's per-facet arrays).
double targetBytesPerFacet();
/// @brief Bytes of the occluder (Embree scene) per coarse facet that can shadow.
double occluderBytesPerFacet();
/// @brief Bytes held per lit facet: its candidate, and with @p clusters (the lobe scheme) its
/// share of the bounds over runs of lit facets.
double litBytesPerFacet(bool clusters);
/// @brief Bytes of a decoded mesh as the scene keeps it.
double meshBytes(double vertices, double triangles);
/// @brief What a facet's surface model adds to the target.
double surfaceBytesPerFacet(MeshSurface surface);
/// @brief @p bytes as a count, saturated at the largest std::uint64_t (a count too large to
/// build is reckoned and refused, not wrapped).
std::uint64_t saturated(double bytes);

}  // namespace glint::memory_model

namespace glint {

/// @brief A floor under the memory a mesh of @p triangles and @p vertices takes as part of a
/// target (decoded, its facets with their @p surface, and with @p occlusion its share of the
/// occluder), known before it is decoded: what the scene reader refuses a model by.
std::uint64_t meshMemoryFloorBytes(std::uint64_t triangles, std::uint64_t vertices,
                                   MeshSurface surface, bool occlusion);

}  // namespace glint
