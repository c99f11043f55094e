#pragma once
/// @file
/// @brief The adaptive observer field: irradiance over a box of observers, refined octree-
/// fashion only where it varies and left empty only where a bound proves it negligible
/// (docs/architecture.md, "How it works": the observer field). OpenVDB holds the result;
/// this header does not include it (see observers/field_grids.h for the grids themselves).

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <vector>

#include "facets/integrator.h"
#include "observers/point_set.h"

namespace glint {

/// @brief A lattice of directions × distances about a centre, one cube face of it: lattice
/// point (i, j, k) lies at centre_m + ρ_k (n + u_i a + v_j b), where a, b, n are the field's
/// axes, u_i = −1 + 2i / face_cells and v_j likewise. Lines of constant (i, j) are rays from
/// the centre; each layer is a square on a plane ρ_k from it.
///
/// The first inner_layers layers step evenly from start_m to near_m, the rest grow by a ratio
/// (ρ_k = near_m × ratio^(k − inner_layers)), so one lattice spans a target's own surface,
/// its surroundings and kilometres beyond with the same relative resolution (the hazard
/// reach's lattice): near the centre, where the geometric steps would shrink to nothing, the
/// even steps keep the radial resolution of the lit ball. Nearer the centre than start_m (the
/// cube of that half-edge) nothing is sampled.
/// The field's grids are then indexed by (i, j, k) alone: their transform, volumeAbove() and
/// exceedance() assume the box's equal cells and do not apply.
struct RadialLattice {
  Vec3 centre_m{0.0};
  int face_cells = 64;   ///< lattice intervals along a face edge (a multiple of block_voxels)
  double near_m = 1.0;   ///< ρ of layer inner_layers, where the growth by ratio begins (m)
  double ratio = 1.01;   ///< ρ_{k+1} / ρ_k beyond near_m, above 1
  int layers = 64;       ///< lattice intervals along k (a multiple of block_voxels)
  int inner_layers = 0;  ///< layers from start_m to near_m in even steps (0: none)
  double start_m = 0.0;  ///< ρ of layer 0 where inner_layers > 0, in (0, near_m) (m)

  /// @brief ρ_k: the distance of layer @p k's plane from the centre (m).
  [[nodiscard]] double layerDistance(int k) const {
    if (k < inner_layers) {
      return start_m + (near_m - start_m) * static_cast<double>(k) / inner_layers;
    }
    return near_m * std::pow(ratio, static_cast<double>(k - inner_layers));
  }
};

/// @brief A plane's lattice laid over a surface: lattice point (i, j) lies offset_m[j × width +
/// i] along the plane's normal (FieldSpec::axes[2]) from its place on the plane. What carries
/// observers at eye height over the terrain (geo/terrain.h, docs/terrain.md).
struct SurfaceOffsets {
  int width = 0;   ///< lattice points along axes[0]: FieldSpec::nodes()[0]
  int height = 0;  ///< along axes[1]
  std::vector<double> offset_m;

