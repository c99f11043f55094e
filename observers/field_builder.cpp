// The adaptive observer field: blocks bounded, sampled and checked level by level.
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <mutex>
#include <numeric>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <unordered_map>

#include "facets/lit_ball.h"
#include "observers/block_check.h"
#include "observers/detail/block_geometry.h"
#include "observers/detail/field_common.h"
#include "observers/detail/piece_pool.h"
#include "observers/field.h"

namespace glint {
namespace {

using namespace field;

constexpr std::uint32_t kNoParent = std::numeric_limits<std::uint32_t>::max();

// A block's candidates: indices into its level's PiecePool (or, for a point's integration,
// into the integrator's lit candidates).
using PieceList = std::vector<std::uint32_t>;

// Share of the floor that pruning may drop from a block's candidates: what every observer in
// it may miss, on top of the integrator's own error.
constexpr double kDropShareOfFloor = 0.25;

// A block of the tree: lattice points o .. o + size[a] along each axis a. It owns the voxels
// [o, o + size) per axis, and the last lattice point of an axis where it touches the box's end.
// A plane's blocks have size 2 along its normal, which at() folds onto its one layer.
struct Block {
  Index3 o;
  BlockSize size;
  int level;
  std::uint32_t parent;  // index into the previous level's blocks
};

struct PointValue {
  double irradiance_w_m2 = 0.0;
  double error_w_m2 = 0.0;  // the integrator's error estimate
  bool excluded = false;
  bool converged = true;
};

// The voxels a block owns (see Block), as an inclusive OpenVDB box.
openvdb::CoordBBox ownedBox(const Block& b, const Lattice& lattice) {
  return field::ownedBox(b.o, b.size, lattice);
}

// The computation of one adaptive field, level by level: every block of a level is bounded,
// then the lattice points its survivors need are evaluated together (each once), then every
// block decides. Working a whole level at a time keeps each point's candidate list, and so the
// result, independent of thread scheduling.
class FieldBuilder {
 public:
  FieldBuilder(const FacetIntegrator& integrator, const FieldSpec& spec, const ExcludedFn& excluded,
               WorkCounter* counter, PointExchange* exchange)
      : classifying_(classifyingAccuracy(integrator, spec)),
        integrator_(classifying_ ? *classifying_ : integrator),
        spec_(spec),
        excluded_(excluded),
        counter_(counter),
        exchange_(exchange != nullptr && exchange->size() > 1 ? exchange : nullptr),
        lattice_{spec.nodes()},
        geometry_(spec_),
        coarse_candidate_(integrator.target().facetCount(), 0),
        lit_centre_m_(litBall(integrator).centre_m) {
    const std::span<const Candidate> lit = integrator.candidates();
    for (std::size_t k = 0; k < lit.size(); ++k) {
      coarse_candidate_[lit[k].facet.coarse] = static_cast<std::uint32_t>(k);
    }
  }

