// The hazard reach: six radial lattices from the target out to the far radius, and the far
// field beyond.
#include "observers/reach.h"

#include <tbb/concurrent_hash_map.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "observers/detail/cube_faces.h"
#include "observers/far_field.h"

namespace glint {
namespace {

constexpr double kFloatMax = static_cast<double>(std::numeric_limits<float>::max());

std::size_t rayIndex(int i, int j, int face_cells) {
  return static_cast<std::size_t>(j) * static_cast<std::size_t>(face_cells + 1) +
         static_cast<std::size_t>(i);
}

// The far field's hazard distance toward unit @p d where it is at least the far radius there
// (nearer, the lattice decides), else 0.
double farReachToward(const FarField& far, double threshold_w_m2, double extinction_per_m,
                      const Vec3& d) {
  const double r =
      far.hazardDistanceToward(d, far.upperIntensity(d), threshold_w_m2, extinction_per_m);
  return r >= farRadiusToward(far.spec(), d) ? r : 0.0;
}

// The stretch of ray (i, j) of a face of @p n cells an edge: its distance over the layer plane's.
double rayStretch(int i, int j, int n) {
  const double step = 2.0 / n;
  const double u = -1.0 + step * i, v = -1.0 + step * j;
  return std::sqrt(1.0 + u * u + v * v);
}

void throwIfStopped(const WorkCounter* counter) {
  if (counter != nullptr && counter->stopRequested()) throw WorkStopped();
}

// Between four rays the largest value a peak could have is taken as their largest plus
// kRaysAllowance times the concave second differences across the rays at their corners (along
// each of the two directions, the larger of the corners', summed). For a round Gaussian peak of
// standard deviation s, wherever it lies among rays h apart, 1.40 is needed at s = 0.433 h (0.95
// along one direction), less as it widens (0.22 at s = h); and the light glint's field counts
// resolved is at least that wide (four standard deviations, its width, reach √3 h; narrower
// light is its narrow-glint bound's, BallBound::narrow_w_m2).
constexpr double kRaysAllowance = 2.0;
// Where that reaches a threshold the square is sampled: its centre and its edges' midpoints,
// and the largest value is taken as the nine samples' largest plus kPartAllowance[m − 1] times
// their lines' concave second differences (the larger of the three lines along each
// direction, summed), m the halvings so far; where that still reaches it, each quarter the same
// way, down to kBetweenRaysDepth halvings. Over a square of side h, the factor needed is 0.27 at
// s = 0.433 h, and the peak is twice as wide against each quarter: 0.153 at 0.87 h, 0.132 at
// 1.7 h, 0.127 at 3.5 h. The factors hold 1.25 times that.
constexpr int kBetweenRaysDepth = 4;
constexpr std::array<double, kBetweenRaysDepth> kPartAllowance = {0.34, 0.19, 0.165, 0.16};

// The squares between the rays of one face of the reach's lattice (computeNearReach()): for
// each cell of rays, the farthest layer at which some point between its four rays counts
// hazardous though the rays do not, for each threshold. Squares are judged from the far end
// of a cell inward and only beyond what its rays already reach, so a cell samples between its
// rays only about its crossings. Each cell is one task with its own samples: the result does
// not depend on the threads.
class BetweenRays {
 public:
  struct Found {
    int i = 0, j = 0, k = 0;
    std::size_t t = 0;
  };

  BetweenRays(const FacetIntegrator& integrator, const ReachSpec& spec, NearReach::Face& face,
              const std::vector<float>& value, const ExcludedFn& excluded, WorkCounter* counter)
      : integrator_(integrator),
        spec_(spec),
        face_(face),
        lattice_(*face.spec.radial),
        value_(value),
        excluded_(excluded),
        counter_(counter) {}

