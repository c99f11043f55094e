#include "observers/detail/field_common.h"

#include <cmath>
#include <limits>
#include <stdexcept>

namespace glint::field {

void noteUnconverged(FieldStats& stats, openvdb::FloatGrid::Accessor& upper_grid,
                     const openvdb::Coord& p, const Vec3& x, double irradiance_w_m2,
                     double error_w_m2) {
  ++stats.unconverged_points;
  // A NaN counts as +∞: it must never let the summary say "none of them can be hazardous".
  double upper = irradiance_w_m2 + error_w_m2;
  if (std::isnan(upper)) upper = std::numeric_limits<double>::infinity();
  stats.unconverged_max_upper_w_m2 = std::max(stats.unconverged_max_upper_w_m2, upper);
  upper_grid.setValue(p, boundAsFloat(upper));
  stats.unconverged_min_m = glm::min(stats.unconverged_min_m, x);
  stats.unconverged_max_m = glm::max(stats.unconverged_max_m, x);
}

void noteNonFinite(FieldStats& stats, const Vec3& x) {
  if (stats.non_finite_points++ == 0) stats.non_finite_at_m = x;
}

std::unique_ptr<FieldGrids> makeGrids(const FieldSpec& spec) {
  auto g = std::make_unique<FieldGrids>();
  const auto transform = fieldTransform(spec);
  g->irradiance = openvdb::FloatGrid::create(0.0f);
  g->irradiance->setName("irradiance_w_m2");
  g->irradiance->setGridClass(openvdb::GRID_FOG_VOLUME);
  g->level = openvdb::FloatGrid::create(-1.0f);
  g->level->setName("refinement_level");
  g->status = openvdb::FloatGrid::create(0.0f);
  g->status->setName("status");
  g->upper = openvdb::FloatGrid::create(0.0f);
  g->upper->setName("irradiance_upper_w_m2");
  for (openvdb::GridBase* grid : {static_cast<openvdb::GridBase*>(g->irradiance.get()),
                                  static_cast<openvdb::GridBase*>(g->level.get()),
                                  static_cast<openvdb::GridBase*>(g->status.get()),
                                  static_cast<openvdb::GridBase*>(g->upper.get())}) {
    grid->setTransform(transform->copy());
  }
  return g;
}

void mergeInto(FieldGrids& into, FieldGrids& from) {
  into.irradiance->tree().merge(from.irradiance->tree());
  into.level->tree().merge(from.level->tree());
  into.status->tree().merge(from.status->tree());
  into.upper->tree().merge(from.upper->tree());
}

void finishStats(const FieldGrids& grids, FieldStats& stats) {
  stats.active_voxels = static_cast<std::int64_t>(grids.irradiance->activeVoxelCount());
  stats.grid_bytes = grids.irradiance->memUsage() + grids.level->memUsage() +
                     grids.status->memUsage() + grids.upper->memUsage();
}

void validateFieldSpec(const FieldSpec& spec) {
  const int b = spec.block_voxels;
  if (!(spec.voxel_m > 0.0) || !std::isfinite(spec.voxel_m) || b < 1 || (b & (b - 1)) != 0 ||
      !(spec.tolerance >= 0.0) || !std::isfinite(spec.tolerance) || !(spec.floor_w_m2 >= 0.0) ||
      !std::isfinite(spec.floor_w_m2) || !(spec.classify_above_w_m2 >= 0.0) ||
      !std::isfinite(spec.classify_above_w_m2)) {
    throw std::invalid_argument("FieldSpec out of range");
  }
  for (const double t : spec.hazard_thresholds_w_m2) {
    if (!(t > 0.0) || !std::isfinite(t))
      throw std::invalid_argument("FieldSpec: a hazard threshold out of range");
  }
  for (std::size_t a = 0; a < 3; ++a) {
    if (!(std::abs(glm::length(spec.axes[a]) - 1.0) < 1e-9) ||
        !(std::abs(glm::dot(spec.axes[a], spec.axes[(a + 1) % 3])) < 1e-9)) {
      throw std::invalid_argument("FieldSpec: axes must be unit and orthogonal");
    }
    if (spec.plane && a == 2) continue;
    if (!spec.radial && !(glm::dot(spec.max_m - spec.min_m, spec.axes[a]) > 0.0))
      throw std::invalid_argument("FieldSpec: empty box");
  }
  if (const std::shared_ptr<const SurfaceOffsets>& o = spec.surface) {
    const auto n = spec.nodes();
    bool finite = true;
    for (double x : o->offset_m) finite = finite && std::isfinite(x);
    if (!spec.plane || spec.radial || o->width != n[0] || o->height != n[1] ||
        o->offset_m.size() != static_cast<std::size_t>(n[0]) * static_cast<std::size_t>(n[1]) ||
        !finite) {
      throw std::invalid_argument("FieldSpec: surface offsets must cover the plane's lattice");
    }
  }
  if (const std::optional<RadialLattice>& r = spec.radial) {
    if (spec.plane || r->face_cells < b || r->face_cells % b != 0 || r->layers < b ||
        r->layers % b != 0 || !(r->near_m > 0.0) || !std::isfinite(r->near_m) ||
        !(r->ratio > 1.0) || !std::isfinite(r->layerDistance(r->layers)) || r->inner_layers < 0 ||
        r->inner_layers > r->layers ||
        (r->inner_layers > 0 && !(r->start_m > 0.0 && r->start_m < r->near_m))) {
      throw std::invalid_argument("FieldSpec: radial lattice out of range");
    }
  }
}

}  // namespace glint::field