  ObserverField run() {
    const auto start = std::chrono::steady_clock::now();
    stats_.nodes = lattice_.n;
    stats_.lattice_points = lattice_.count();
    std::vector<Block> blocks;
    forEachCoarseBlock(lattice_, spec_.block_voxels, [&](const Index3& o, int b) {
      blocks.push_back({o, {b, b, flat() ? 2 : b}, 0, kNoParent});
    });

    // Each level's pieces live in that level's pool; its blocks hold indices into it. The
    // parents' pool is dropped once the level is bounded.
    auto parent_pool = std::make_unique<PiecePool>();
    std::vector<PieceList> parent_lists;
    std::vector<double> parent_dropped;
    while (!blocks.empty()) {
      stats_.levels = blocks.front().level;
      auto pool = std::make_unique<PiecePool>();
      std::vector<PieceList> lists(blocks.size());
      std::vector<BallBound> bounds(blocks.size());
      boundBlocks(blocks, *parent_pool, parent_lists, parent_dropped, *pool, lists, bounds);
      parent_pool.reset();
      parent_lists.clear();
      // Shared with other processes, a stop is agreed at the exchange of the level's points:
      // leaving before it would leave them waiting.
      if (exchange_ == nullptr) throwIfStopped();
      evaluateSamples(blocks, *pool, lists, bounds);
      throwIfStopped();
      const std::vector<Decision> decisions = decide(blocks, bounds);

      std::vector<Block> children;
      std::vector<PieceList> child_parent_lists;
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
            if (unevaluated(blk, bounds[i])) {
              final_.push_back({blk, decisions[i],
                                Unresolved{std::numeric_limits<double>::infinity(),
                                           bounds[i].resolving_spacing_m},
                                true});
            } else {
              final_.push_back({blk, decisions[i], unresolvedBound(blk, bounds[i])});
            }
            break;
          case Verdict::Refine: {
            ++stats_.blocks_refined;
            const auto parent = static_cast<std::uint32_t>(child_parent_lists.size());
            child_parent_lists.push_back(std::move(lists[i]));
            child_parent_dropped.push_back(bounds[i].dropped_w_m2);
            // Halved along the axes the check chose (never a plane's normal, whose size 2 is
            // exact): 2, 4 or 8 children.
            const std::uint8_t split =
                spec_.anisotropic ? decisions[i].split : splittableAxes(blk.size);
            BlockSize child_size = blk.size;
            for (std::size_t a = 0; a < 3; ++a) {
              if ((split & (4 >> a)) != 0) child_size[a] /= 2;
            }
            for (int c = 0; c < 8; ++c) {
              if ((c & ~split) != 0) continue;  // an offset along an axis not halved
              children.push_back(
                  {{blk.o[0] + child_size[0] * (c >> 2), blk.o[1] + child_size[1] * ((c >> 1) & 1),
                    blk.o[2] + child_size[2] * (c & 1)},
                   child_size,
                   blk.level + 1,
                   parent});
            }
            break;
          }
        }
      }
      blocks = std::move(children);
      parent_pool = std::move(pool);
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
                                 : f.unresolved         ? VoxelStatus::Unresolved
                                                        : VoxelStatus::Evaluated;
      blocks_out.push_back({f.block.o, f.block.size, f.block.level, status,
                            f.unresolved ? f.unresolved->bound_w_m2 : 0.0});
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

  // A finest block that may hide a glint narrower than its lattice (narrowGlintBound()).
  struct Unresolved {
    double bound_w_m2 = 0.0;  // narrowGlintBound() (+∞ where the ball reaches the target)
    double resolving_spacing_m = 0.0;  // BallBound::resolving_spacing_m
  };
  struct FinalBlock {
    Block block;
    Decision decision;
    std::optional<Unresolved> unresolved = std::nullopt;
    bool unevaluated = false;  // see unevaluated()
  };
  // What a finest block's bound says that its samples (all its lattice points) cannot.
  [[nodiscard]] std::optional<Unresolved> unresolvedBound(const Block& b,
                                                          const BallBound& bound) const {
    double largest = 0.0;
    field::forEachSample(b.size, [&](int di, int dj, int dk) {
      const PointValue& v = values_.at(keyAt(b, di, dj, dk));
      if (!v.excluded) largest = std::max(largest, v.irradiance_w_m2);
    });
    const std::optional<double> most = field::narrowGlintBound(
        bound, largest, spec_.tolerance, spec_.floor_w_m2, spec_.lowestHazardThresholdW_m2());
    if (!most) return std::nullopt;
    return Unresolved{*most, bound.resolving_spacing_m};
  }

  // The samples of block @p b, as the checks read them (field::BlockSamples).
  [[nodiscard]] field::BlockSamples samplesOf(const Block& b) const {
    field::BlockSamples samples;
    samples.far_from_target = farFromTarget(b);
    field::forEachSample(b.size, [&](int di, int dj, int dk) {
      const Index3 p = at(b, di, dj, dk);
      const PointValue& v = values_.at(lattice_.key(p[0], p[1], p[2]));
      const std::size_t s = samples.count++;
      samples.excluded = samples.excluded || v.excluded;
      samples.irradiance_w_m2[s] = v.irradiance_w_m2;
      if (samples.far_from_target) samples.distance_m[s] = litDistance(p[0], p[1], p[2]);
    });
    return samples;
  }

  // Whether a point of value @p value_w_m2 in a block whose bound is @p bound_w_m2 may be judged
  // wrongly by its value: a threshold lies above the value and within the bound (any, where
  // there are no thresholds). Each threshold counts, not only the lowest: a point between the
  // lowest and the MPE, beside a glint the lattice cannot see, may be above the MPE.
  [[nodiscard]] bool boundMayCross(double value_w_m2, double bound_w_m2) const {
    if (spec_.hazard_thresholds_w_m2.empty()) return true;
    return std::any_of(spec_.hazard_thresholds_w_m2.begin(), spec_.hazard_thresholds_w_m2.end(),
                       [&](double t) { return value_w_m2 < t && !(bound_w_m2 < t); });
  }