  // Judges every square of cell (i, j) (called once a cell, from any thread).
  void judgeCell(int i, int j) {
    Task& task = tasks_.local();
    const int n = lattice_.face_cells;
    for (std::size_t t = 0; t < spec_.thresholds_w_m2.size(); ++t) {
      const double hazardous_w_m2 = (1.0 - spec_.tolerance) * spec_.thresholds_w_m2[t];
      double rays_plane_m = 0.0;  // what the cell's rays reach
      for (int c = 0; c < 4; ++c) {
        const int a = i + (c & 1), b = j + (c >> 1);
        rays_plane_m =
            std::max(rays_plane_m, static_cast<double>(face_.reach_m[t][rayIndex(a, b, n)]) /
                                       rayStretch(a, b, n));
      }
      for (int k = lattice_.layers; k >= 0; --k) {
        const double beyond_m = lattice_.layerDistance(std::min(k + 1, lattice_.layers));
        // Nothing nearer extends the cell's reach (the rays' reach is kept as a float).
        if (beyond_m <= rays_plane_m * (1.0 + 1e-6)) break;
        if (!squareMayReach(task, i, j, k, hazardous_w_m2)) continue;
        face_.between_plane_m[t][static_cast<std::size_t>(j) * static_cast<std::size_t>(n) +
                                 static_cast<std::size_t>(i)] = static_cast<float>(beyond_m);
        task.found.push_back({i, j, k, t});
        break;
      }
    }
  }

  [[nodiscard]] std::int64_t points() const {
    std::int64_t total = 0;
    for (const Task& t : tasks_) total += t.points;
    return total;
  }
  [[nodiscard]] std::int64_t evaluations() const {
    std::int64_t total = 0;
    for (const Task& t : tasks_) total += t.evaluations;
    return total;
  }
  // The squares found hazardous, in the order of their cells and thresholds.
  [[nodiscard]] std::vector<Found> found() const {
    std::vector<Found> all;
    for (const Task& t : tasks_) all.insert(all.end(), t.found.begin(), t.found.end());
    const int n = lattice_.face_cells;
    std::sort(all.begin(), all.end(), [n](const Found& a, const Found& b) {
      const int ca = a.j * n + a.i, cb = b.j * n + b.i;
      return ca != cb ? ca < cb : a.t < b.t;
    });
    return all;
  }

 private:
  // Sample coordinates in units of 1 / 2^kBetweenRaysDepth of the rays' spacing.
  static constexpr int kUnit = 1 << kBetweenRaysDepth;

  struct Task {
    IntegratorWorkspace workspace;
    std::vector<Found> found;
    std::int64_t points = 0, evaluations = 0;
  };
  // (k, x, y) → value (NaN: inside the target), shared by the cells: a sample on an edge
  // between two cells is integrated once, by whichever comes first (the same value either way).
  using Samples = tbb::concurrent_hash_map<std::uint64_t, double>;

  // The value at lattice point (i, j, k): NaN inside the target.
  [[nodiscard]] double latticeValue(int i, int j, int k) const {
    return static_cast<double>(
        value_[rayIndex(i, j, lattice_.face_cells) * static_cast<std::size_t>(lattice_.layers + 1) +
               static_cast<std::size_t>(k)]);
  }

  // The value at (x, y) (in kUnit units of the rays' spacing from the face's corner ray) on
  // layer k: the lattice's own at a ray, else integrated here (its value and error where it
  // did not converge), NaN inside the target.
  double sampleAt(Task& task, int x, int y, int k) {
    if (x % kUnit == 0 && y % kUnit == 0 && x >= 0 && y >= 0 && x <= kUnit * lattice_.face_cells &&
        y <= kUnit * lattice_.face_cells) {
      return latticeValue(x / kUnit, y / kUnit, k);
    }
    constexpr std::uint64_t kOffset = 1u << 20;
    const std::uint64_t key = (static_cast<std::uint64_t>(k) << 42) |
                              (static_cast<std::uint64_t>(x + static_cast<int>(kOffset)) << 21) |
                              static_cast<std::uint64_t>(y + static_cast<int>(kOffset));
    Samples::accessor entry;
    if (!samples_.insert(entry, key)) return entry->second;  // (others wait for a new one)
    const double step = 2.0 / lattice_.face_cells;
    const std::array<Vec3, 3>& e = face_.spec.axes;
    const Vec3 p = lattice_.centre_m +
                   lattice_.layerDistance(k) *
                       (e[2] + (-1.0 + step * x / kUnit) * e[0] + (-1.0 + step * y / kUnit) * e[1]);
    double v = std::numeric_limits<double>::quiet_NaN();
    if (!(excluded_ && excluded_(p))) {
      const ObserverResult r = integrator_.adaptive(p, task.workspace);
      v = r.irradiance_w_m2 + (r.converged ? 0.0 : r.error_estimate_w_m2);
      ++task.points;
      task.evaluations += r.evaluations;
      if (counter_ != nullptr) counter_->evaluations.fetch_add(r.evaluations);
    }
    entry->second = v;
    return v;
  }