  [[nodiscard]] double at(int i, int j) const {
    return offset_m[static_cast<std::size_t>(j) * static_cast<std::size_t>(width) +
                    static_cast<std::size_t>(i)];
  }
  /// @brief The least and greatest offsets of lattice points (i0..i1, j0..j1), ends included.
  [[nodiscard]] std::array<double, 2> range(int i0, int j0, int i1, int j1) const;
};

/// @brief The observer box or plane and its accuracy (scene keys `observers`, `planes`).
///
/// Observers sit on a lattice of spacing voxel_m starting at min_m; the region is extended up
/// to whole coarse blocks of block_voxels × voxel_m. Lattice point (i, j, k) is OpenVDB voxel
/// (i, j, k) at world position min_m + voxel_m · (i axes[0] + j axes[1] + k axes[2]).
struct FieldSpec {
  Vec3 min_m{0.0};
  Vec3 max_m{0.0};  ///< the far corner: its offset from min_m along each axis is the extent
  /// Lattice directions, unit and orthogonal: the world axes for a box; a plane's u, v, normal.
  std::array<Vec3, 3> axes{Vec3(1.0, 0.0, 0.0), Vec3(0.0, 1.0, 0.0), Vec3(0.0, 0.0, 1.0)};
  /// A plane of observers: one lattice layer along axes[2], square blocks (a quadtree).
  bool plane = false;
  double voxel_m = 0.0;   ///< finest lattice spacing
  int block_voxels = 16;  ///< coarsest block edge in voxels, a power of two
  /// A block is accepted (its voxels interpolated) when interpolation from its corners misses
  /// every finer sample by at most tolerance × the block's largest sample (+ the floor).
  double tolerance = 1e-2;
  double floor_w_m2 = 0.0;  ///< irradiance below this counts as negligible
  /// Candidate facets are split 1→4 down to this depth to tighten a block's bound. Deeper
  /// splits prove more blocks dark, but each block then carries up to 4^depth pieces of every
  /// lit facet its light may reach.
  int bound_split_depth = 6;
  /// A refined block is halved only along the axes whose samples bend (a rim's step is then
  /// resolved across itself and interpolated along itself); false halves every axis, as the
  /// octree of the first versions did (kept to measure the difference).
  bool anisotropic = true;
  /// The irradiances judged (W/m², each > 0: the MPE, the aided MPE, each level's): a finest
  /// block whose bound reaches one while a glint narrower than its lattice may pass unseen
  /// marks VoxelStatus::Unresolved each of its points whose value lies below a threshold its
  /// bound reaches, so that every threshold, not only the lowest, is judged with the bound
  /// (FieldBlock::bound_w_m2). Empty: every such block marks all its points.
  std::vector<double> hazard_thresholds_w_m2;
  /// A field that only sorts its points into hazardous and not (the hazard reach), where > 0:
  /// a block is then also skipped where its bound is below (1 − tolerance) × the lowest
  /// threshold (none of its points can count hazardous), and accepted whole, its
  /// points interpolated, where every one of its samples is at least this (all its points
  /// count hazardous, whatever passes between the samples, so neither its bound nor its
  /// interpolation error matters). Values below the first or between the samples of the second
  /// are then not resolved, and values below the lowest threshold only to tolerance × it (each
  /// point's integration and each block's interpolation): the accuracy a point at the threshold
  /// has, which is all the sorting reads. 0: the field resolves its values.
  double classify_above_w_m2 = 0.0;
  /// A plane laid over a surface (plane only): each point offset along axes[2]; null: flat.
  std::shared_ptr<const SurfaceOffsets> surface;
  /// A lattice of directions × distances instead of the box (min_m, max_m and voxel_m are then
  /// unused): see RadialLattice.
  std::optional<RadialLattice> radial;

  /// @brief The least of hazard_thresholds_w_m2 (W/m²; 0 where there is none).
  [[nodiscard]] double lowestHazardThresholdW_m2() const {
    double lowest = 0.0;
    for (const double t : hazard_thresholds_w_m2) lowest = lowest == 0.0 ? t : std::min(lowest, t);
    return lowest;
  }
  /// @brief Lattice points per axis (voxels + 1), after extending to whole blocks.
  [[nodiscard]] std::array<int, 3> nodes() const;
  /// @brief World position of lattice point (i, j, k).
  [[nodiscard]] Vec3 position(int i, int j, int k) const {
    if (radial) return radialPosition(i, j, k);
    const Vec3 flat =
        min_m + voxel_m * (static_cast<double>(i) * axes[0] + static_cast<double>(j) * axes[1] +
                           static_cast<double>(k) * axes[2]);
    return surface ? flat + surface->at(i, j) * axes[2] : flat;
  }

