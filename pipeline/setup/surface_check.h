#pragma once
/// @file
/// @brief How far the meshes' surface model moves a run's answer: an estimate of the
/// tessellation's own error (docs/meshes.md), so an analyst knows when to ask for a finer mesh.
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
#include "pipeline/input/scene.h"

namespace glint {

/// @brief The surfaces a mesh is compared with, built from the same vertices and normals in
/// other ways: the quadric fit (facet by facet, PN where a fit fails) and Nagata patches for PN
/// triangles; PN and one of those for the others; PN for flat facets. Each can fail where the
/// other holds (the fit falls back to PN on thin cylinders' long facets, where it is PN again;
/// Nagata bulges where neighbouring normals are nearly parallel), so the check takes the
/// largest change among those that converge.
std::vector<MeshSurface> alternativeSurfaces(MeshSurface surface);

/// @brief One observer at which the surfaces are compared.
struct SurfaceProbe {
  std::string where;             ///< e.g. "the box's peak"
  Vec3 at_m{0.0};                ///< world position
  double irradiance_w_m2 = 0.0;  ///< with the meshes' own surfaces
  /// With the alternative surfaces (alternativeSurfaces()) that changed it most, of those that
  /// converged here; `alternative` names it for the first mesh ("" where none converged).
  double alternative_w_m2 = 0.0;
  std::string alternative;
  /// |alternative / irradiance − 1|; 0 where both are 0 or no alternative converged, +∞ where
  /// only the alternative is lit.
  [[nodiscard]] double relativeChange() const;
};

/// @brief The comparison at a run's brightest observers.
struct SurfaceModelCheck {
  /// Empty when it was made; otherwise why not (no mesh, nothing lit, a mesh too large).
  std::string skipped;
  std::vector<SurfaceProbe> probes;
  double max_relative_change = 0.0;  ///< over the probes
};

/// @brief Meshes whose triangles together exceed this are not checked: each alternative target
/// would double the run's largest allocation.
inline constexpr std::size_t kSurfaceCheckMaxTriangles = 1'000'000;

/// @brief Integrates each probe (a label and a world position) with @p integrator, the run's,
/// and again with every mesh of @p scene rebuilt on each of alternativeSurfaces() under the
/// same beam and options. Probes that see nothing are dropped; an alternative's value at a probe
/// counts only where it converged. Skipped (SurfaceModelCheck::skipped) for a scene without
/// meshes, without a lit probe, or with more than kSurfaceCheckMaxTriangles.
SurfaceModelCheck checkSurfaceModel(const Scene& scene, const FacetIntegrator& integrator,
                                    const std::vector<std::pair<std::string, Vec3>>& probes);

}  // namespace glint
