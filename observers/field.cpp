#include "observers/field.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <unordered_map>

#include "observers/block_check.h"
#include "observers/field_grids.h"

namespace glint {
namespace {

using field::Decision;
using field::Verdict;

using Index3 = std::array<int, 3>;
constexpr std::uint32_t kNoParent = std::numeric_limits<std::uint32_t>::max();

// Share of the floor that pruning may drop from a block's candidates: what every observer in
// it may miss, on top of the integrator's own error.
constexpr double kDropShareOfFloor = 0.25;
// Candidates are split to tighten block bounds down to this subdivision depth.
constexpr int kMaxBoundSplitDepth = 6;

struct Lattice {
  Index3 n;  // points per axis

  [[nodiscard]] std::uint64_t key(int i, int j, int k) const {
    return (static_cast<std::uint64_t>(i) * static_cast<std::uint64_t>(n[1]) +
            static_cast<std::uint64_t>(j)) *
               static_cast<std::uint64_t>(n[2]) +
           static_cast<std::uint64_t>(k);
  }
  [[nodiscard]] std::int64_t count() const { return static_cast<std::int64_t>(n[0]) * n[1] * n[2]; }
};

// Calls fn(origin, size) for every block of the coarsest level.
// A plane's lattice has one layer (n[2] == 1): its blocks are squares at k = 0.
template <class Fn>
void forEachCoarseBlock(const Lattice& lattice, int size, Fn&& fn) {
  const bool flat = lattice.n[2] == 1;
  for (int i = 0; i + 1 < lattice.n[0]; i += size)
    for (int j = 0; j + 1 < lattice.n[1]; j += size)
      for (int k = 0; flat ? k == 0 : k + 1 < lattice.n[2]; k += size) fn(Index3{i, j, k}, size);
}

// A block of the octree: lattice points o .. o + size on each axis. It owns the voxels
// [o, o + size) per axis, and the last lattice point of an axis where it touches the box's end.
struct Block {
  Index3 o;
  int size;
  int level;
  std::uint32_t parent;  // index into the previous level's blocks
};

struct PointValue {
  double irradiance_w_m2 = 0.0;
  double error_w_m2 = 0.0;  // the integrator's error estimate
  bool excluded = false;
  bool converged = true;
};

float code(VoxelStatus s) { return static_cast<float>(static_cast<int>(s)); }

void noteUnconverged(FieldStats& stats, const Vec3& x, double irradiance_w_m2, double error_w_m2) {
  ++stats.unconverged_points;
  // A NaN counts as +∞: it must never let the summary say "none of them can be hazardous".
  const double upper = irradiance_w_m2 + error_w_m2;
  if (!(upper <= stats.unconverged_max_upper_w_m2)) {
    stats.unconverged_max_upper_w_m2 =
        std::isnan(upper) ? std::numeric_limits<double>::infinity() : upper;
  }
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
  for (openvdb::GridBase* grid : {static_cast<openvdb::GridBase*>(g->irradiance.get()),
                                  static_cast<openvdb::GridBase*>(g->level.get()),
                                  static_cast<openvdb::GridBase*>(g->status.get())}) {
    grid->setTransform(transform->copy());
  }
  return g;
}

// Threads write into their own grids; the owned voxel ranges are disjoint, so merging them is
// a union.
void mergeInto(FieldGrids& into, FieldGrids& from) {
  into.irradiance->tree().merge(from.irradiance->tree());
  into.level->tree().merge(from.level->tree());
  into.status->tree().merge(from.status->tree());
}

// The voxels a block owns (see Block), as an inclusive OpenVDB box.
openvdb::CoordBBox ownedBox(const Block& b, const Lattice& lattice) {
  openvdb::Coord lo(b.o[0], b.o[1], b.o[2]), hi;
  for (int a = 0; a < 3; ++a) {
    const int end = b.o[a] + b.size;
    hi[a] = lattice.n[a] == 1 ? 0 : end == lattice.n[a] - 1 ? end : end - 1;
  }
  return {lo, hi};
}

struct ThreadGrids {
  std::unique_ptr<FieldGrids> grids;
  openvdb::FloatGrid::Accessor irradiance;
  openvdb::FloatGrid::Accessor level;
  openvdb::FloatGrid::Accessor status;

