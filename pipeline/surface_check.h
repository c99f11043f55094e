#pragma once
/// @file
/// @brief How far the meshes' surface model moves a run's answer: an estimate of the
/// tessellation's own error (README, "Meshes"), so an analyst knows when to ask for a finer mesh.
///
/// A mesh fixes only its vertices and their normals; between them each surface model guesses
/// the surface its own way, and a glint's irradiance follows the curvature of that guess. Where
/// two good guesses from the same vertices disagree, the mesh does not determine the answer to
/// better than their difference. Measured on meshes of shapes glint knows exactly
/// (bench/RESULTS.md), the change is of the order of the default surface's true error, and
/// larger on spheres and cylinders, where the default is the better of the two.

#include <string>
#include <vector>

#include "facets/integrator.h"
#include "facets/tessellate.h"
#include "pipeline/scene.h"

namespace glint {

/// @brief The surface a mesh is compared with: the quadric fit for PN triangles and Nagata
/// patches (the paper's surface from the same vertices and normals, fitted facet by facet),
/// PN triangles for the quadric fit and flat facets.
MeshSurface alternativeSurface(MeshSurface surface);

/// @brief One observer at which the two surfaces are compared.
struct SurfaceProbe {
  std::string where;              ///< e.g. "the observer box's peak"
  Vec3 at_m{0.0};                 ///< world position
  double irradiance_w_m2 = 0.0;   ///< with the meshes' own surfaces
  double alternative_w_m2 = 0.0;  ///< with alternativeSurface() for every mesh
  /// |alternative / irradiance − 1|; 0 where both are 0, +∞ where only the alternative is lit.
  [[nodiscard]] double relativeChange() const;
};

/// @brief The comparison at a run's brightest observers.
struct SurfaceModelCheck {
  /// Empty when it was made; otherwise why not (no mesh, nothing lit, a mesh too large).
  std::string skipped;
  std::vector<SurfaceProbe> probes;
  double max_relative_change = 0.0;  ///< over the probes
};

/// @brief Meshes whose triangles together exceed this are not checked: the alternative target
/// would double the run's largest allocation.
inline constexpr std::size_t kSurfaceCheckMaxTriangles = 1'000'000;

/// @brief Integrates each probe (a label and a world position) with @p integrator, the run's,
/// and again with every mesh of @p scene rebuilt on alternativeSurface() under the same beam and
/// options. Probes that see nothing are dropped. Skipped (SurfaceModelCheck::skipped) for a
/// scene without meshes, without a lit probe, or with more than kSurfaceCheckMaxTriangles.
SurfaceModelCheck checkSurfaceModel(const Scene& scene, const FacetIntegrator& integrator,
                                    const std::vector<std::pair<std::string, Vec3>>& probes);

}  // namespace glint
