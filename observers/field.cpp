#include "observers/field.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>

#include "observers/detail/field_common.h"
#include "observers/field_grids.h"

namespace glint {

openvdb::math::Transform::Ptr fieldTransform(const FieldSpec& spec) {
  const std::array<Vec3, 3>& e = spec.axes;
  if (e[0] == Vec3(1.0, 0.0, 0.0) && e[1] == Vec3(0.0, 1.0, 0.0) && e[2] == Vec3(0.0, 0.0, 1.0)) {
    auto transform = openvdb::math::Transform::createLinearTransform(spec.voxel_m);
    transform->postTranslate(openvdb::Vec3d(spec.min_m.x, spec.min_m.y, spec.min_m.z));
    return transform;
  }
  // OpenVDB maps index to world as a row vector times this matrix: rows are the scaled axes.
  openvdb::Mat4d m = openvdb::Mat4d::identity();
  for (int a = 0; a < 3; ++a) {
    const Vec3 row = spec.voxel_m * e[static_cast<std::size_t>(a)];
    m.setRow(a, openvdb::Vec4d(row.x, row.y, row.z, 0.0));
  }
  m.setRow(3, openvdb::Vec4d(spec.min_m.x, spec.min_m.y, spec.min_m.z, 1.0));
  return openvdb::math::Transform::createLinearTransform(m);
}

std::vector<float> activeOnLattice(const openvdb::FloatGrid& grid, const std::array<int, 3>& n,
                                   std::size_t& outside) {
  std::vector<float> out(static_cast<std::size_t>(n[0]) * static_cast<std::size_t>(n[1]) *
                             static_cast<std::size_t>(n[2]),
                         0.0f);
  outside = 0;
  for (auto it = grid.cbeginValueOn(); it; ++it) {
    // A tile stands for all its voxels.
    const openvdb::CoordBBox box = it.getBoundingBox();
    for (auto c = box.begin(); c; ++c) {
      const openvdb::Coord& q = *c;
      if (q.x() < 0 || q.y() < 0 || q.z() < 0 || q.x() >= n[0] || q.y() >= n[1] || q.z() >= n[2]) {
        ++outside;
        continue;
      }
      out[(static_cast<std::size_t>(q.z()) * static_cast<std::size_t>(n[1]) +
           static_cast<std::size_t>(q.y())) *
              static_cast<std::size_t>(n[0]) +
          static_cast<std::size_t>(q.x())] = *it;
    }
  }
  return out;
}

std::array<double, 2> SurfaceOffsets::range(int i0, int j0, int i1, int j1) const {
  std::array<double, 2> r{at(i0, j0), at(i0, j0)};
  for (int j = j0; j <= j1; ++j)
    for (int i = i0; i <= i1; ++i) {
      const double o = at(i, j);
      r[0] = std::min(r[0], o);
      r[1] = std::max(r[1], o);
    }
  return r;
}

std::array<int, 3> FieldSpec::nodes() const {
  if (radial) return {radial->face_cells + 1, radial->face_cells + 1, radial->layers + 1};
  std::array<int, 3> n{};
  for (int a = 0; a < 3; ++a) {
    if (plane && a == 2) {
      n[2] = 1;
      continue;
    }
    // A box edge within a millionth of a voxel of a whole number of voxels is that number.
    const double voxels = glm::dot(max_m - min_m, axes[static_cast<std::size_t>(a)]) / voxel_m;
    const auto whole = static_cast<std::int64_t>(std::ceil(voxels - 1e-6));
    const std::int64_t blocks =
        (std::max<std::int64_t>(whole, 1) + block_voxels - 1) / block_voxels;
    n[static_cast<std::size_t>(a)] = static_cast<int>(blocks * block_voxels + 1);
  }
  return n;
}

FieldStats FieldStats::countsOnly() const {
  FieldStats c = *this;
  const FieldStats none;
  c.unconverged_min_m = none.unconverged_min_m;
  c.unconverged_max_m = none.unconverged_max_m;
  c.unresolved_max_bound_w_m2 = none.unresolved_max_bound_w_m2;
  c.unresolved_bound_at_m = none.unresolved_bound_at_m;
  c.unresolved_unbounded_blocks = none.unresolved_unbounded_blocks;
  c.unresolved_min_m = none.unresolved_min_m;
  c.unresolved_max_m = none.unresolved_max_m;
  c.unresolved_resolving_voxel_m = none.unresolved_resolving_voxel_m;
  c.peak_w_m2 = none.peak_w_m2;
  c.peak_at_m = none.peak_at_m;
  return c;
}

FieldStats& FieldStats::operator+=(const FieldStats& o) {
  lattice_points += o.lattice_points;
  evaluated_points += o.evaluated_points;
  interpolated_points += o.interpolated_points;
  below_floor_points += o.below_floor_points;
  excluded_points += o.excluded_points;
  unconverged_points += o.unconverged_points;
  unconverged_min_m = glm::min(unconverged_min_m, o.unconverged_min_m);
  unconverged_max_m = glm::max(unconverged_max_m, o.unconverged_max_m);
  unconverged_max_upper_w_m2 = std::max(unconverged_max_upper_w_m2, o.unconverged_max_upper_w_m2);
  if (non_finite_points == 0) non_finite_at_m = o.non_finite_at_m;
  non_finite_points += o.non_finite_points;
  blocks_skipped += o.blocks_skipped;
  blocks_accepted += o.blocks_accepted;
  blocks_accepted_spread += o.blocks_accepted_spread;
  blocks_refined += o.blocks_refined;
  blocks_finest += o.blocks_finest;
  unresolved_blocks += o.unresolved_blocks;
  unresolved_points += o.unresolved_points;
  if (o.unresolved_max_bound_w_m2 > unresolved_max_bound_w_m2) {
    unresolved_max_bound_w_m2 = o.unresolved_max_bound_w_m2;
    unresolved_bound_at_m = o.unresolved_bound_at_m;
  }
  unresolved_unbounded_blocks += o.unresolved_unbounded_blocks;
  unresolved_min_m = glm::min(unresolved_min_m, o.unresolved_min_m);
  unresolved_max_m = glm::max(unresolved_max_m, o.unresolved_max_m);
  // 0 means "none computed", not a voxel of zero size.
  if (o.unresolved_resolving_voxel_m > 0.0 &&
      (unresolved_resolving_voxel_m == 0.0 ||
       o.unresolved_resolving_voxel_m < unresolved_resolving_voxel_m)) {
    unresolved_resolving_voxel_m = o.unresolved_resolving_voxel_m;
  }
  evaluations += o.evaluations;
  bound_evaluations += o.bound_evaluations;
  levels = std::max(levels, o.levels);
  if (o.peak_w_m2 > peak_w_m2) {
    peak_w_m2 = o.peak_w_m2;
    peak_at_m = o.peak_at_m;
  }
  seconds += o.seconds;
  active_voxels += o.active_voxels;
  grid_bytes += o.grid_bytes;
  return *this;
}

ObserverField::ObserverField(FieldSpec spec, FieldStats stats, std::unique_ptr<FieldGrids> grids,
                             std::vector<FieldBlock> blocks)
    : spec_(spec), stats_(stats), grids_(std::move(grids)), blocks_(std::move(blocks)) {}
ObserverField::~ObserverField() = default;
ObserverField::ObserverField(ObserverField&&) noexcept = default;
ObserverField& ObserverField::operator=(ObserverField&&) noexcept = default;

double ObserverField::irradiance(int i, int j, int k) const {
  return static_cast<double>(grids_->irradiance->tree().getValue(openvdb::Coord(i, j, k)));
}
std::vector<float> ObserverField::irradianceLattice() const {
  std::size_t outside = 0;
  return activeOnLattice(*grids_->irradiance, spec_.nodes(), outside);
}
std::vector<float> ObserverField::upperLattice(int stride) const {
  const auto n = spec_.nodes();
  std::array<int, 3> m{};
  for (int a = 0; a < 3; ++a) m[a] = (n[a] - 1) / stride + 1;
  const auto index = [&](const openvdb::Coord& q) -> std::optional<std::size_t> {
    for (int a = 0; a < 3; ++a) {
      if (q[a] < 0 || q[a] % stride != 0 || q[a] / stride >= m[a]) return std::nullopt;
    }
    return (static_cast<std::size_t>(q.z() / stride) * static_cast<std::size_t>(m[1]) +
            static_cast<std::size_t>(q.y() / stride)) *
               static_cast<std::size_t>(m[0]) +
           static_cast<std::size_t>(q.x() / stride);
  };
  std::vector<float> out(static_cast<std::size_t>(m[0]) * static_cast<std::size_t>(m[1]) *
                         static_cast<std::size_t>(m[2]));
  auto irradiance = grids_->irradiance->getConstAccessor();
  std::size_t p = 0;
  for (int k = 0; k < m[2]; ++k)
    for (int j = 0; j < m[1]; ++j)
      for (int i = 0; i < m[0]; ++i, ++p) {
        const openvdb::Coord c(i * stride, j * stride, k * stride);
        out[p] = irradiance.isValueOn(c) ? irradiance.getValue(c) : 0.0f;
      }
  const auto raise = [&](const openvdb::Coord& q, float value) {
    if (const std::optional<std::size_t> at = index(q)) out[*at] = std::max(out[*at], value);
  };
  for (auto it = grids_->upper->cbeginValueOn(); it; ++it) raise(it.getCoord(), *it);
  forEachUnresolvedPoint(
      [&](int i, int j, int k, float bound) { raise(openvdb::Coord(i, j, k), bound); });
  return out;
}

void ObserverField::forEachUnresolvedPoint(
    const std::function<void(int, int, int, float)>& visit) const {
  const field::Lattice lattice{spec_.nodes()};
  auto status = grids_->status->getConstAccessor();
  for (const FieldBlock& b : blocks_) {
    if (b.status != VoxelStatus::Unresolved) continue;
    const float bound = field::boundAsFloat(b.bound_w_m2);
    const openvdb::CoordBBox box = field::ownedBox(b.origin, b.size, lattice);
    for (auto it = box.begin(); it; ++it) {
      const openvdb::Coord& q = *it;
      // Only the block's points marked Unresolved: the rest are at the thresholds already.
      if (static_cast<VoxelStatus>(std::lround(status.getValue(q))) == VoxelStatus::Unresolved)
        visit(q.x(), q.y(), q.z(), bound);
    }
  }
}

double ObserverField::unconvergedUpper(int i, int j, int k) const {
  return static_cast<double>(grids_->upper->tree().getValue(openvdb::Coord(i, j, k)));
}
VoxelStatus ObserverField::status(int i, int j, int k) const {
  return static_cast<VoxelStatus>(
      std::lround(grids_->status->tree().getValue(openvdb::Coord(i, j, k))));
}
int ObserverField::level(int i, int j, int k) const {
  return static_cast<int>(std::lround(grids_->level->tree().getValue(openvdb::Coord(i, j, k))));
}

double ObserverField::volumeAbove(double threshold_w_m2) const {
  std::int64_t count = 0;
  for (auto it = grids_->irradiance->cbeginValueOn(); it; ++it) {
    if (static_cast<double>(*it) >= threshold_w_m2)
      count += static_cast<std::int64_t>(it.getVoxelCount());
  }
  return static_cast<double>(count) * spec_.voxel_m * spec_.voxel_m * spec_.voxel_m;
}

ObserverField::Exceedance ObserverField::exceedance(double threshold_w_m2,
                                                    const Vec3& from_m) const {
  Exceedance r;
  r.min_m = Vec3(std::numeric_limits<double>::infinity());
  r.max_m = -r.min_m;
  const auto n = spec_.nodes();
  const auto add = [&](const openvdb::Coord& c) {
    for (int a = 0; a < 3; ++a) {
      const auto last = n[static_cast<std::size_t>(a)] - 1;
      r.reaches_edge = r.reaches_edge || (last > 0 && (c[a] == 0 || c[a] == last));
    }
    const Vec3 x = spec_.position(c.x(), c.y(), c.z());
    r.min_m = glm::min(r.min_m, x);
    r.max_m = glm::max(r.max_m, x);
    const double d = glm::length(x - from_m);
    if (d > r.farthest_m) {
      r.farthest_m = d;
      r.farthest_at_m = x;
    }
  };
  for (auto it = grids_->irradiance->cbeginValueOn(); it; ++it) {
    if (!(static_cast<double>(*it) >= threshold_w_m2)) continue;
    if (it.isVoxelValue()) {
      add(it.getCoord());
      ++r.points;
      continue;
    }
    // A tile: its box's corners hold its extremes.
    openvdb::CoordBBox box;
    it.getBoundingBox(box);
    for (int c = 0; c < 8; ++c) {
      add(openvdb::Coord((c & 4) != 0 ? box.max().x() : box.min().x(),
                         (c & 2) != 0 ? box.max().y() : box.min().y(),
                         (c & 1) != 0 ? box.max().z() : box.min().z()));
    }
    r.points += static_cast<std::int64_t>(box.volume());
  }
  // An Unconverged point below the threshold whose value plus error reaches it: the
  // integration that stopped short cannot say it is safe, so it counts.
  const auto irradiance = grids_->irradiance->getConstAccessor();
  for (auto it = grids_->upper->cbeginValueOn(); it; ++it) {
    if (!(static_cast<double>(*it) >= threshold_w_m2)) continue;
    if (static_cast<double>(irradiance.getValue(it.getCoord())) >= threshold_w_m2) continue;
    add(it.getCoord());
    ++r.points;
    ++r.by_error_points;
  }
  if (r.points == 0) r.min_m = r.max_m = Vec3(0.0);
  r.volume_m3 = static_cast<double>(r.points) * spec_.voxel_m * spec_.voxel_m * spec_.voxel_m;
  return r;
}

std::uint64_t fieldMemoryFloorBytes(const FieldSpec& spec, bool dense) {
  // Measured (glint run -q, peak resident memory against box size, nothing to evaluate): the
  // dense twin 43 bytes per lattice point, the adaptive field 1 600 bytes per coarse block
  // (its Block, bound, decision and final record, the grids' tiles, the VTU cell); a little
  // below, so the floor stays one.
  constexpr double kDenseBytesPerPoint = 40.0;
  constexpr double kAdaptiveBytesPerCoarseBlock = 1500.0;
  const std::array<int, 3> n = spec.nodes();
  double points = 1.0, blocks = 1.0;
  for (int a = 0; a < 3; ++a) {
    points *= n[a];
    const int cells = std::max(1, n[a] - 1);
    blocks *=
        spec.plane && a == 2 ? 1.0 : std::ceil(static_cast<double>(cells) / spec.block_voxels);
  }
  double bytes = dense ? kDenseBytesPerPoint * points : kAdaptiveBytesPerCoarseBlock * blocks;
  if (spec.plane) {
    // A plane is one layer of voxels, so no 8³ leaf of its grids is ever whole or uniform and
    // none prunes to a tile: the status and level grids (written at every lattice point,
    // whatever the point's fate) keep a leaf of 512 floats per 8 × 8 points. Measured: a dark
    // 4097² far-field face 1.15 GB of grids (68 bytes a point), a dark 4097² plane of glint run
    // 1.79 GB of peak resident memory (106 bytes a point); counted here, 64.
    constexpr double kLeafBytes = 512.0 * sizeof(float);
    const double leaves = std::ceil(n[0] / 8.0) * std::ceil(n[1] / 8.0);
    const double leaf_bytes = 2.0 * kLeafBytes * leaves;
    // The dense twin's figure per point was measured on boxes, its grids included.
    bytes = dense ? std::max(bytes, leaf_bytes) : bytes + leaf_bytes;
  }
  return bytes >= 1.8e19 ? std::numeric_limits<std::uint64_t>::max()
                         : static_cast<std::uint64_t>(bytes);
}

}  // namespace glint
