// The dense twin of the adaptive field: every lattice point integrated, for checking it.
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <chrono>
#include <cmath>
#include <vector>

#include "observers/detail/field_common.h"
#include "observers/field.h"

namespace glint {

using namespace field;

ObserverField computeDenseField(const FacetIntegrator& integrator, const FieldSpec& spec,
                                const ExcludedFn& excluded, WorkCounter* counter) {
  validateFieldSpec(spec);
  openvdb::initialize();
  const auto start = std::chrono::steady_clock::now();
  const Lattice lattice{spec.nodes()};
  if (counter != nullptr)
    counter->items_scheduled.fetch_add(static_cast<std::size_t>(lattice.count()));
  FieldStats stats;
  stats.nodes = lattice.n;
  stats.lattice_points = lattice.count();
  int finest = 0;
  for (int b = spec.block_voxels; b > 1; b /= 2) ++finest;
  stats.levels = finest;

  struct Local {
    ThreadGrids grids;
    IntegratorWorkspace workspace;
    FieldStats stats;
  };
  tbb::enumerable_thread_specific<Local> per_thread([&] {
    return Local{ThreadGrids(spec), {}, {}};
  });
  // One task per line of points along z: each thread's grid then holds whole lines.
  const std::int64_t lines = static_cast<std::int64_t>(lattice.n[0]) * lattice.n[1];
  tbb::parallel_for(std::int64_t{0}, lines, [&](std::int64_t line) {
    if (counter != nullptr && counter->stopRequested()) return;
    Local& local = per_thread.local();
    const int i = static_cast<int>(line / lattice.n[1]);
    const int j = static_cast<int>(line % lattice.n[1]);
    for (int k = 0; k < lattice.n[2]; ++k) {
      const openvdb::Coord p(i, j, k);
      const Vec3 x = spec.position(i, j, k);
      local.grids.level.setValue(p, static_cast<float>(finest));
      if (excluded && excluded(x)) {
        local.grids.status.setValue(p, statusCode(VoxelStatus::Excluded));
        ++local.stats.excluded_points;
        continue;
      }
      const ObserverResult r = integrator.adaptive(x, local.workspace);
      ++local.stats.evaluated_points;
      local.stats.evaluations += r.evaluations;
      if (counter != nullptr) {
        counter->items_done.fetch_add(1, std::memory_order_relaxed);
        counter->evaluations.fetch_add(r.evaluations, std::memory_order_relaxed);
      }
      if (!std::isfinite(r.irradiance_w_m2)) {
        noteNonFinite(local.stats, x);
        local.grids.status.setValue(p, statusCode(VoxelStatus::Unconverged));
        continue;
      }
      local.grids.irradiance.setValue(p, static_cast<float>(r.irradiance_w_m2));
      local.grids.status.setValue(
          p, statusCode(r.converged ? VoxelStatus::Evaluated : VoxelStatus::Unconverged));
      if (!r.converged) {
        noteUnconverged(local.stats, local.grids.upper, p, x, r.irradiance_w_m2,
                        r.error_estimate_w_m2);
      }
      if (r.irradiance_w_m2 > local.stats.peak_w_m2) {
        local.stats.peak_w_m2 = r.irradiance_w_m2;
        local.stats.peak_at_m = x;
      }
    }
  });
  if (counter != nullptr && counter->stopRequested()) throw WorkStopped();
  std::unique_ptr<FieldGrids> grids = makeGrids(spec);
  for (Local& local : per_thread) {
    mergeInto(*grids, *local.grids.grids);
    stats += local.stats;
  }
  finishStats(*grids, stats);
  std::vector<FieldBlock> blocks;
  forEachCoarseBlock(lattice, spec.block_voxels, [&](const Index3& o, int b) {
    blocks.push_back({o, {b, b, lattice.n[2] == 1 ? 2 : b}, 0, VoxelStatus::Evaluated});
  });
  stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return {spec, stats, std::move(grids), std::move(blocks)};
}

}  // namespace glint