 private:
  [[nodiscard]] Vec3 radialPosition(int i, int j, int k) const {
    const RadialLattice& r = *radial;
    const double step = 2.0 / r.face_cells;
    return r.centre_m + r.layerDistance(k) *
                            (axes[2] + (-1.0 + step * i) * axes[0] + (-1.0 + step * j) * axes[1]);
  }
};

/// @brief What a voxel of the result holds (grid `status`). Inactive irradiance never stands
/// for 0 without one of these saying why.
enum class VoxelStatus : int {
  Outside = 0,       ///< not in the box (the grids' background)
  Evaluated = 1,     ///< integrated at this very point
  Interpolated = 2,  ///< trilinear from evaluated points, within the tolerance
  BelowFloor = 3,    ///< a bound proves the irradiance ≤ floor here; not computed
  Excluded = 4,      ///< inside or on the target: no observer can be here
  /// Integrated here, but the integrator hit its depth or evaluation limit before its
  /// tolerance: the value is its best estimate, not a converged one.
  Unconverged = 5,
  /// Integrated here (a finest block's point), but the block's bound reaches the hazard
  /// threshold while a glint narrower than the lattice may pass between its points unseen.
  Unresolved = 6,
};

/// @brief What each VoxelStatus value means, in one line for files that carry the codes.
inline const char* voxelStatusMeanings() {
  return "0 outside the box, 1 evaluated, 2 interpolated, 3 proven below floor_w_m2 (not "
         "computed), 4 inside or on the target, 5 evaluated but unconverged (integrator limit "
         "reached), 6 evaluated, but a bound above the hazard threshold says a glint narrower "
         "than the lattice may pass here";
}

/// @brief What the outputs' `irradiance_upper_w_m2` holds (ObserverField::upperLattice()), in
/// one line for files that carry it.
inline const char* upperIrradianceMeaning() {
  return "W/m^2: the most each point may receive: its irradiance, plus its error estimate where "
         "unconverged (status 5), its block's bound where a narrower glint may pass (status 6; "
         "3.4e38 where unbounded)";
}

/// @brief Whether the irradiance of a voxel with status @p s was integrated at that point.
inline bool integratedHere(VoxelStatus s) {
  return s == VoxelStatus::Evaluated || s == VoxelStatus::Unconverged ||
         s == VoxelStatus::Unresolved;
}

/// @brief Counts and figures of one field computation.
struct FieldStats {
  std::array<int, 3> nodes{};         ///< lattice points per axis
  std::int64_t lattice_points = 0;    ///< in the box
  std::int64_t evaluated_points = 0;  ///< integrated (each once)
  std::int64_t interpolated_points = 0;
  std::int64_t below_floor_points = 0;
  std::int64_t excluded_points = 0;
  std::int64_t unconverged_points = 0;  ///< integrator did not reach its tolerance (status 5)
  /// The box around the unconverged points (meaningful when there are any).
  Vec3 unconverged_min_m{std::numeric_limits<double>::infinity()};
  Vec3 unconverged_max_m{-std::numeric_limits<double>::infinity()};
  /// The largest irradiance + error estimate of an unconverged point (W/m²): below the MPE,
  /// none of them can be hazardous however the integration would have ended.
  double unconverged_max_upper_w_m2 = 0.0;
  /// Integrated points whose irradiance is not a finite number (never written to the grids):
  /// none for a scene within pipeline/base/limits.h; any is an error the caller must report.
  std::int64_t non_finite_points = 0;
  Vec3 non_finite_at_m{0.0};         ///< one of them
  std::int64_t blocks_skipped = 0;   ///< proven below the floor
  std::int64_t blocks_accepted = 0;  ///< interpolated
  /// Of those, the blocks that interpolated E·r or E·r² (r from the lit facets' centre)
  /// because E itself failed the check: the far field's fall-off.
  std::int64_t blocks_accepted_spread = 0;
  std::int64_t blocks_refined = 0;
  std::int64_t blocks_finest = 0;  ///< every point evaluated
  /// Finest blocks whose bound says a glint narrower than the lattice may pass between their
  /// points above a hazard threshold (FieldSpec::hazard_thresholds_w_m2), and the points
  /// they mark VoxelStatus::Unresolved.
  std::int64_t unresolved_blocks = 0;
  std::int64_t unresolved_points = 0;
  /// The largest finite bound of those blocks (W/m²) and the centre of its block; the blocks
  /// whose ball reaches a lit facet have none and are counted apart.
  double unresolved_max_bound_w_m2 = 0.0;
  Vec3 unresolved_bound_at_m{0.0};
  std::int64_t unresolved_unbounded_blocks = 0;
  /// The box around the marked points (meaningful when there are any).
  Vec3 unresolved_min_m{std::numeric_limits<double>::infinity()};
  Vec3 unresolved_max_m{-std::numeric_limits<double>::infinity()};
  /// A voxel size that resolves every one of those blocks: the narrowest light among their
  /// narrow facets / √3 (BallBound::resolving_spacing_m); 0 where none could be computed.
  double unresolved_resolving_voxel_m = 0.0;
  std::int64_t evaluations = 0;        ///< reflection calculations, all points
  std::int64_t bound_evaluations = 0;  ///< contribution bounds of candidate facets
  int levels = 0;                      ///< refinement levels used (0 = coarsest blocks only)
  double peak_w_m2 = 0.0;
  Vec3 peak_at_m{0.0};
  double seconds = 0.0;
  std::int64_t active_voxels = 0;  ///< of the irradiance grid
  std::size_t grid_bytes = 0;      ///< memory of all grids