  // Square (i, j) of layer k, between four rays whose values are the lattice's.
  bool squareMayReach(Task& task, int i, int j, int k, double hazardous_w_m2) {
    const int n = lattice_.face_cells;
    double largest = 0.0, bend_x = 0.0, bend_y = 0.0;
    for (int c = 0; c < 4; ++c) {
      const int a = i + (c & 1), b = j + (c >> 1);
      const double v = latticeValue(a, b, k);
      if (std::isnan(v)) return false;  // the target's surface: its own rule
      if (v >= hazardous_w_m2) return true;
      largest = std::max(largest, v);
      // On a face's edge, the difference one ray in; one that meets the target's inside (NaN)
      // counts as steep as can be.
      const int ca = std::clamp(a, 1, n - 1), cb = std::clamp(b, 1, n - 1);
      const double dx =
          2.0 * latticeValue(ca, b, k) - latticeValue(ca - 1, b, k) - latticeValue(ca + 1, b, k);
      const double dy =
          2.0 * latticeValue(a, cb, k) - latticeValue(a, cb - 1, k) - latticeValue(a, cb + 1, k);
      bend_x = std::isnan(dx) ? std::numeric_limits<double>::infinity() : std::max(bend_x, dx);
      bend_y = std::isnan(dy) ? std::numeric_limits<double>::infinity() : std::max(bend_y, dy);
    }
    if (largest + kRaysAllowance * (bend_x + bend_y) < hazardous_w_m2) return false;
    return partMayReach(task, kUnit * i, kUnit * j, kUnit, k, 1, hazardous_w_m2);
  }

  // The part of side s (kUnit units) at (x0, y0) of a square, @p depth halvings of the rays'
  // spacing deep once its nine samples are taken.
  bool partMayReach(Task& task, int x0, int y0, int s, int k, int depth, double hazardous_w_m2) {
    const int h = s / 2;
    std::array<double, 9> v{};  // index 3b + a, at (x0 + a h, y0 + b h)
    double largest = std::numeric_limits<double>::quiet_NaN();
    for (int b = 0; b < 3; ++b)
      for (int a = 0; a < 3; ++a) {
        const double x = sampleAt(task, x0 + a * h, y0 + b * h, k);
        if (x >= hazardous_w_m2) return true;
        v[static_cast<std::size_t>(3 * b + a)] = x;
        if (!std::isnan(x)) largest = std::isnan(largest) ? x : std::max(largest, x);
      }
    if (std::isnan(largest)) return false;  // wholly inside the target
    double bend_x = 0.0, bend_y = 0.0;
    for (int l = 0; l < 3; ++l) {
      const auto at = [&](int a, int b) { return v[static_cast<std::size_t>(3 * b + a)]; };
      const double dx = 2.0 * at(1, l) - at(0, l) - at(2, l);
      const double dy = 2.0 * at(l, 1) - at(l, 0) - at(l, 2);
      bend_x = std::isnan(dx) ? std::numeric_limits<double>::infinity() : std::max(bend_x, dx);
      bend_y = std::isnan(dy) ? std::numeric_limits<double>::infinity() : std::max(bend_y, dy);
    }
    const double allowance = kPartAllowance[static_cast<std::size_t>(depth - 1)];
    if (largest + allowance * (bend_x + bend_y) < hazardous_w_m2) return false;
    if (depth == kBetweenRaysDepth) return true;
    for (int c = 0; c < 4; ++c) {
      if (partMayReach(task, x0 + (c & 1) * h, y0 + (c >> 1) * h, h, k, depth + 1,
                       hazardous_w_m2)) {
        return true;
      }
    }
    return false;
  }