  explicit ThreadGrids(const FieldSpec& spec)
      : grids(makeGrids(spec)),
        irradiance(grids->irradiance->getAccessor()),
        level(grids->level->getAccessor()),
        status(grids->status->getAccessor()) {}
};

// The computation of one adaptive field, level by level: every block of a level is bounded,
// then the lattice points its survivors need are evaluated together (each once), then every
// block decides. Working a whole level at a time keeps each point's candidate list, and so the
// result, independent of thread scheduling.
class FieldBuilder {
 public:
  FieldBuilder(const FacetIntegrator& integrator, const FieldSpec& spec, const ExcludedFn& excluded,
               WorkCounter* counter)
      : integrator_(integrator),
        spec_(spec),
        excluded_(excluded),
        counter_(counter),
        lattice_{spec.nodes()},
        coarse_candidate_(integrator.target().facetCount(), 0) {
    const std::span<const Candidate> lit = integrator.candidates();
    Vec3 lo(std::numeric_limits<double>::infinity()), hi(-lo);
    for (std::size_t k = 0; k < lit.size(); ++k) {
      coarse_candidate_[lit[k].facet.coarse] = static_cast<std::uint32_t>(k);
      const Vec3 origin = integrator.target().objects[lit[k].object].origin_m;
      for (const Vec3& corner : lit[k].geometry.corner_m) {
        lo = glm::min(lo, origin + corner);
        hi = glm::max(hi, origin + corner);
      }
    }
    if (!lit.empty()) lit_centre_m_ = 0.5 * (lo + hi);
  }

  ObserverField run() {
    const auto start = std::chrono::steady_clock::now();
    stats_.nodes = lattice_.n;
    stats_.lattice_points = lattice_.count();
    std::vector<Block> blocks;
    forEachCoarseBlock(lattice_, spec_.block_voxels, [&](const Index3& o, int b) {
      blocks.push_back({o, b, 0, kNoParent});
    });

    std::vector<std::vector<Candidate>> parent_lists;
    std::vector<double> parent_dropped;
    while (!blocks.empty()) {
      stats_.levels = blocks.front().level;
      std::vector<std::vector<Candidate>> lists(blocks.size());
      std::vector<RegionBound> bounds(blocks.size());
      boundBlocks(blocks, parent_lists, parent_dropped, lists, bounds);
      throwIfStopped();
      evaluateSamples(blocks, lists, bounds);
      throwIfStopped();
      const std::vector<Decision> decisions = decide(blocks, bounds);

      std::vector<Block> children;
      std::vector<std::vector<Candidate>> child_parent_lists;
      std::vector<double> child_parent_dropped;
      for (std::size_t i = 0; i < blocks.size(); ++i) {
        const Block& blk = blocks[i];
        switch (decisions[i].verdict) {
          case Verdict::Skip:
            ++stats_.blocks_skipped;
            final_.push_back({blk, decisions[i]});
            break;
          case Verdict::Accept:
            ++stats_.blocks_accepted;
            if (decisions[i].power > 0) ++stats_.blocks_accepted_spread;
            final_.push_back({blk, decisions[i]});
            break;
          case Verdict::Finest:
            ++stats_.blocks_finest;
            final_.push_back({blk, decisions[i]});
            break;
          case Verdict::Refine: {
            ++stats_.blocks_refined;
            const auto parent = static_cast<std::uint32_t>(child_parent_lists.size());
            child_parent_lists.push_back(std::move(lists[i]));
            child_parent_dropped.push_back(bounds[i].dropped_w_m2);
            const int h = blk.size / 2;
            for (int c = 0; c < 8; ++c) {
              children.push_back(
                  {{blk.o[0] + h * (c >> 2), blk.o[1] + h * ((c >> 1) & 1), blk.o[2] + h * (c & 1)},
                   h,
                   blk.level + 1,
                   parent});
            }
            break;
          }
        }
      }
      blocks = std::move(children);
      parent_lists = std::move(child_parent_lists);
      parent_dropped = std::move(child_parent_dropped);
    }

    std::unique_ptr<FieldGrids> grids = writeGrids();
    throwIfStopped();
    std::vector<FieldBlock> blocks_out;
    blocks_out.reserve(final_.size());
    for (const FinalBlock& f : final_) {
      const Verdict v = f.decision.verdict;
      const VoxelStatus status = v == Verdict::Skip     ? VoxelStatus::BelowFloor
                                 : v == Verdict::Accept ? VoxelStatus::Interpolated
                                                        : VoxelStatus::Evaluated;
      blocks_out.push_back({f.block.o, f.block.size, f.block.level, status});
    }
    stats_.seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return {spec_, stats_, std::move(grids), std::move(blocks_out)};
  }