  /// @brief Adds the statistics of other points of the same run (another thread's share, a
  /// far-field face): counts, times and memory add, boxes join, maxima keep the larger with
  /// its place. On a tie the first kept wins, and the first non-finite point stays the one
  /// named, so a merge in a fixed order gives the same statistics every run. `nodes` stays.
  FieldStats& operator+=(const FieldStats& other);

  /// @brief These statistics without what belongs to the field's own positions and units (the
  /// boxes, the peak, the unresolved blocks' bounds and their resolving voxel): the counts, the
  /// work, the time, the memory, the unconverged points' largest value plus error and where the
  /// first non-finite point lies. What adds up across fields of another kind (a far field's
  /// faces, whose values become intensities).
  [[nodiscard]] FieldStats countsOnly() const;
};

/// @brief A block of the tree as it ended: lattice points origin .. origin + size[a] along
/// each axis a (a plane's blocks: 2 along the normal, folded onto its one layer).
struct FieldBlock {
  std::array<int, 3> origin{};
  std::array<int, 3> size{};  ///< edges in voxels
  int level = 0;              ///< 0 = coarsest
  /// Evaluated, Interpolated, BelowFloor or Unresolved.
  VoxelStatus status = VoxelStatus::Evaluated;
  /// Unresolved blocks only: what a point of the block may receive at most
  /// (field::narrowGlintBound(), W/m²; +∞ where its ball reaches a lit facet).
  double bound_w_m2 = 0.0;
};

/// @brief Observer positions glint does not evaluate (inside or on the target).
using ExcludedFn = std::function<bool(const Vec3& point_m)>;

struct FieldGrids;  // observers/field_grids.h

/// @brief The computed field: OpenVDB grids at the finest voxel size and their statistics.
class ObserverField {
 public:
  ObserverField(FieldSpec spec, FieldStats stats, std::unique_ptr<FieldGrids> grids,
                std::vector<FieldBlock> blocks);
  ~ObserverField();
  ObserverField(ObserverField&&) noexcept;
  ObserverField& operator=(ObserverField&&) noexcept;

  [[nodiscard]] const FieldSpec& spec() const { return spec_; }
  [[nodiscard]] const FieldStats& stats() const { return stats_; }
  [[nodiscard]] const FieldGrids& grids() const { return *grids_; }
  /// @brief For the field's owner to consume them (writeVdb() frees each grid once written).
  [[nodiscard]] FieldGrids& grids() { return *grids_; }
  /// @brief The final blocks (for the dense twin: the coarsest blocks, all evaluated).
  [[nodiscard]] const std::vector<FieldBlock>& blocks() const { return blocks_; }