  const FacetIntegrator& integrator_;
  const ReachSpec& spec_;
  NearReach::Face& face_;
  const RadialLattice& lattice_;
  const std::vector<float>& value_;
  const ExcludedFn& excluded_;
  WorkCounter* counter_;
  tbb::enumerable_thread_specific<Task> tasks_;
  Samples samples_;
};

}  // namespace

double NearReach::cellPlaneM(int f, std::size_t t, int i, int j) const {
  const int n = spec.face_cells;
  const Face& face = faces[static_cast<std::size_t>(f)];
  // The layers are planes: a ray's reach is a layer's plane distance times its stretch, and a
  // point of the cell between the rays lies no farther than that plane along its own direction.
  const std::vector<float>& r = face.reach_m[t];
  double plane_m =
      face.between_plane_m[t][static_cast<std::size_t>(j) * static_cast<std::size_t>(n) +
                              static_cast<std::size_t>(i)];
  for (int c = 0; c < 4; ++c) {
    const int a = i + (c & 1), b = j + (c >> 1);
    plane_m = std::max(plane_m, static_cast<double>(r[rayIndex(a, b, n)]) / rayStretch(a, b, n));
  }
  return plane_m;
}

double reachStartM(const ReachSpec& spec) { return spec.near_m / (spec.inner_layers + 1); }

FieldSpec reachFaceSpec(int face, const ReachSpec& spec) {
  const cube::FaceFrame& frame = cube::kFaceFrames.at(static_cast<std::size_t>(face));
  FieldSpec s;
  s.axes = {frame.u, frame.v, frame.normal};
  s.voxel_m = 1.0;  // unused by a radial lattice
  s.block_voxels = spec.block_voxels;
  s.tolerance = spec.tolerance;
  s.floor_w_m2 = spec.floor_w_m2;
  s.hazard_thresholds_w_m2 = spec.thresholds_w_m2;
  // Only whether points are hazardous is read (computeNearReach()): a block hazardous at
  // every sample for the highest threshold is taken whole, a hair above it so that its
  // interpolated points, rounded to float, stay so.
  if (!spec.thresholds_w_m2.empty()) {
    s.classify_above_w_m2 =
        (1.0 - spec.tolerance) *
        *std::max_element(spec.thresholds_w_m2.begin(), spec.thresholds_w_m2.end()) * (1.0 + 1e-6);
  }
  const int inner = spec.inner_layers;
  const double outer = std::ceil(std::log(spec.far_m / spec.near_m) / std::log(spec.ratio));
  const int b = spec.block_voxels;
  const int whole = std::max(b, static_cast<int>(std::ceil((inner + outer) / b)) * b);
  s.radial = RadialLattice{spec.centre_m, spec.face_cells, spec.near_m,      spec.ratio,
                           whole,         inner,           reachStartM(spec)};
  return s;
}

double NearReach::toward(const Vec3& direction, std::size_t t) const {
  const int n = spec.face_cells;
  const cube::FaceHit h = cube::faceHit(direction, n);
  const int i = std::clamp(static_cast<int>(std::floor(h.x)), 0, n - 1);
  const int j = std::clamp(static_cast<int>(std::floor(h.y)), 0, n - 1);
  const double plane_m = cellPlaneM(h.face, t, i, j);
  const double cos_n =
      glm::dot(direction, cube::kFaceFrames[static_cast<std::size_t>(h.face)].normal);
  return plane_m / cos_n;
}

double NearReach::lastLayerToward(const Vec3& direction) const {
  const cube::FaceHit h = cube::faceHit(direction, spec.face_cells);
  const RadialLattice& r = *faces[static_cast<std::size_t>(h.face)].spec.radial;
  // The layers are planes: along d their distance grows as 1 / (d · n).
  const double cos_n =
      glm::dot(direction, cube::kFaceFrames[static_cast<std::size_t>(h.face)].normal);
  return r.layerDistance(r.layers) / cos_n;
}

std::int64_t NearReach::evaluatedPoints() const {
  std::int64_t n = 0;
  for (const Face& f : faces) n += f.stats.evaluated_points;
  return n;
}

std::int64_t NearReach::evaluations() const {
  std::int64_t n = 0;
  for (const Face& f : faces) n += f.stats.evaluations;
  return n;
}

std::int64_t NearReach::unresolvedPoints() const {
  std::int64_t n = 0;
  for (const Face& f : faces) n += f.stats.unresolved_points;
  return n;
}

std::int64_t NearReach::betweenPoints() const {
  std::int64_t n = 0;
  for (const Face& f : faces) n += f.between_points;
  return n;
}

std::uint64_t nearReachScratchBytes(const ReachSpec& spec) {
  const FieldSpec face = reachFaceSpec(0, spec);
  const double rays = std::pow(spec.face_cells + 1.0, 2.0);
  const double points = rays * (face.radial->layers + 1.0);
  const double thresholds = static_cast<double>(spec.thresholds_w_m2.size());
  // One face at a time: each point's value (float) and hazard bits (a byte). Kept for all six:
  // each threshold's reach per ray and between the rays per cell, and each ray's peak.
  const double per_face = points * (sizeof(float) + sizeof(std::uint8_t));
  const double kept = 6.0 * (rays * sizeof(float) * (thresholds + 1.0) +
                             std::pow(spec.face_cells, 2.0) * sizeof(float) * thresholds);
  return static_cast<std::uint64_t>(std::min(per_face + kept, 1.8e19));
}

NearReach computeNearReach(const FacetIntegrator& integrator, const ReachSpec& spec,
                           const ExcludedFn& excluded, WorkCounter* counter,
                           PointExchange* exchange) {
  // The accuracy the lattice's own points have (a classifying field's): below the lowest
  // threshold only tolerance × it.
  const double lowest_w_m2 =
      spec.thresholds_w_m2.empty()
          ? 0.0
          : *std::min_element(spec.thresholds_w_m2.begin(), spec.thresholds_w_m2.end());
  const FacetIntegrator classifying = integrator.withAccuracy(
      integrator.options().tolerance,
      std::max(integrator.options().floor_w_m2, spec.tolerance * lowest_w_m2));
  NearReach near;
  near.spec = spec;
  const std::size_t thresholds = spec.thresholds_w_m2.size();
  near.volume_m3.assign(thresholds, 0.0);
  std::vector<double> hazardous_w_m2;
  for (const double t : spec.thresholds_w_m2) hazardous_w_m2.push_back((1.0 - spec.tolerance) * t);
  for (int f = 0; f < cube::kFaces; ++f) {
    if (counter != nullptr) counter->beginStage("face", f + 1, cube::kFaces);
    NearReach::Face& out = near.faces[static_cast<std::size_t>(f)];
    out.spec = reachFaceSpec(f, spec);
    const ObserverField field = computeField(integrator, out.spec, excluded, counter, exchange);
    throwIfStopped(counter);
    out.stats = field.stats();
    const RadialLattice& r = *out.spec.radial;
    const int n = r.face_cells;
    const std::size_t rays = rayIndex(n, n, n) + 1;
    out.reach_m.assign(thresholds, std::vector<float>(rays, 0.0f));
    out.peak_w_m2.assign(rays, 0.0f);
    // Each lattice point read once: bit t says whether it counts as hazardous for threshold t.
    // An Unconverged point may be short of its value by its error
    // (ObserverField::unconvergedUpper); the target's inside is no place. (nearReachScratchBytes()
    // counts these arrays.)
    const int layers = r.layers + 1;
    const auto at = [&](int i, int j, int k) {
      return (rayIndex(i, j, n) * static_cast<std::size_t>(layers)) + static_cast<std::size_t>(k);
    };
    const std::size_t points = rays * static_cast<std::size_t>(layers);
    if (counter != nullptr && !counter->admits(points * (sizeof(float) + sizeof(std::uint8_t))))
      throw WorkStopped();
    std::vector<std::uint8_t> hazard_bits(points, 0);
    // Each point's value as the squares between the rays read it: NaN inside the target.
    std::vector<float> value(points, std::numeric_limits<float>::quiet_NaN());
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i) {
        double peak = 0.0;
        for (int k = 0; k <= r.layers; ++k) {
          const VoxelStatus s = field.status(i, j, k);
          if (s == VoxelStatus::Excluded) continue;
          const double e = field.irradiance(i, j, k);
          value[at(i, j, k)] = static_cast<float>(e);
          peak = std::max(peak, e);
          const double upper = field.unconvergedUpper(i, j, k);
          std::uint8_t bits = 0;
          for (std::size_t t = 0; t < thresholds; ++t) {
            const bool hazardous = e >= hazardous_w_m2[t] || upper >= hazardous_w_m2[t];
            bits = static_cast<std::uint8_t>(bits | (hazardous ? 1u << t : 0u));
          }
          hazard_bits[at(i, j, k)] = bits;
        }
        out.peak_w_m2[rayIndex(i, j, n)] = static_cast<float>(peak);
      }
    // An Unresolved point may have a glint beside it that its lattice cannot see, up to its
    // block's bound: it counts for each threshold that bound reaches (the lowest threshold's
    // bound says nothing of the MPE's). Read from the few such points, not from a lattice of
    // bounds as large as the face's.
    field.forEachUnresolvedPoint([&](int i, int j, int k, float bound) {
      std::uint8_t& cell = hazard_bits[at(i, j, k)];
      for (std::size_t t = 0; t < thresholds; ++t) {
        if (!(static_cast<double>(bound) < hazardous_w_m2[t]))
          cell = static_cast<std::uint8_t>(cell | (1u << t));
      }
    });
    const auto hazardous = [&](int i, int j, int k, std::size_t t) {
      return ((hazard_bits[at(i, j, k)] >> t) & 1u) != 0;
    };
    const double step = 2.0 / n;
    std::vector<double> volume(thresholds, 0.0);
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i) {
        const double u = -1.0 + step * i, v = -1.0 + step * j;
        const double stretch = std::sqrt(1.0 + u * u + v * v);  // distance / ρ along this ray
        const std::size_t ray = rayIndex(i, j, n);
        for (std::size_t t = 0; t < thresholds; ++t) {
          for (int k = r.layers; k >= 0; --k) {
            if (!hazardous(i, j, k, t)) continue;
            out.reach_m[t][ray] =
                static_cast<float>(stretch * r.layerDistance(std::min(k + 1, r.layers)));
            break;
          }
        }
        if (i == n || j == n) continue;
        // Cell (i, j, k) holds ρ² dρ du dv: (ρ1³ − ρ0³) / 3 × step², weighted by the share of
        // its eight corners that are hazardous.
        for (int k = 0; k < r.layers; ++k) {
          const double a = r.layerDistance(k), b = r.layerDistance(k + 1);
          const double cell_m3 = step * step * (b * b * b - a * a * a) / 3.0;
          for (std::size_t t = 0; t < thresholds; ++t) {
            int corners = 0;
            for (int c = 0; c < 8; ++c)
              corners += hazardous(i + (c & 1), j + ((c >> 1) & 1), k + (c >> 2), t) ? 1 : 0;
            volume[t] += cell_m3 * corners / 8.0;
          }
        }
      }
    // Between the rays: each cell's squares beyond what its rays reach (see BetweenRays).
    out.between_plane_m.assign(thresholds,
                               std::vector<float>(static_cast<std::size_t>(n) * n, 0.0f));
    BetweenRays between(classifying, spec, out, value, excluded, counter);
    tbb::parallel_for(0, n * n, [&](int cell) {
      if (counter != nullptr && counter->stopRequested()) return;
      between.judgeCell(cell % n, cell / n);
    });
    if (counter != nullptr && counter->stopRequested()) throw WorkStopped();
    out.between_points = between.points();
    out.between_evaluations = between.evaluations();
    out.stats.evaluated_points += out.between_points;
    out.stats.evaluations += out.between_evaluations;
    // A square found hazardous holds four hazardous points in the volume's reckoning: a share
    // of the two cells either side of it.
    for (const BetweenRays::Found& found : between.found()) {
      for (int k = std::max(0, found.k - 1); k <= std::min(found.k, r.layers - 1); ++k) {
        const double a = r.layerDistance(k), b = r.layerDistance(k + 1);
        const double cell_m3 = step * step * (b * b * b - a * a * a) / 3.0;
        int corners = 0;
        for (int c = 0; c < 4; ++c)
          corners += hazardous(found.i + (c & 1), found.j + (c >> 1), found.k, found.t) ? 1 : 0;
        volume[found.t] += cell_m3 * (4 - corners) / 8.0;
      }
    }
    for (std::size_t t = 0; t < thresholds; ++t) near.volume_m3[t] += volume[t];
  }
  return near;
}