  // Marks status Unresolved the evaluated points of the unresolved blocks whose value lies below
  // a threshold their block's bound reaches (all of them without thresholds), and counts them.
  void markUnresolved(FieldGrids& grids) {
    auto irradiance = grids.irradiance->getAccessor();
    auto status = grids.status->getAccessor();
    for (FinalBlock& f : final_) {
      if (!f.unresolved) continue;
      std::int64_t marked = 0;
      const openvdb::CoordBBox box = ownedBox(f.block, lattice_);
      for (auto it = box.begin(); it; ++it) {
        const openvdb::Coord& p = *it;
        const float code = status.getValue(p);
        // An unevaluated block's points were filled Unresolved, but for those that are samples
        // of its neighbours.
        const bool filled = f.unevaluated && code == statusCode(VoxelStatus::Unresolved);
        if (!filled) {
          if (code != statusCode(VoxelStatus::Evaluated)) continue;
          if (!boundMayCross(static_cast<double>(irradiance.getValue(p)), f.unresolved->bound_w_m2))
            continue;
          status.setValue(p, statusCode(VoxelStatus::Unresolved));
        }
        const Vec3 x = spec_.position(p[0], p[1], p[2]);
        stats_.unresolved_min_m = glm::min(stats_.unresolved_min_m, x);
        stats_.unresolved_max_m = glm::max(stats_.unresolved_max_m, x);
        ++marked;
      }
      if (marked == 0) {  // every point already at the thresholds: the samples say it all
        f.unresolved.reset();
        continue;
      }
      stats_.unresolved_points += marked;
      ++stats_.unresolved_blocks;
      const Unresolved& u = *f.unresolved;
      if (!std::isfinite(u.bound_w_m2)) {
        ++stats_.unresolved_unbounded_blocks;
      } else if (u.bound_w_m2 > stats_.unresolved_max_bound_w_m2) {
        stats_.unresolved_max_bound_w_m2 = u.bound_w_m2;
        stats_.unresolved_bound_at_m = centre(f.block);
      }
      if (std::isfinite(u.resolving_spacing_m) && u.resolving_spacing_m > 0.0 &&
          (stats_.unresolved_resolving_voxel_m == 0.0 ||
           u.resolving_spacing_m < stats_.unresolved_resolving_voxel_m)) {
        stats_.unresolved_resolving_voxel_m = u.resolving_spacing_m;
      }
    }
  }

  // r^power, r the distance of lattice point (i, j, k) from the lit facets' centre.
  [[nodiscard]] double spreadWeight(int i, int j, int k, int power) const {
    return power == 0 ? 1.0 : field::spreadWeight(litDistance(i, j, k), power);
  }
  // The distance of lattice point (i, j, k) from the lit facets' centre.
  [[nodiscard]] double litDistance(int i, int j, int k) const {
    return glm::length(spec_.position(i, j, k) - lit_centre_m_);
  }