 private:
  // The run's watcher asked to stop (memory): the loops skip their remaining items, and the
  // builder leaves between them; nothing half-computed is returned.
  [[nodiscard]] bool stopRequested() const {
    return counter_ != nullptr && counter_->stopRequested();
  }
  void throwIfStopped() const {
    if (stopRequested()) throw WorkStopped();
  }

  struct FinalBlock {
    Block block;
    Decision decision;
  };

  // r^power, r the distance of lattice point (i, j, k) from the lit facets' centre.
  [[nodiscard]] double spreadWeight(int i, int j, int k, int power) const {
    if (power == 0) return 1.0;
    const double r = glm::length(spec_.position(i, j, k) - lit_centre_m_);
    return power == 1 ? r : r * r;
  }

  // Whether E·r^p may be interpolated over block b for p > 0: only where the block keeps clear
  // of the centre by its own diagonal, so that no weight is near 0 and r varies smoothly.
  [[nodiscard]] bool farFromTarget(const Block& b) const {
    const double diagonal_m = std::sqrt(3.0) * spec_.voxel_m * b.size;
    return glm::length(centre(b) - lit_centre_m_) > 1.5 * diagonal_m;
  }

  [[nodiscard]] bool flat() const { return lattice_.n[2] == 1; }

  // Lattice point (di, dj, dk) of block b; a plane's blocks have no depth, so dk maps to its
  // one layer and the 3×3×3 samples of the checks repeat the 3×3 ones: the trilinear checks
  // and fill then are bilinear ones, exactly.
  [[nodiscard]] Index3 at(const Block& b, int di, int dj, int dk) const {
    return {b.o[0] + di, b.o[1] + dj, flat() ? 0 : b.o[2] + dk};
  }
  [[nodiscard]] std::uint64_t keyAt(const Block& b, int di, int dj, int dk) const {
    const Index3 p = at(b, di, dj, dk);
    return lattice_.key(p[0], p[1], p[2]);
  }

  [[nodiscard]] Vec3 centre(const Block& b) const {
    const double half = 0.5 * b.size;
    const std::array<Vec3, 3>& e = spec_.axes;
    return spec_.position(b.o[0], b.o[1], b.o[2]) +
           spec_.voxel_m * half * (e[0] + e[1] + (flat() ? Vec3(0.0) : e[2]));
  }

  void boundBlocks(const std::vector<Block>& blocks,
                   const std::vector<std::vector<Candidate>>& parent_lists,
                   const std::vector<double>& parent_dropped,
                   std::vector<std::vector<Candidate>>& lists, std::vector<RegionBound>& bounds) {
    tbb::enumerable_thread_specific<std::int64_t> bound_evaluations(0);
    tbb::parallel_for(std::size_t{0}, blocks.size(), [&](std::size_t i) {
      if (stopRequested()) return;
      const Block& b = blocks[i];
      const bool root = b.parent == kNoParent;
      const std::span<const Candidate> inherited =
          root ? integrator_.candidates() : std::span<const Candidate>(parent_lists[b.parent]);
      RegionOptions options;
      options.drop_allowance_w_m2 = kDropShareOfFloor * spec_.floor_w_m2;
      options.sample_spacing_m = spec_.voxel_m * std::max(1, b.size / 2);
      options.max_split_depth = kMaxBoundSplitDepth;
      const double radius = 0.5 * std::sqrt(flat() ? 2.0 : 3.0) * spec_.voxel_m * b.size;
      bounds[i] = integrator_.boundRegion(centre(b), radius, inherited,
                                          root ? 0.0 : parent_dropped[b.parent], options, lists[i]);
      bound_evaluations.local() += bounds[i].bound_evaluations;
    });
    for (std::int64_t n : bound_evaluations) stats_.bound_evaluations += n;
  }