double reachToward(const NearReach& near, const FarField& far, std::size_t t, const Vec3& direction,
                   double extinction_per_m) {
  return std::max(near.toward(direction, t), farReachToward(far, near.spec.thresholds_w_m2.at(t),
                                                            extinction_per_m, direction));
}

ReachSummary summarizeReach(const NearReach& near, const FarField& far, std::size_t t,
                            const FarReach& beyond, double extinction_per_m) {
  ReachSummary s;
  s.threshold_w_m2 = near.spec.thresholds_w_m2.at(t);
  // The farthest of what toward() gives over every direction: within a lattice cell, the
  // farthest layer plane of its four rays and its own bounds taken along the cell's most
  // oblique corner, which lies beyond every one of the four rays' own reach where the farthest
  // plane is not that corner's.
  const int n = near.spec.face_cells;
  for (int f = 0; f < cube::kFaces; ++f) {
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const double plane_m = near.cellPlaneM(f, t, i, j);
        double stretch = 0.0;
        int corner_i = i, corner_j = j;
        for (int c = 0; c < 4; ++c) {
          const int a = i + (c & 1), b = j + (c >> 1);
          const double k = rayStretch(a, b, n);
          if (k > stretch) {
            stretch = k;
            corner_i = a;
            corner_j = b;
          }
        }
        const double d = plane_m * stretch;
        if (d > s.distance_m) {
          s.distance_m = d;
          s.direction = cube::planeDirection(f, corner_i, corner_j, n);
        }
      }
  }
  if (beyond.nohd_m > s.distance_m) {
    s.distance_m = beyond.nohd_m;
    s.direction = beyond.direction;
    s.from_far_field = true;
  }
  // Beyond each direction's last layer, the shell out to the far field's hazard distance,
  // over the map's lattice directions (their solid angles by the trapezoid rule on each face).
  // Row by row in parallel, the rows' sums added in order: the same sum on any threads.
  const int m = far.spec().face_pixels;
  const double h = 2.0 / m;
  std::vector<double> row_m3(static_cast<std::size_t>(FarField::kFaces) * (m + 1), 0.0);
  tbb::parallel_for(std::size_t{0}, row_m3.size(), [&](std::size_t row) {
    const int f = static_cast<int>(row / static_cast<std::size_t>(m + 1));
    const int j = static_cast<int>(row % static_cast<std::size_t>(m + 1));
    for (int i = 0; i <= m; ++i) {
      const Vec3 d = far.latticeDirection(f, i, j);
      const double r = far.hazardDistanceToward(d, far.latticeIntensity(f, i, j), s.threshold_w_m2,
                                                extinction_per_m);
      const double last = near.lastLayerToward(d);
      if (!(r > last) || !std::isfinite(r)) continue;
      const double u = -1.0 + h * i, v = -1.0 + h * j;
      const double weight = (i == 0 || i == m ? 0.5 : 1.0) * (j == 0 || j == m ? 0.5 : 1.0);
      const double solid_angle = weight * h * h / std::pow(1.0 + u * u + v * v, 1.5);
      row_m3[row] += solid_angle * (r * r * r - last * last * last) / 3.0;
    }
  });
  double shell_m3 = 0.0;
  for (const double v : row_m3) shell_m3 += v;
  s.unclassified_half_edge_m = reachStartM(near.spec);
  s.unclassified_m3 = 8.0 * std::pow(s.unclassified_half_edge_m, 3);
  s.volume_m3 = near.volume_m3.at(t) + shell_m3 + s.unclassified_m3;
  if (std::isfinite(s.distance_m))
    s.farthest_point_m = near.spec.centre_m + s.distance_m * s.direction;
  // The lattice reaches the far radius along every ray; beyond it the far field answers for
  // every direction only where its radius is one (verified) and every glint is bounded.
  s.closed = std::isfinite(s.distance_m) && far.spec().far_radius_verified &&
             near.spec.far_m >= far.spec().far_radius_m;
  return s;
}