  /// @brief Irradiance at lattice point (i, j, k); 0 where not computed (see status()).
  [[nodiscard]] double irradiance(int i, int j, int k) const;
  /// @brief The irradiance of every lattice point (W/m²), as stored (float), 0 where not
  /// computed; indexed [(k · nodes[1] + j) · nodes[0] + i].
  [[nodiscard]] std::vector<float> irradianceLattice() const;
  /// @brief An Unconverged point's irradiance plus its error estimate (W/m², rounded up to a
  /// float); 0 at every other point.
  [[nodiscard]] double unconvergedUpper(int i, int j, int k) const;
  /// @brief The most each point of the lattice taken every @p stride points may receive (W/m²):
  /// its irradiance, an Unconverged point's value plus its error, an Unresolved point's block
  /// bound (the largest float where unbounded); indexed as irradianceLattice() over that lattice
  /// ((n − 1) / stride + 1 points along each axis). What the outputs' `irradiance_upper_w_m2`
  /// holds: where it reaches a threshold and the irradiance does not, the point is in doubt.
  [[nodiscard]] std::vector<float> upperLattice(int stride = 1) const;
  /// @brief Calls @p visit(i, j, k, bound_w_m2) at each point whose status() is Unresolved, with
  /// its block's bound (FieldBlock::bound_w_m2 rounded up to a float; the largest float where
  /// unbounded): what a glint beside the point that its lattice cannot see may reach.
  void forEachUnresolvedPoint(const std::function<void(int, int, int, float)>& visit) const;
  [[nodiscard]] VoxelStatus status(int i, int j, int k) const;
  [[nodiscard]] int level(int i, int j, int k) const;

  /// @brief Volume in m³ of the lattice cells whose irradiance is at least @p threshold_w_m2
  /// (each lattice point standing for one voxel_m³).
  [[nodiscard]] double volumeAbove(double threshold_w_m2) const;

  /// @brief Where the irradiance may be at least a threshold (at the MPE: the nominal hazard
  /// zone): where its value is, or an Unconverged point's value plus its error estimate.
  struct Exceedance {
    std::int64_t points = 0;  ///< lattice points, each standing for one voxel_m³
    /// Of those, the Unconverged points counted by their value plus error alone: the zone may
    /// be smaller by them had their integration converged, never larger.
    std::int64_t by_error_points = 0;
    double volume_m3 = 0.0;
    Vec3 min_m{0.0};  ///< box around those points (when points > 0)
    Vec3 max_m{0.0};
    double farthest_m = 0.0;  ///< the largest distance of such a point from `from_m`
    Vec3 farthest_at_m{0.0};
    /// Some such point lies on the lattice's outer layer (a plane's normal aside): the region
    /// may go on beyond the box or plane.
    bool reaches_edge = false;
  };
  /// @brief The lattice points whose irradiance, or whose value plus error where Unconverged,
  /// is at least @p threshold_w_m2, with their box and the farthest of them from @p from_m.
  [[nodiscard]] Exceedance exceedance(double threshold_w_m2, const Vec3& from_m) const;

 private:
  FieldSpec spec_;
  FieldStats stats_;
  std::unique_ptr<FieldGrids> grids_;
  std::vector<FieldBlock> blocks_;
};

/// @brief A floor under the memory computeField (@p dense: computeDenseField) takes for
/// @p spec, in bytes, known before anything is allocated: per coarse block (adaptive) or per
/// lattice point (dense), as measured on fields with nothing to evaluate, with the grids and
/// the output writers; a plane's grids besides, a leaf per 8 × 8 points. Evaluated points
/// cost more (the run's summary reports bytes per active voxel), which the run's memory watch
/// covers.
std::uint64_t fieldMemoryFloorBytes(const FieldSpec& spec, bool dense);

/// @brief The adaptive field: top-down over blocks, each pruning its candidate facets by
/// bound, skipping where the bound is below the floor, else evaluating its 3×3×3 lattice and
/// refining where interpolation misses, halved along the axes that need it. Evaluated points are
/// cached and never computed twice; TBB runs over blocks and points. @p integrator's options are
/// used per point. @p counter (optional) counts evaluated points and evaluations.
/// With @p exchange (an MPI job), each process integrates its share of every level's points
/// (every size-th of them, which spreads a costly region over all) and receives the others';
/// every process then holds the field one process would have computed, bit for bit.
/// @throw WorkStopped when the counter's stop flag is raised (also computeDenseField); with an
/// exchange, on every process at once.
ObserverField computeField(const FacetIntegrator& integrator, const FieldSpec& spec,
                           const ExcludedFn& excluded, WorkCounter* counter = nullptr,
                           PointExchange* exchange = nullptr);

/// @brief The uniform dense twin: every lattice point of the box evaluated with the same
/// integrator over every lit facet.
ObserverField computeDenseField(const FacetIntegrator& integrator, const FieldSpec& spec,
                                const ExcludedFn& excluded, WorkCounter* counter = nullptr);

}  // namespace glint