  // What the points of a block integrate over: the whole coarse facets of which its bound kept
  // any piece, in the order of the block's list. The pieces were split to tighten the block's
  // bound; handed to the integrator they would make every point start finer than it needs,
  // since each piece costs an evaluation before the integrator can see that a smooth facet
  // wants no more. (Measured on bench/scenes/sphere.json at 0.2 m: 4.1e8 evaluations with the
  // pieces, 9.1e7 with their coarse facets; dense 9.4e7. The cylinder is unchanged.)
  [[nodiscard]] std::vector<Candidate> integrationList(std::span<const Candidate> kept) const {
    const std::span<const Candidate> lit = integrator_.candidates();
    std::vector<char> taken(lit.size(), 0);
    std::vector<Candidate> out;
    for (const Candidate& c : kept) {
      const std::uint32_t k = coarse_candidate_[c.facet.coarse];
      if (taken[k] != 0) continue;
      taken[k] = 1;
      out.push_back(lit[k]);
    }
    return out;
  }

  // Only a bound proven at most the floor skips a block; NaN never does (and cannot occur:
  // RegionBound is never NaN).
  [[nodiscard]] bool skipped(const RegionBound& bound) const {
    return bound.upper_w_m2 <= spec_.floor_w_m2;
  }

  // Evaluates the sample lattice points of every block not skipped that no earlier level
  // evaluated; a point shared by several blocks takes the candidates of the first.
  void evaluateSamples(const std::vector<Block>& blocks,
                       const std::vector<std::vector<Candidate>>& lists,
                       const std::vector<RegionBound>& bounds) {
    std::vector<std::pair<std::uint64_t, std::uint32_t>> wanted;  // (point, block)
    for (std::size_t i = 0; i < blocks.size(); ++i) {
      if (skipped(bounds[i])) continue;
      const Block& b = blocks[i];
      field::forEachSample(b.size, [&](int di, int dj, int dk) {
        const std::uint64_t key = keyAt(b, di, dj, dk);
        if (!values_.contains(key)) wanted.emplace_back(key, static_cast<std::uint32_t>(i));
      });
    }
    tbb::parallel_sort(wanted.begin(), wanted.end());
    wanted.erase(std::unique(wanted.begin(), wanted.end(),
                             [](const auto& x, const auto& y) { return x.first == y.first; }),
                 wanted.end());

    if (counter_ != nullptr) counter_->items_scheduled.fetch_add(wanted.size());
    std::vector<char> sampled(blocks.size(), 0);
    for (const auto& [key, block] : wanted) sampled[block] = 1;
    std::vector<std::vector<Candidate>> point_lists(blocks.size());
    tbb::parallel_for(std::size_t{0}, blocks.size(), [&](std::size_t i) {
      if (sampled[i] != 0) point_lists[i] = integrationList(lists[i]);
    });
    std::vector<PointValue> results(wanted.size());
    std::vector<std::int64_t> evaluations(wanted.size(), 0);
    tbb::enumerable_thread_specific<IntegratorWorkspace> workspaces;
    tbb::parallel_for(std::size_t{0}, wanted.size(), [&](std::size_t w) {
      if (stopRequested()) return;
      const std::uint64_t key = wanted[w].first;
      const auto nk = static_cast<std::uint64_t>(lattice_.n[2]);
      const auto nj = static_cast<std::uint64_t>(lattice_.n[1]);
      const int k = static_cast<int>(key % nk);
      const int j = static_cast<int>((key / nk) % nj);
      const int i = static_cast<int>(key / nk / nj);
      const Vec3 x = spec_.position(i, j, k);
      if (excluded_ && excluded_(x)) {
        results[w].excluded = true;
        return;
      }
      const ObserverResult r =
          integrator_.adaptive(x, point_lists[wanted[w].second], workspaces.local());
      results[w].irradiance_w_m2 = r.irradiance_w_m2;
      results[w].error_w_m2 = r.error_estimate_w_m2;
      results[w].converged = r.converged;
      evaluations[w] = r.evaluations;
      if (counter_ != nullptr) {
        counter_->items_done.fetch_add(1, std::memory_order_relaxed);
        counter_->evaluations.fetch_add(r.evaluations, std::memory_order_relaxed);
      }
    });
    for (std::size_t w = 0; w < wanted.size(); ++w) {
      values_.emplace(wanted[w].first, results[w]);
      if (results[w].excluded) {
        ++stats_.excluded_points;
        continue;
      }
      ++stats_.evaluated_points;
      stats_.evaluations += evaluations[w];
    }
  }