std::vector<float> reachLatLong(const NearReach& near, const FarField& far,
                                const LatLongIntensity& beyond, std::size_t t,
                                double extinction_per_m) {
  const double threshold = near.spec.thresholds_w_m2.at(t);
  // The far field's largest hazard distance over each pixel (0 where it ends inside r_far).
  const std::vector<float> far_m = latLongHazardDistance(far, beyond, threshold, extinction_per_m);
  std::vector<float> reach(far_m.size());
  tbb::parallel_for(std::size_t{0}, reach.size(), [&](std::size_t p) {
    const Vec3 d = cube::latLongDirection(p, beyond.width, beyond.height);
    const double r = std::max(near.toward(d, t), static_cast<double>(far_m[p]));
    reach[p] = static_cast<float>(std::min(r, kFloatMax));
  });
  return reach;
}

ReachSurface reachSurface(const NearReach& near, const FarField& far, double extinction_per_m) {
  ReachSurface s;
  const int n = near.spec.face_cells;
  const double threshold = near.spec.thresholds_w_m2.at(0);
  const Vec3 centre = near.spec.centre_m;
  const auto row = static_cast<std::int64_t>(n + 1);
  for (int f = 0; f < cube::kFaces; ++f) {
    const NearReach::Face& face = near.faces[static_cast<std::size_t>(f)];
    const auto base = static_cast<std::int64_t>(s.points_m.size());
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i) {
        const Vec3 d = cube::planeDirection(f, i, j, n);
        const std::size_t ray = rayIndex(i, j, n);
        const double beyond = farReachToward(far, threshold, extinction_per_m, d);
        // The ray's own reach, and the squares between it and its neighbours (drawn through the
        // ray): the surface encloses what they count hazardous.
        double between_plane_m = 0.0;
        for (int c = 0; c < 4; ++c) {
          const int a = i - (c & 1), b = j - (c >> 1);
          if (a < 0 || b < 0 || a >= n || b >= n) continue;
          between_plane_m =
              std::max(between_plane_m,
                       static_cast<double>(face.between_plane_m[0][static_cast<std::size_t>(b) *
                                                                       static_cast<std::size_t>(n) +
                                                                   static_cast<std::size_t>(a)]));
        }
        const double r = std::max({static_cast<double>(face.reach_m[0][ray]),
                                   between_plane_m * rayStretch(i, j, n), beyond});
        // A glint the far field could not bound has no distance to draw: its point stays at
        // the lattice's end, and its distance reads as the largest float.
        s.points_m.push_back(centre + (std::isfinite(r) ? r : near.lastLayerToward(d)) * d);
        s.distance_m.push_back(static_cast<float>(std::min(r, kFloatMax)));
        s.hazard_ratio.push_back(
            static_cast<float>(static_cast<double>(face.peak_w_m2[ray]) / threshold));
      }
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const std::int64_t a = base + j * row + i;
        s.quads.push_back({a, a + 1, a + 1 + row, a + row});
      }
  }
  return s;
}

}  // namespace glint