  // Whether E·r^p may be interpolated over block b for p > 0: only where the block keeps clear
  // of the centre by its own diagonal, so that no weight is near 0 and r varies smoothly.
  [[nodiscard]] bool farFromTarget(const Block& b) const {
    // A radial lattice about the lit centre, beyond its even inner layers: r is the layer's
    // distance times a smooth factor of the direction, never near 0, wherever the block lies.
    if (spec_.radial && b.o[2] >= spec_.radial->inner_layers &&
        glm::length(spec_.radial->centre_m - lit_centre_m_) <= 1e-9 * spec_.radial->near_m) {
      return true;
    }
    const double diagonal_m = 2.0 * radius(b);
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

  [[nodiscard]] Vec3 centre(const Block& b) const { return geometry_.centre(b.o, b.size); }
  [[nodiscard]] double radius(const Block& b) const { return geometry_.radius(b.o, b.size); }

  // Bounds every block of a level from its parent's pieces (@p parent_pool, @p parent_lists),
  // interning the pieces each keeps into @p pool and their indices into @p lists.
  void boundBlocks(const std::vector<Block>& blocks, const PiecePool& parent_pool,
                   const std::vector<PieceList>& parent_lists,
                   const std::vector<double>& parent_dropped, PiecePool& pool,
                   std::vector<PieceList>& lists, std::vector<BallBound>& bounds) {
    tbb::enumerable_thread_specific<std::int64_t> bound_evaluations(0);
    struct Scratch {
      std::vector<Candidate> inherited, kept;
    };
    tbb::enumerable_thread_specific<Scratch> scratch;
    tbb::parallel_for(std::size_t{0}, blocks.size(), [&](std::size_t i) {
      if (stopRequested()) return;
      const Block& b = blocks[i];
      const bool root = b.parent == kNoParent;
      Scratch& s = scratch.local();
      if (!root) {
        s.inherited.clear();
        for (const std::uint32_t p : parent_lists[b.parent]) s.inherited.push_back(parent_pool[p]);
      }
      const std::span<const Candidate> inherited =
          root ? integrator_.candidates() : std::span<const Candidate>(s.inherited);
      BallBoundOptions options;
      options.drop_allowance_w_m2 = kDropShareOfFloor * spec_.floor_w_m2;
      options.sample_spacing_m = geometry_.sampleSpacing(b.o, b.size);
      options.max_split_depth = spec_.bound_split_depth;
      bounds[i] = integrator_.boundBall(centre(b), radius(b), inherited,
                                        root ? 0.0 : parent_dropped[b.parent], options, s.kept);
      // A skipped block's pieces are never read again.
      if (!skipped(bounds[i])) {
        lists[i].reserve(s.kept.size());
        for (const Candidate& c : s.kept) lists[i].push_back(pool.intern(c));
      }
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
  // Indices into integrator_.candidates().
  [[nodiscard]] PieceList integrationList(const PiecePool& pool, const PieceList& kept) const {
    std::vector<char> taken(integrator_.candidates().size(), 0);
    PieceList out;
    for (const std::uint32_t piece : kept) {
      const std::uint32_t k = coarse_candidate_[pool[piece].facet.coarse];
      if (taken[k] != 0) continue;
      taken[k] = 1;
      out.push_back(k);
    }
    return out;
  }

  // Only a bound proven at most the floor skips a block, or in a classifying field one below
  // what counts as hazardous; NaN never does (and cannot occur: BallBound is never NaN).
  [[nodiscard]] bool skipped(const BallBound& bound) const {
    return bound.upper_w_m2 <= spec_.floor_w_m2 ||
           (classifying() &&
            bound.upper_w_m2 < (1.0 - spec_.tolerance) * spec_.lowestHazardThresholdW_m2());
  }
  [[nodiscard]] bool classifying() const { return spec_.classify_above_w_m2 > 0.0; }

  // A classifying field's finest block whose ball reaches a lit facet: every point of it below
  // the threshold would be marked Unresolved, so every point counts hazardous whatever it
  // receives, and none is integrated (next to a lit surface, where integration costs most).
  [[nodiscard]] bool unevaluated(const Block& b, const BallBound& bound) const {
    return classifying() && splittableAxes(b.size) == 0 && !bound.bounded();
  }

  // A classifying field's block whose every sample counts hazardous (none inside the target).
  [[nodiscard]] bool allHazardous(const Block& b) const {
    bool all = true;
    field::forEachSample(b.size, [&](int di, int dj, int dk) {
      const PointValue& v = values_.at(keyAt(b, di, dj, dk));
      all = all && !v.excluded && v.irradiance_w_m2 >= spec_.classify_above_w_m2 &&
            std::isfinite(v.irradiance_w_m2);
    });
    return all;
  }

  // Evaluates the sample lattice points of every block not skipped that no earlier level
  // evaluated; a point shared by several blocks takes the candidates of the first.
  void evaluateSamples(const std::vector<Block>& blocks, const PiecePool& pool,
                       const std::vector<PieceList>& lists, const std::vector<BallBound>& bounds) {
    std::vector<std::pair<std::uint64_t, std::uint32_t>> wanted;  // (point, block)
    for (std::size_t i = 0; i < blocks.size(); ++i) {
      if (skipped(bounds[i]) || unevaluated(blocks[i], bounds[i])) continue;
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

    std::vector<char> sampled(blocks.size(), 0);
    for (const auto& [key, block] : wanted) sampled[block] = 1;
    std::vector<PieceList> point_lists(blocks.size());
    tbb::parallel_for(std::size_t{0}, blocks.size(), [&](std::size_t i) {
      if (sampled[i] != 0) point_lists[i] = integrationList(pool, lists[i]);
    });
    std::vector<PointValue> results(wanted.size());
    std::vector<std::int64_t> evaluations(wanted.size(), 0);
    struct Scratch {
      IntegratorWorkspace workspace;
      std::vector<Candidate> candidates;
    };
    tbb::enumerable_thread_specific<Scratch> scratch;
    const std::span<const Candidate> lit = integrator_.candidates();
    // The points of @p indices (into wanted), integrated in parallel.
    const auto integrate = [&](std::span<const std::size_t> indices) {
      if (counter_ != nullptr) {
        counter_->items_scheduled.fetch_add(indices.size());
        counter_->beginStep("level", stats_.levels + 1, 0, indices.size());
      }
      tbb::parallel_for(std::size_t{0}, indices.size(), [&](std::size_t m) {
        if (stopRequested()) return;
        const std::size_t w = indices[m];
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
        Scratch& s = scratch.local();
        s.candidates.clear();
        for (const std::uint32_t c : point_lists[wanted[w].second]) s.candidates.push_back(lit[c]);
        const ObserverResult r = integrator_.adaptive(x, s.candidates, s.workspace);
        results[w].irradiance_w_m2 = r.irradiance_w_m2;
        results[w].error_w_m2 = r.error_estimate_w_m2;
        results[w].converged = r.converged;
        evaluations[w] = r.evaluations;
        if (counter_ != nullptr) {
          counter_->items_done.fetch_add(1, std::memory_order_relaxed);
          counter_->evaluations.fetch_add(r.evaluations, std::memory_order_relaxed);
        }
      });
    };
    if (exchange_ == nullptr) {
      std::vector<std::size_t> all(wanted.size());
      std::iota(all.begin(), all.end(), std::size_t{0});
      integrate(all);
    } else {
      // Shared with the other processes, as glint points shares its observers: each integrates
      // its share and all receive every point; a stop on any process stops all of them here.
      shareObservers(
          *exchange_, wanted.size(),
          [&](std::span<const std::size_t> mine, WireWriter& out) {
            integrate(mine);
            if (stopRequested()) throw WorkStopped();
            for (const std::size_t w : mine) {
              out.put(results[w].irradiance_w_m2);
              out.put(results[w].error_w_m2);
              out.put(evaluations[w]);
              out.put<std::uint8_t>(results[w].excluded ? 1 : 0);
              out.put<std::uint8_t>(results[w].converged ? 1 : 0);
            }
          },
          [&](std::size_t w, WireReader& in) {
            results[w].irradiance_w_m2 = in.get<double>();
            results[w].error_w_m2 = in.get<double>();
            evaluations[w] = in.get<std::int64_t>();
            results[w].excluded = in.get<std::uint8_t>() != 0;
            results[w].converged = in.get<std::uint8_t>() != 0;
          });
    }
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
                               const std::vector<BallBound>& bounds) const {
    std::vector<Decision> decisions(blocks.size());
    tbb::parallel_for(std::size_t{0}, blocks.size(),
                      [&](std::size_t i) { decisions[i] = decideBlock(blocks[i], bounds[i]); });
    return decisions;
  }

  [[nodiscard]] Decision decideBlock(const Block& b, const BallBound& bound) const {
    if (skipped(bound)) return {Verdict::Skip};
    if (unevaluated(b, bound)) return {Verdict::Finest};
    // Hazardous at every sample: every point counts so, even where the ball reaches the target.
    if (classifying() && allHazardous(b)) return {Verdict::Accept, 0};
    if (const std::optional<Decision> d = field::decideByBound(bound, b.size, spec_.floor_w_m2)) {
      return *d;
    }
    return field::decideBySamples(samplesOf(b), b.size, bound, spec_.tolerance, spec_.floor_w_m2,
                                  classifying() ? spec_.lowestHazardThresholdW_m2() : 0.0);
  }

  // Writes final block @p f's status, level and (accepted) interpolated irradiance into @p t,
  // counting its interpolated and below-floor points. Its samples come later, from values_.
  void fillBlock(const FinalBlock& f, ThreadGrids& t, std::int64_t& interpolated,
                 std::int64_t& below) const {
    const Block& b = f.block;
    const openvdb::CoordBBox box = ownedBox(b, lattice_);
    switch (f.decision.verdict) {
      case Verdict::Skip:
        t.grids->status->tree().fill(box, statusCode(VoxelStatus::BelowFloor), true);
        t.grids->level->tree().fill(box, static_cast<float>(b.level), true);
        below += static_cast<std::int64_t>(box.volume());
        break;
      case Verdict::Finest:
        t.grids->level->tree().fill(box, static_cast<float>(b.level), true);
        if (f.unevaluated) {  // those of its points that are nobody's samples: hazardous
          auto status = t.grids->status->getAccessor();
          for (auto it = box.begin(); it; ++it) {
            const openvdb::Coord& p = *it;
            const bool inside = excluded_ && excluded_(spec_.position(p[0], p[1], p[2]));
            status.setValue(p,
                            statusCode(inside ? VoxelStatus::Excluded : VoxelStatus::Unresolved));
          }
        }
        break;  // its samples: written below
      case Verdict::Accept: {
        t.grids->level->tree().fill(box, static_cast<float>(b.level), true);
        t.grids->status->tree().fill(box, statusCode(VoxelStatus::Interpolated), true);
        interpolated += static_cast<std::int64_t>(box.volume());
        const BlockSize h{b.size[0] / 2, b.size[1] / 2, b.size[2] / 2};
        const int power = f.decision.power;
        std::array<double, 27> v{};  // E·r^power at the 3×3×3 lattice
        for (int a = 0; a < 3; ++a)
          for (int c = 0; c < 3; ++c)
            for (int e = 0; e < 3; ++e) {
              const Index3 p = at(b, a * h[0], c * h[1], e * h[2]);
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
            oct[a] = std::min(local / h[a], 1);
            t3[a] = static_cast<double>(local - oct[a] * h[a]) / h[a];
          }
          const double value =
              field::octantFill(v, oct, t3) / spreadWeight(p[0], p[1], p[2], power);
          // At most the floor is negligible (FieldSpec::floor_w_m2): left at 0 and inactive,
          // so that a kilometre box stores its lit sheet, not the dark around it that its
          // accepted blocks also cover.
          if (value > spec_.floor_w_m2) t.irradiance.setValue(p, static_cast<float>(value));
        }
        break;
      }
      case Verdict::Refine:
        break;
    }
  }

  std::unique_ptr<FieldGrids> writeGrids() {
    // The final blocks by their coarsest ancestor, each such group written into grids of its
    // own and pruned before joining its thread's: a block's region of one status and level
    // is then a tile wherever it covers whole leaves, and never waits voxel by voxel for the
    // end (the 2 km example: 3.4 GB of grids before the final prune, 2.8 GB after it).
    const int bv = spec_.block_voxels;
    const auto coarseKey = [&](const Block& b) {
      std::uint64_t key = 0;
      for (std::size_t a = 0; a < 3; ++a) {
        key = key * static_cast<std::uint64_t>(lattice_.n[a] / bv + 1) +
              static_cast<std::uint64_t>(b.o[a] / bv);
      }
      return key;
    };
    std::vector<std::pair<std::uint64_t, std::uint32_t>> order(final_.size());
    for (std::size_t f = 0; f < final_.size(); ++f) {
      order[f] = {coarseKey(final_[f].block), static_cast<std::uint32_t>(f)};
    }
    std::sort(order.begin(), order.end());
    std::vector<std::size_t> group_start;
    for (std::size_t i = 0; i < order.size(); ++i) {
      if (i == 0 || order[i].first != order[i - 1].first) group_start.push_back(i);
    }
    group_start.push_back(order.size());

    tbb::enumerable_thread_specific<std::unique_ptr<FieldGrids>> per_thread(
        [&] { return makeGrids(spec_); });
    tbb::enumerable_thread_specific<std::int64_t> interpolated(0), below(0);
    tbb::parallel_for(std::size_t{0}, group_start.size() - 1, [&](std::size_t g) {
      ThreadGrids t(spec_);
      for (std::size_t i = group_start[g]; i < group_start[g + 1]; ++i) {
        fillBlock(final_[order[i].second], t, interpolated.local(), below.local());
      }
      t.grids->status->tree().prune();
      t.grids->level->tree().prune();
      mergeInto(*per_thread.local(), *t.grids);
    });
    std::unique_ptr<FieldGrids> grids = makeGrids(spec_);
    for (std::unique_ptr<FieldGrids>& t : per_thread) mergeInto(*grids, *t);
    per_thread.clear();
    // Leaves shared by neighbouring groups (coarse blocks not a multiple of 8 voxels) become
    // uniform only once merged: tiles too, before the samples are written in.
    grids->status->tree().prune();
    grids->level->tree().prune();
    for (std::int64_t n : interpolated) stats_.interpolated_points += n;
    for (std::int64_t n : below) stats_.below_floor_points += n;

    // Every sample, wherever its block ended up, with its own value.
    auto irradiance = grids->irradiance->getAccessor();
    auto status = grids->status->getAccessor();
    auto upper = grids->upper->getAccessor();
    const auto nk = static_cast<std::uint64_t>(lattice_.n[2]);
    const auto nj = static_cast<std::uint64_t>(lattice_.n[1]);
    for (const auto& [key, value] : values_) {
      const openvdb::Coord p(static_cast<int>(key / nk / nj), static_cast<int>((key / nk) % nj),
                             static_cast<int>(key % nk));
      const float before = status.getValue(p);
      if (before == statusCode(VoxelStatus::Interpolated)) --stats_.interpolated_points;
      if (before == statusCode(VoxelStatus::BelowFloor)) --stats_.below_floor_points;
      if (value.excluded) {
        status.setValue(p, statusCode(VoxelStatus::Excluded));
        irradiance.setValueOff(p, 0.0f);
        continue;
      }
      if (!std::isfinite(value.irradiance_w_m2)) {
        noteNonFinite(stats_, spec_.position(p[0], p[1], p[2]));
        status.setValue(p, statusCode(VoxelStatus::Unconverged));
        irradiance.setValueOff(p, 0.0f);
        continue;
      }
      status.setValue(
          p, statusCode(value.converged ? VoxelStatus::Evaluated : VoxelStatus::Unconverged));
      if (!value.converged) {
        noteUnconverged(stats_, upper, p, spec_.position(p[0], p[1], p[2]), value.irradiance_w_m2,
                        value.error_w_m2);
      }
      irradiance.setValue(p, static_cast<float>(value.irradiance_w_m2));
      if (value.irradiance_w_m2 > stats_.peak_w_m2) {
        stats_.peak_w_m2 = value.irradiance_w_m2;
        stats_.peak_at_m = spec_.position(p[0], p[1], p[2]);
      }
    }
    markUnresolved(*grids);
    // Blocks fill whole regions with one status and level; as tiles they cost nothing per voxel.
    grids->status->tree().prune();
    grids->level->tree().prune();
    finishStats(*grids, stats_);
    return grids;
  }

 private:
  // A classifying field's points need, below the threshold, only the accuracy of a point at
  // it (FieldSpec::classify_above_w_m2): a point far below it, where the diffuse glow of a
  // whole lit side is summed to a thousandth, is then settled by a few pieces.
  // None for a field that resolves its values: it integrates with the caller's integrator,
  // not a copy (whose candidates a mesh's lit facets make large).
  static std::optional<FacetIntegrator> classifyingAccuracy(const FacetIntegrator& integrator,
                                                            const FieldSpec& spec) {
    if (!(spec.classify_above_w_m2 > 0.0)) return std::nullopt;
    return integrator.withAccuracy(integrator.options().tolerance,
                                   std::max(integrator.options().floor_w_m2,
                                            spec.tolerance * spec.lowestHazardThresholdW_m2()));
  }

  const std::optional<FacetIntegrator> classifying_;
  const FacetIntegrator& integrator_;  // classifying_, or the caller's
  const FieldSpec& spec_;
  const ExcludedFn& excluded_;
  WorkCounter* counter_;
  PointExchange* exchange_;  // null when this process computes the field alone
  Lattice lattice_;
  BlockGeometry geometry_;  // where a block lies in space: box, radial or surface lattice
  std::vector<std::uint32_t> coarse_candidate_;  // coarse facet → index of its lit candidate
  Vec3 lit_centre_m_;  // centre of the lit facets' box: where the light spreads from
  FieldStats stats_;
  std::unordered_map<std::uint64_t, PointValue> values_;  // every sample, evaluated once
  std::vector<FinalBlock> final_;
};

}  // namespace

ObserverField computeField(const FacetIntegrator& integrator, const FieldSpec& spec,
                           const ExcludedFn& excluded, WorkCounter* counter,
                           PointExchange* exchange) {
  validateFieldSpec(spec);
  openvdb::initialize();
  return FieldBuilder(integrator, spec, excluded, counter, exchange).run();
}

}  // namespace glint