  std::vector<Decision> decide(const std::vector<Block>& blocks,
                               const std::vector<RegionBound>& bounds) const {
    std::vector<Decision> decisions(blocks.size());
    tbb::parallel_for(std::size_t{0}, blocks.size(), [&](std::size_t i) {
      decisions[i] = decideBlock(blocks[i], bounds[i]);
    });
    return decisions;
  }

  [[nodiscard]] Decision decideBlock(const Block& b, const RegionBound& bound) const {
    if (const std::optional<Decision> d = field::decideByBound(bound, b.size, spec_.floor_w_m2)) {
      return *d;
    }
    field::BlockSamples samples;
    samples.far_from_target = farFromTarget(b);
    field::forEachSample(b.size, [&](int di, int dj, int dk) {
      const Index3 p = at(b, di, dj, dk);
      const PointValue& v = values_.at(lattice_.key(p[0], p[1], p[2]));
      const std::size_t s = samples.count++;
      samples.excluded = samples.excluded || v.excluded;
      samples.irradiance_w_m2[s] = v.irradiance_w_m2;
      for (std::size_t k = 0; k < field::kInterpolationPowers.size(); ++k) {
        const int power = field::kInterpolationPowers[k];
        samples.weight[k][s] =
            power == 0 || samples.far_from_target ? spreadWeight(p[0], p[1], p[2], power) : 1.0;
      }
    });
    return field::decideBySamples(samples, bound, spec_.tolerance, spec_.floor_w_m2);
  }

