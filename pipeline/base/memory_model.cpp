#include "pipeline/base/memory_model.h"

#include <algorithm>
#include <array>
#include <limits>

#include "facets/integrator.h"
#include "facets/pn_triangle.h"
#include "facets/quadric.h"

namespace glint::memory_model {

namespace {

// What each coarse facet holds, whatever its shape (Target's per-facet arrays): corners, object,
// surface model and its index, rim bits. Measured: 84 to 93 bytes a facet resident after
// buildTarget() on disks of 1 024 to 4 096 segments (glint_memory_bench).
constexpr double kTargetBytesPerFacet = sizeof(std::array<Vec3, 3>) + 2 * sizeof(std::uint32_t) +
                                        sizeof(SurfaceModel) + sizeof(std::uint8_t);
// The occluder's Embree scene (each coarse facet split to level 2: 16 triangles) and its
// lift per facet. Measured: 1 672 bytes a facet resident (a 250 000-triangle sphere mesh) and
// 1 791 (two disks, 665 600 facets), 2 100 to 2 830 at the peak of its build.
constexpr double kOccluderBytesPerFacet = 1500.0;
// A lit facet's candidate, and in the lobe scheme its share of the bounds over runs of 8 lit
// facets (LitClusters: a PatchGeometry a node at the lowest level, as many again above).
// Measured: 457 bytes a lit facet (disks of 2 048 segments, all lit against 2 % lit); counted
// here, the candidate and the lowest level, 428. Both before PatchGeometry gained its normal
// band (40 bytes, in the candidate and the cluster alike), which sizeof follows.
constexpr double kLitBytesPerFacet = sizeof(Candidate);
constexpr double kLitClusterBytesPerFacet = sizeof(PatchGeometry) / 8.0;
// A decoded mesh as the scene keeps it (TriangleMesh): a position and a normal a vertex, three
// indices a triangle.
constexpr double kMeshBytesPerVertex = 2 * sizeof(Vec3);
constexpr double kMeshBytesPerTriangle = sizeof(std::array<std::uint32_t, 3>);

}  // namespace

// What a facet's surface model adds to the target: a mesh's PN (or Nagata) patch, a fitted
// quadric where the fit holds (a PN patch where it does not: the smaller counts). An analytic
// object's facets share its one quadric.
double surfaceBytesPerFacet(MeshSurface surface) {
  switch (surface) {
    case MeshSurface::Flat:
      return 0.0;
    case MeshSurface::QuadricFit:
      return static_cast<double>(std::min(sizeof(Quadric), sizeof(PNTriangle)));
    case MeshSurface::PN:
    case MeshSurface::Nagata:
    case MeshSurface::PNVlachos:
      break;
  }
  return sizeof(PNTriangle);
}

std::uint64_t saturated(double bytes) {
  return bytes >= 1.8e19 ? std::numeric_limits<std::uint64_t>::max()
                         : static_cast<std::uint64_t>(bytes);
}

double targetBytesPerFacet() { return kTargetBytesPerFacet; }
double occluderBytesPerFacet() { return kOccluderBytesPerFacet; }
double litBytesPerFacet(bool clusters) {
  return kLitBytesPerFacet + (clusters ? kLitClusterBytesPerFacet : 0.0);
}
double meshBytes(double vertices, double triangles) {
  return kMeshBytesPerVertex * vertices + kMeshBytesPerTriangle * triangles;
}

}  // namespace glint::memory_model

namespace glint {

std::uint64_t meshMemoryFloorBytes(std::uint64_t triangles, std::uint64_t vertices,
                                   MeshSurface surface, bool occlusion) {
  using namespace memory_model;
  const auto t = static_cast<double>(triangles);
  return saturated(meshBytes(static_cast<double>(vertices), t) +
                   t * (targetBytesPerFacet() + surfaceBytesPerFacet(surface) +
                        (occlusion ? occluderBytesPerFacet() : 0.0)));
}

}  // namespace glint
