#pragma once
/// @file
/// @brief Where a block of an adaptive field's lattice lies in space. Internal to observers/.

#include <array>

#include "observers/block_check.h"
#include "observers/detail/field_common.h"
#include "observers/field.h"

namespace glint::field {

/// @brief The space a block of lattice points spans, for each lattice a FieldSpec describes: a
/// box or plane of equal voxels, a radial lattice about a centre (rays × layers), and a plane
/// draped over a surface. What the block bound needs of a block is a ball that holds every
/// point of it and the widest gap between the samples its check reads; this is where the three
/// lattices differ, and the only place.
///
/// A block is lattice points origin .. origin + size[a] along each axis a; a plane's blocks have
/// size 2 along the normal but no depth. Holds a reference to the spec: keep it alive.
class BlockGeometry {
 public:
  explicit BlockGeometry(const FieldSpec& spec) : spec_(spec), flat_(spec.nodes()[2] == 1) {}

  /// @brief The centre of the ball that holds the block (m).
  [[nodiscard]] Vec3 centre(const Index3& origin, const BlockSize& size) const;
  /// @brief The radius of that ball (m): every point of the block lies in it.
  [[nodiscard]] double radius(const Index3& origin, const BlockSize& size) const;
  /// @brief The widest gap between the block's check samples (m): three samples span each edge,
  /// so a glint narrower than this may pass between them.
  [[nodiscard]] double sampleSpacing(const Index3& origin, const BlockSize& size) const;

 private:
  [[nodiscard]] std::array<Vec3, 8> corners(const Index3& o, const BlockSize& size) const;
  [[nodiscard]] std::array<double, 2> offsetRange(const Index3& o, const BlockSize& size) const;
  [[nodiscard]] Vec3 surfaceCentre(const Index3& o, const BlockSize& size) const;
  [[nodiscard]] double surfaceRadius(const Index3& o, const BlockSize& size) const;
  [[nodiscard]] double measuredSampleSpacing(const Index3& o, const BlockSize& size) const;

  const FieldSpec& spec_;
  bool flat_;  // one lattice layer: a plane's blocks have no depth
};

}  // namespace glint::field