  std::unique_ptr<FieldGrids> writeGrids() {
    tbb::enumerable_thread_specific<ThreadGrids> per_thread([&] { return ThreadGrids(spec_); });
    tbb::enumerable_thread_specific<std::int64_t> interpolated(0), below(0);
    tbb::parallel_for(std::size_t{0}, final_.size(), [&](std::size_t f) {
      const Block& b = final_[f].block;
      ThreadGrids& t = per_thread.local();
      const openvdb::CoordBBox box = ownedBox(b, lattice_);
      switch (final_[f].decision.verdict) {
        case Verdict::Skip:
          t.grids->status->tree().fill(box, code(VoxelStatus::BelowFloor), true);
          t.grids->level->tree().fill(box, static_cast<float>(b.level), true);
          below.local() += static_cast<std::int64_t>(box.volume());
          break;
        case Verdict::Finest:
          t.grids->level->tree().fill(box, static_cast<float>(b.level), true);
          break;  // its points are all samples: written below
        case Verdict::Accept: {
          t.grids->level->tree().fill(box, static_cast<float>(b.level), true);
          const int h = b.size / 2;
          const int power = final_[f].decision.power;
          std::array<double, 27> v{};  // E·r^power at the 3×3×3 lattice
          for (int a = 0; a < 3; ++a)
            for (int c = 0; c < 3; ++c)
              for (int e = 0; e < 3; ++e) {
                const Index3 p = at(b, a * h, c * h, e * h);
                v[static_cast<std::size_t>(9 * a + 3 * c + e)] =
                    values_.at(lattice_.key(p[0], p[1], p[2])).irradiance_w_m2 *
                    spreadWeight(p[0], p[1], p[2], power);
              }
          // Each octant from its own corners: the finer samples the check compared against.
          for (auto it = box.begin(); it; ++it) {
            const openvdb::Coord& p = *it;
            std::array<int, 3> oct{};
            std::array<double, 3> t3{};
            for (std::size_t a = 0; a < 3; ++a) {
              const int local = p[static_cast<int>(a)] - b.o[a];  // 0 along a plane's normal
              oct[a] = std::min(local / h, 1);
              t3[a] = static_cast<double>(local - oct[a] * h) / h;
            }
            const double value =
                field::octantFill(v, oct, t3) / spreadWeight(p[0], p[1], p[2], power);
            t.irradiance.setValue(p, static_cast<float>(value));
            t.status.setValue(p, code(VoxelStatus::Interpolated));
            ++interpolated.local();
          }
          break;
        }
        case Verdict::Refine:
          break;
      }
    });
    std::unique_ptr<FieldGrids> grids = makeGrids(spec_);
    for (ThreadGrids& t : per_thread) mergeInto(*grids, *t.grids);
    for (std::int64_t n : interpolated) stats_.interpolated_points += n;
    for (std::int64_t n : below) stats_.below_floor_points += n;

    // Every sample, wherever its block ended up, with its own value.
    auto irradiance = grids->irradiance->getAccessor();
    auto status = grids->status->getAccessor();
    const auto nk = static_cast<std::uint64_t>(lattice_.n[2]);
    const auto nj = static_cast<std::uint64_t>(lattice_.n[1]);
    for (const auto& [key, value] : values_) {
      const openvdb::Coord p(static_cast<int>(key / nk / nj), static_cast<int>((key / nk) % nj),
                             static_cast<int>(key % nk));
      const float before = status.getValue(p);
      if (before == code(VoxelStatus::Interpolated)) --stats_.interpolated_points;
      if (before == code(VoxelStatus::BelowFloor)) --stats_.below_floor_points;
      if (value.excluded) {
        status.setValue(p, code(VoxelStatus::Excluded));
        irradiance.setValueOff(p, 0.0f);
        continue;
      }
      if (!std::isfinite(value.irradiance_w_m2)) {
        noteNonFinite(stats_, spec_.position(p[0], p[1], p[2]));
        status.setValue(p, code(VoxelStatus::Unconverged));
        irradiance.setValueOff(p, 0.0f);
        continue;
      }
      status.setValue(p, code(value.converged ? VoxelStatus::Evaluated : VoxelStatus::Unconverged));
      if (!value.converged) {
        noteUnconverged(stats_, spec_.position(p[0], p[1], p[2]), value.irradiance_w_m2,
                        value.error_w_m2);
      }
      irradiance.setValue(p, static_cast<float>(value.irradiance_w_m2));
      if (value.irradiance_w_m2 > stats_.peak_w_m2) {
        stats_.peak_w_m2 = value.irradiance_w_m2;
        stats_.peak_at_m = spec_.position(p[0], p[1], p[2]);
      }
    }
    finishStats(*grids, stats_);
    return grids;
  }

 public:
  static void finishStats(const FieldGrids& grids, FieldStats& stats) {
    stats.active_voxels = static_cast<std::int64_t>(grids.irradiance->activeVoxelCount());
    stats.grid_bytes =
        grids.irradiance->memUsage() + grids.level->memUsage() + grids.status->memUsage();
  }

