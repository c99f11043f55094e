// The space a block of each lattice spans (observers/detail/block_geometry.h), and the merge of
// a field's statistics (FieldStats::operator+=).
#include "observers/detail/block_geometry.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>

namespace glint::field {
namespace {

// Every lattice point of the block lies in its ball, and no two neighbouring samples of its
// check (three along each edge) are farther apart than its sample spacing: what the block bound
// relies on to see every observer the block holds and every glint as wide as the spacing.
void expectBlockInItsBall(const FieldSpec& spec, const Index3& o, const BlockSize& size) {
  const BlockGeometry geometry(spec);
  const Vec3 centre = geometry.centre(o, size);
  const double radius_m = geometry.radius(o, size);
  const bool flat = spec.nodes()[2] == 1;
  const int depth = flat ? 0 : size[2];
  double farthest_m = 0.0;
  for (int i = 0; i <= size[0]; ++i)
    for (int j = 0; j <= size[1]; ++j)
      for (int k = 0; k <= depth; ++k) {
        farthest_m =
            std::max(farthest_m, glm::length(spec.position(o[0] + i, o[1] + j, o[2] + k) - centre));
      }
  EXPECT_LE(farthest_m, radius_m) << "a point of the block outside its ball";
  // A ball far larger than the block would make every bound loose: within rounding of the
  // farthest corner for the box and the radial lattice, of the offsets' box over a surface.
  EXPECT_LE(radius_m, (spec.surface ? 1.5 : 1.0 + 1e-9) * farthest_m) << "a loose ball";

  const double spacing_m = geometry.sampleSpacing(o, size);
  const std::array<int, 3> step = {std::max(1, size[0] / 2), std::max(1, size[1] / 2),
                                   std::max(1, depth / 2)};
  double widest_m = 0.0;
  for (int i = 0; i <= size[0]; i += step[0])
    for (int j = 0; j <= size[1]; j += step[1])
      for (int k = 0; k <= depth; k += step[2]) {
        const Vec3 p = spec.position(o[0] + i, o[1] + j, o[2] + k);
        if (i + step[0] <= size[0])
          widest_m = std::max(
              widest_m, glm::length(spec.position(o[0] + i + step[0], o[1] + j, o[2] + k) - p));
        if (j + step[1] <= size[1])
          widest_m = std::max(
              widest_m, glm::length(spec.position(o[0] + i, o[1] + j + step[1], o[2] + k) - p));
        if (!flat && k + step[2] <= depth)
          widest_m = std::max(
              widest_m, glm::length(spec.position(o[0] + i, o[1] + j, o[2] + k + step[2]) - p));
      }
  EXPECT_LE(widest_m, spacing_m * (1.0 + 1e-12)) << "samples farther apart than the spacing";
}

FieldSpec box() {
  FieldSpec s;
  s.min_m = {-1.0, 2.0, 0.5};
  s.max_m = {7.0, 10.0, 8.5};
  s.voxel_m = 0.25;
  s.block_voxels = 8;
  return s;
}

TEST(BlockGeometry, TheBallHoldsEveryPointOfABoxBlockAndIsHalfItsDiagonal) {
  const FieldSpec s = box();
  for (const BlockSize& size : {BlockSize{8, 8, 8}, BlockSize{4, 2, 8}, BlockSize{1, 1, 2}}) {
    expectBlockInItsBall(s, {8, 16, 0}, size);
    const double diagonal_m =
        s.voxel_m * std::sqrt(size[0] * size[0] + size[1] * size[1] + size[2] * size[2]);
    EXPECT_NEAR(BlockGeometry(s).radius({8, 16, 0}, size), 0.5 * diagonal_m, 1e-15 * diagonal_m)
        << "a box block's ball is the one about its diagonal";
  }
}

TEST(BlockGeometry, APlanesBlockHasNoDepth) {
  FieldSpec s = box();
  s.plane = true;
  s.axes = {glm::normalize(Vec3(1.0, 1.0, 0.0)), Vec3(0.0, 0.0, 1.0),
            glm::normalize(Vec3(1.0, -1.0, 0.0))};
  s.max_m = s.min_m + 8.0 * s.axes[0] + 8.0 * s.axes[1];
  expectBlockInItsBall(s, {8, 0, 0}, {8, 8, 2});
  EXPECT_NEAR(BlockGeometry(s).radius({8, 0, 0}, {8, 8, 2}), 0.5 * std::sqrt(2.0) * 8 * s.voxel_m,
              1e-15)
      << "a plane's block: half the diagonal of its square";
}

TEST(BlockGeometry, TheBallHoldsEveryPointOfARadialBlock) {
  FieldSpec s;
  RadialLattice r;
  r.centre_m = {3.0, -2.0, 1.0};
  r.face_cells = 16;
  r.layers = 32;
  r.inner_layers = 8;
  r.start_m = 0.2;
  r.near_m = 2.0;
  r.ratio = 1.2;
  s.radial = r;
  s.block_voxels = 8;
  s.axes = {Vec3(0.0, 1.0, 0.0), Vec3(0.0, 0.0, 1.0), Vec3(1.0, 0.0, 0.0)};
  for (const Index3& o : {Index3{0, 0, 0}, Index3{8, 0, 8}, Index3{0, 8, 24}})
    for (const BlockSize& size : {BlockSize{8, 8, 8}, BlockSize{2, 8, 4}, BlockSize{1, 1, 1}})
      expectBlockInItsBall(s, o, size);
}

TEST(BlockGeometry, TheBallHoldsEveryPointOfABlockOverASurface) {
  FieldSpec s = box();
  s.plane = true;
  s.max_m = s.min_m + Vec3(8.0, 8.0, 0.0);
  const std::array<int, 3> n = s.nodes();
  auto offsets = std::make_shared<SurfaceOffsets>();
  offsets->width = n[0];
  offsets->height = n[1];
  for (int j = 0; j < n[1]; ++j)
    for (int i = 0; i < n[0]; ++i)  // a ridge and a slope: offsets of either sign
      offsets->offset_m.push_back(1.7 + 0.3 * i - 2.0 * std::abs(std::sin(0.2 * j)));
  s.surface = offsets;
  for (const BlockSize& size : {BlockSize{8, 8, 2}, BlockSize{4, 2, 2}, BlockSize{1, 1, 2}})
    expectBlockInItsBall(s, {8, 16, 0}, size);
}

TEST(FieldStats, AMergeAddsCountsJoinsBoxesAndKeepsTheFirstOfEqualPeaks) {
  FieldStats a, b;
  a.evaluated_points = 3;
  a.evaluations = 40;
  a.peak_w_m2 = 5.0;
  a.peak_at_m = Vec3(1.0);
  a.unconverged_min_m = a.unconverged_max_m = Vec3(0.0, 1.0, 2.0);
  a.unresolved_resolving_voxel_m = 0.0;  // none computed
  b.evaluated_points = 4;
  b.evaluations = 2;
  b.peak_w_m2 = 5.0;
  b.peak_at_m = Vec3(2.0);
  b.unconverged_min_m = b.unconverged_max_m = Vec3(-1.0, 4.0, 2.0);
  b.non_finite_points = 1;
  b.non_finite_at_m = Vec3(9.0);
  b.unresolved_resolving_voxel_m = 0.1;
  b.unresolved_max_bound_w_m2 = 7.0;
  b.unresolved_bound_at_m = Vec3(3.0);
  b.levels = 4;
  FieldStats c;
  c.non_finite_points = 2;
  c.non_finite_at_m = Vec3(8.0);
  c.unresolved_resolving_voxel_m = 0.05;
  c.peak_w_m2 = 4.0;

  a += b;
  a += c;
  EXPECT_EQ(a.evaluated_points, 7) << "points add";
  EXPECT_EQ(a.evaluations, 42) << "evaluations add";
  EXPECT_EQ(a.peak_at_m, Vec3(1.0)) << "of equal peaks the first kept stays";
  EXPECT_EQ(a.peak_w_m2, 5.0);
  EXPECT_EQ(a.unconverged_min_m, Vec3(-1.0, 1.0, 2.0)) << "boxes join";
  EXPECT_EQ(a.unconverged_max_m, Vec3(0.0, 4.0, 2.0)) << "boxes join";
  EXPECT_EQ(a.non_finite_points, 3);
  EXPECT_EQ(a.non_finite_at_m, Vec3(9.0)) << "the first non-finite point stays the one named";
  EXPECT_EQ(a.unresolved_resolving_voxel_m, 0.05) << "the finest voxel; 0 counts as none";
  EXPECT_EQ(a.unresolved_max_bound_w_m2, 7.0);
  EXPECT_EQ(a.unresolved_bound_at_m, Vec3(3.0));
  EXPECT_EQ(a.levels, 4) << "the deepest level";
}

}  // namespace
}  // namespace glint::field
