#pragma once
/// @file
/// @brief (Sub)facets of the 1→4 hierarchy and their geometry: what the reflection kernel and
/// the contribution bound need to know about a piece of surface.

#include <array>
#include <cstdint>
#include <vector>

#include "facets/target.h"
#include "facets/vec3.h"

namespace glint {

/// @brief Which normal a (sub)facet's BRDF sees.
enum class NormalModel : std::uint8_t {
  /// The curved facet: the true surface normal at the facet centre (quadric gradient, or the
  /// PN normal field) and the area of the curved patch. A chord triangle's plane is tilted
  /// against the surface it spans by up to half its angular size, which shifts a narrow lobe
  /// off its glint until the facets are smaller than the lobe, and its area falls short of
  /// the surface's by a same-signed O(h²) that never cancels; the centre normal and the
  /// curved area make each facet the midpoint rule of the true surface integral instead, so
  /// coarse facets already place glints correctly and smooth errors cancel between facets.
  Surface,
  /// The paper's flat facet: the normal of the plane through the three corners and the area
  /// of that triangle. Kept so that the two can be compared (bench/).
  Flat,
};

/// @brief A (sub)facet: three corners on the surface of a coarse facet.
struct SubFacet {
  std::array<Vec3, 3> corner_m;  ///< object-local positions, counter-clockwise from outside
  std::array<Vec3, 3> bary;      ///< the corners' barycentric coordinates in the coarse facet
  std::uint32_t coarse = 0;      ///< index of the coarse facet in the Target
  std::uint8_t depth = 0;        ///< subdivision level, 0 for the coarse facet itself
  std::uint8_t rim_edges = 0;    ///< bit k: edge (k, k+1) lies on the object's rim
};

/// @brief A bound of a patch's normals along one axis: every normal n it can show has n·axis in
/// [sin_lo, sin_hi], a band of latitudes about the great circle normal to the axis. The cone
/// bounds the normals in every direction at once; the band in one, where a cylinder's piece,
/// whose normals spread along its circumference only, has no width at all.
struct NormalBand {
  Vec3 axis{0.0};  ///< unit; zero where the patch has no band (its cone alone bounds it)
  double sin_lo = -1.0;
  double sin_hi = 1.0;
};

/// @brief The geometry of a (sub)facet.
struct PatchGeometry {
  Vec3 centre_m{0.0};          ///< x_C: the mean of the corners (the paper's choice)
  Vec3 normal{0.0, 0.0, 1.0};  ///< unit normal the BRDF sees (see NormalModel)
  double area_m2 = 0.0;        ///< area the kernel weights by: the curved patch's (Surface
                               ///< normals) or the chord triangle's (Flat normals)

  // The corners and their surface normals: cos θi and cos θr are modelled linearly between
  // them, so a facet straddling the terminator or the observer's horizon is clipped there.
  std::array<Vec3, 3> corner_m{};
  std::array<Vec3, 3> corner_normal{};

  // Bounds, filled only where requested (the uniform twin does not need them).
  double radius_m = 0.0;       ///< a ball of this radius about centre_m holds the curved patch
  double cone_rad = 0.0;       ///< every normal the patch can show lies within this of `normal`
  double area_bound_m2 = 0.0;  ///< an upper bound of the curved patch's true area
  NormalBand band{};           ///< where known, a second bound of the normals, along one axis
};

/// @brief The coarse facet @p facet of @p target as the root of its hierarchy.
SubFacet coarseSubFacet(const Target& target, std::uint32_t facet);

/// @brief The four children of @p f (corner children 0–2, then the middle one), with their
/// new corners placed on the facet's surface model.
std::array<SubFacet, 4> split(const Target& target, const SubFacet& f);

/// @brief Replaces @p out by the sub-facets of coarse facet @p facet at depth @p level (4^level
/// of them, depth first), on the facet's surface model.
void subFacetsAtDepth(const Target& target, std::uint32_t facet, int level,
                      std::vector<SubFacet>& out);

/// @brief Geometry of @p f including its bounds.
PatchGeometry patchGeometry(const Target& target, const SubFacet& f, NormalModel normals);

}  // namespace glint