 private:
  const FacetIntegrator& integrator_;
  const FieldSpec& spec_;
  const ExcludedFn& excluded_;
  WorkCounter* counter_;
  Lattice lattice_;
  std::vector<std::uint32_t> coarse_candidate_;  // coarse facet → index of its lit candidate
  Vec3 lit_centre_m_{0.0};  // centre of the lit facets' box: where the light spreads from
  FieldStats stats_;
  std::unordered_map<std::uint64_t, PointValue> values_;  // every sample, evaluated once
  std::vector<FinalBlock> final_;
};

void validate(const FieldSpec& spec) {
  const int b = spec.block_voxels;
  if (!(spec.voxel_m > 0.0) || !std::isfinite(spec.voxel_m) || b < 1 || (b & (b - 1)) != 0 ||
      !(spec.tolerance >= 0.0) || !std::isfinite(spec.tolerance) || !(spec.floor_w_m2 >= 0.0) ||
      !std::isfinite(spec.floor_w_m2)) {
    throw std::invalid_argument("FieldSpec out of range");
  }
  for (std::size_t a = 0; a < 3; ++a) {
    if (!(std::abs(glm::length(spec.axes[a]) - 1.0) < 1e-9) ||
        !(std::abs(glm::dot(spec.axes[a], spec.axes[(a + 1) % 3])) < 1e-9)) {
      throw std::invalid_argument("FieldSpec: axes must be unit and orthogonal");
    }
    if (spec.plane && a == 2) continue;
    if (!(glm::dot(spec.max_m - spec.min_m, spec.axes[a]) > 0.0))
      throw std::invalid_argument("FieldSpec: empty box");
  }
}

}  // namespace

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
      if (q.x() < 0 || q.y() < 0 || q.z() < 0 || q.x() >= n[0] || q.y() >= n[1] ||
          q.z() >= n[2]) {
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

std::array<int, 3> FieldSpec::nodes() const {
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

ObserverField::ObserverField(FieldSpec spec, FieldStats stats, std::unique_ptr<FieldGrids> grids,
                             std::vector<FieldBlock> blocks)
    : spec_(spec), stats_(stats), grids_(std::move(grids)), blocks_(std::move(blocks)) {}
ObserverField::~ObserverField() = default;
ObserverField::ObserverField(ObserverField&&) noexcept = default;
ObserverField& ObserverField::operator=(ObserverField&&) noexcept = default;

double ObserverField::irradiance(int i, int j, int k) const {
  return grids_->irradiance->tree().getValue(openvdb::Coord(i, j, k));
}
std::vector<float> ObserverField::irradianceLattice() const {
  std::size_t outside = 0;
  return activeOnLattice(*grids_->irradiance, spec_.nodes(), outside);
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

ObserverField::Region ObserverField::regionAbove(double threshold_w_m2,
                                                const Vec3& from_m) const {
  Region r;
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
    blocks *= spec.plane && a == 2 ? 1.0 : std::ceil(static_cast<double>(cells) / spec.block_voxels);
  }
  const double bytes = dense ? kDenseBytesPerPoint * points : kAdaptiveBytesPerCoarseBlock * blocks;
  return bytes >= 1.8e19 ? std::numeric_limits<std::uint64_t>::max()
                         : static_cast<std::uint64_t>(bytes);
}

ObserverField computeField(const FacetIntegrator& integrator, const FieldSpec& spec,
                           const ExcludedFn& excluded, WorkCounter* counter) {
  validate(spec);
  openvdb::initialize();
  return FieldBuilder(integrator, spec, excluded, counter).run();
}

ObserverField computeDenseField(const FacetIntegrator& integrator, const FieldSpec& spec,
                                const ExcludedFn& excluded, WorkCounter* counter) {
  validate(spec);
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
        local.grids.status.setValue(p, code(VoxelStatus::Excluded));
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
        local.grids.status.setValue(p, code(VoxelStatus::Unconverged));
        continue;
      }
      local.grids.irradiance.setValue(p, static_cast<float>(r.irradiance_w_m2));
      local.grids.status.setValue(
          p, code(r.converged ? VoxelStatus::Evaluated : VoxelStatus::Unconverged));
      if (!r.converged) noteUnconverged(local.stats, x, r.irradiance_w_m2, r.error_estimate_w_m2);
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
    stats.evaluated_points += local.stats.evaluated_points;
    stats.excluded_points += local.stats.excluded_points;
    stats.evaluations += local.stats.evaluations;
    stats.unconverged_points += local.stats.unconverged_points;
    if (stats.non_finite_points == 0) stats.non_finite_at_m = local.stats.non_finite_at_m;
    stats.non_finite_points += local.stats.non_finite_points;
    stats.unconverged_min_m = glm::min(stats.unconverged_min_m, local.stats.unconverged_min_m);
    stats.unconverged_max_m = glm::max(stats.unconverged_max_m, local.stats.unconverged_max_m);
    stats.unconverged_max_upper_w_m2 =
        std::max(stats.unconverged_max_upper_w_m2, local.stats.unconverged_max_upper_w_m2);
    if (local.stats.peak_w_m2 > stats.peak_w_m2) {
      stats.peak_w_m2 = local.stats.peak_w_m2;
      stats.peak_at_m = local.stats.peak_at_m;
    }
  }
  FieldBuilder::finishStats(*grids, stats);
  std::vector<FieldBlock> blocks;
  forEachCoarseBlock(lattice, spec.block_voxels, [&](const Index3& o, int b) {
    blocks.push_back({o, b, 0, VoxelStatus::Evaluated});
  });
  stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return {spec, stats, std::move(grids), std::move(blocks)};
}

}  // namespace glint
