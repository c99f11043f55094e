#include "observers/exposure.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>

#include "facets/sum.h"

namespace glint {
namespace {

// Times are integers on the finest dyadic grid of the span, so that observers that split the
// same interval share its samples and bounds, and no time drifts by rounding.
struct TimeGrid {
  double start_s = 0.0;
  double duration_s = 0.0;
  std::int64_t ticks = 1;  // grid steps in the span
  [[nodiscard]] double at(std::int64_t k) const {
    return start_s + duration_s * (static_cast<double>(k) / static_cast<double>(ticks));
  }
};

// An interval of one observer's span still to be decided, its ends' irradiance known.
struct Open {
  std::size_t observer = 0;
  std::int64_t k0 = 0, k1 = 0;
  int depth = 0;
  double e0 = 0.0, e1 = 0.0;
  // Filled by the round:
  double upper_w_m2 = 0.0;   // bound over the interval
  double narrow_w_m2 = 0.0;  // bound of light narrower than the samples' spacing
  double em = 0.0;           // the middle's irradiance
  // The interval it is half of already met the tolerance (not the narrow-glint rule). An
  // interval is accepted only where its parent's check agreed with its own: one check alone
  // can be met by chance, where the errors of its two halves cancel (a glint's flanks about
  // their inflection points: a 15 ms glint read 1.4 % low before).
  bool parent_followed = false;
};

struct Sample {
  std::int64_t k = 0;
  double irradiance_w_m2 = 0.0;
};

// How far from the pivot the target reaches: the light of any facet travels at most an
// observer's distance from the pivot plus this.
double targetRadiusM(const Target& target, const Vec3& pivot_m) {
  double r = 0.0;
  for (std::size_t i = 0; i < target.facetCount(); ++i) {
    const Vec3 origin = target.objects[target.object[i]].origin_m;
    for (const Vec3& c : target.corners_m[i]) r = std::max(r, glm::length(c + origin - pivot_m));
  }
  return r;
}

// Calls fn(first, last) for each run of @p items (sorted by key) with equal keys, in parallel.
template <class Item, class Key, class Fn>
void forEachGroup(std::vector<Item>& items, Key key, Fn fn) {
  std::vector<std::pair<std::size_t, std::size_t>> runs;
  for (std::size_t i = 0; i < items.size();) {
    std::size_t j = i + 1;
    while (j < items.size() && key(items[j]) == key(items[i])) ++j;
    runs.emplace_back(i, j);
    i = j;
  }
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, runs.size(), 1),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      for (std::size_t r = range.begin(); r != range.end(); ++r) {
                        fn(runs[r].first, runs[r].second);
                      }
                    });
}

// The irradiance of @p e0, @p em, @p e1 (equally spaced) interpolated by a parabola, at its top
// where that lies inside and the parabola is concave; otherwise the largest of the three.
double parabolaTop(double e0, double em, double e1) {
  const double largest = std::max({e0, em, e1});
  const double curvature = e0 - 2.0 * em + e1;
  if (!(curvature < 0.0)) return largest;
  const double u = -(e1 - e0) / (2.0 * curvature);
  if (!(std::abs(u) < 1.0)) return largest;
  return std::max(largest, em - (e1 - e0) * (e1 - e0) / (8.0 * curvature));
}

// The exposure (trapezoids through the samples) and the peak of @p h's samples.
void totalUp(ExposureHistory& h) {
  CompensatedSum exposure;
  for (std::size_t i = 0; i < h.time_s.size(); ++i) {
    if (i == 0 || h.irradiance_w_m2[i] > h.peak_w_m2) {
      h.peak_w_m2 = h.irradiance_w_m2[i];
      h.peak_time_s = h.time_s[i];
    }
    if (i > 0) {
      exposure.add(0.5 * (h.irradiance_w_m2[i - 1] + h.irradiance_w_m2[i]) *
                   (h.time_s[i] - h.time_s[i - 1]));
    }
  }
  h.exposure_j_m2 = exposure.value();
}

// The bound of what the ball (@p centre_m at t = 0, @p radius_m) riding the motion's platform
// receives over [t0, t1], under @p swept, the integrator of the interval's swept beam, and of
// the light narrower than what the samples at its ends and middle are apart in it.
// @p target_radius_m: how far the target reaches from the pivot.
BallBound boundOverInterval(const FacetIntegrator& swept, const Motion& motion, double t0,
                            double t1, const Vec3& centre_m, double radius_m, double floor_w_m2,
                            double target_radius_m, std::vector<Candidate>& kept) {
  const double mid = 0.5 * (t0 + t1);
  const Vec3 centre = motion.toTargetFrame(mid, motion.observerAt(mid, centre_m));
  // Each point of the ball sweeps as its centre does, and further by the target's turn over
  // the ball's own radius.
  const double sweep = motion.observerSweepM(t0, t1, centre_m) +
                       0.5 * (t1 - t0) * motion.ratesOver(t0, t1).target_turn_rad_s * radius_m;
  BallBoundOptions o;
  // Between the samples the observer moves through the light by its own sweep and by what the
  // beam's turn moves the reflection over the distance to the target.
  const double distance = glm::length(centre - motion.spec().pivot_m) + target_radius_m;
  o.sample_spacing_m = sweep + distance * swept.beam().sweep_angle_rad;
  // Only whether the interval is dark, and the narrow light, are asked of the bound: light
  // within half the floor may go, and a few splits tighten it where a long interval's ball sees
  // part of a facet's light. Split deeper, a mesh's facets multiply by thousands at every one
  // of its intervals.
  o.drop_allowance_w_m2 = 0.5 * floor_w_m2;
  o.max_split_depth = 3;
  return swept.boundBall(centre, radius_m + sweep, swept.candidates(), 0.0, o, kept);
}

// One observer's history on the wire (integrateExposures() under MPI): its sample count,
// times, irradiances and totals.
void putHistory(WireWriter& out, const ExposureHistory& h) {
  out.put<std::uint64_t>(h.time_s.size());
  for (double t : h.time_s) out.put(t);
  for (double e : h.irradiance_w_m2) out.put(e);
  for (double v : {h.exposure_j_m2, h.error_j_m2, h.peak_w_m2, h.peak_time_s}) out.put(v);
  out.put<std::int64_t>(h.evaluations);
  out.put<std::uint8_t>(h.converged ? 1 : 0);
}

ExposureHistory getHistory(WireReader& in) {
  ExposureHistory h;
  const auto n = in.get<std::uint64_t>();
  if (n > in.left() / (2 * sizeof(double)))
    throw std::runtime_error("exposure exchange: a history longer than its message");
  h.time_s.resize(n);
  h.irradiance_w_m2.resize(n);
  for (double& t : h.time_s) t = in.get<double>();
  for (double& e : h.irradiance_w_m2) e = in.get<double>();
  h.exposure_j_m2 = in.get<double>();
  h.error_j_m2 = in.get<double>();
  h.peak_w_m2 = in.get<double>();
  h.peak_time_s = in.get<double>();
  h.evaluations = in.get<std::int64_t>();
  h.converged = in.get<std::uint8_t>() != 0;
  return h;
}

class ExposureRun {
 public:
  ExposureRun(const FacetIntegrator& reference, const Motion& motion,
              std::span<const Vec3> observers, const ExposureOptions& options, WorkCounter* counter)
      : reference_(reference),
        motion_(motion),
        observers_(observers),
        options_(options),
        counter_(counter),
        samples_(observers.size()),
        histories_(observers.size()),
        accepted_j_m2_(observers.size(), 0.0) {
    grid_.start_s = motion.spec().start_s;
    grid_.duration_s = motion.durationS();
    grid_.ticks = std::int64_t{options.initial_intervals} << options.max_depth;
    target_radius_m_ = targetRadiusM(reference.target(), motion.spec().pivot_m);
  }

  std::vector<ExposureHistory> run() {
    const std::int64_t step = std::int64_t{1} << options_.max_depth;
    // The initial samples, every observer at every initial time.
    std::vector<Open> first;
    for (std::size_t o = 0; o < observers_.size(); ++o) {
      for (int j = 0; j <= options_.initial_intervals; ++j) {
        first.push_back({o, j * step, j * step, 0});
      }
    }
    sample(
        first, [](const Open& w) { return w.k0; }, [](Open& w, double e) { w.e0 = e; });
    const auto per_observer = static_cast<std::size_t>(options_.initial_intervals) + 1;
    std::vector<double> initial(observers_.size() * per_observer);
    for (const Open& w : first) initial[w.observer * per_observer + w.k0 / step] = w.e0;
    std::vector<Open> open;
    for (std::size_t o = 0; o < observers_.size(); ++o) {
      for (std::size_t j = 0; j + 1 < per_observer; ++j) {
        const auto k = static_cast<std::int64_t>(j) * step;
        open.push_back(
            {o, k, k + step, 0, initial[o * per_observer + j], initial[o * per_observer + j + 1]});
      }
    }
    while (!open.empty()) {
      if (counter_ != nullptr && counter_->stopRequested()) throw WorkStopped();
      open = round(std::move(open));
    }
    return finish();
  }

 private:
  // Bounds every open interval, samples the middle of those not proven dark, and returns the
  // halves of those whose samples do not yet follow the irradiance.
  std::vector<Open> round(std::vector<Open> open) {
    std::sort(open.begin(), open.end(), [](const Open& a, const Open& b) {
      return a.k0 != b.k0 ? a.k0 < b.k0 : (a.k1 != b.k1 ? a.k1 < b.k1 : a.observer < b.observer);
    });
    bound(open);
    std::vector<Open> lit;
    for (Open& w : open) {
      if (w.upper_w_m2 <= options_.floor_w_m2) {
        acceptDark(w);
      } else if (w.depth >= options_.max_depth) {
        // As short as allowed and not followed: its trapezoid stands, its bound the error,
        // the observer unconverged.
        histories_[w.observer].converged = false;
        histories_[w.observer].error_j_m2 += w.upper_w_m2 * length(w);
        accepted_j_m2_[w.observer] += whole(w);
      } else {
        lit.push_back(w);
      }
    }
    sample(
        lit, [](const Open& w) { return (w.k0 + w.k1) / 2; }, [](Open& w, double e) { w.em = e; });
    // Each observer's exposure as the samples now tell it: what an interval's share of the
    // tolerance is measured against where it cannot be measured against its own.
    std::vector<double> estimate = accepted_j_m2_;
    for (const Open& w : lit) estimate[w.observer] += halves(w);
    std::vector<Open> next;
    for (const Open& w : lit) {
      const std::int64_t km = (w.k0 + w.k1) / 2;
      const bool smooth = changeWithinTolerance(w, estimate[w.observer]);
      const bool followed = smooth && w.parent_followed && w.narrow_w_m2 <= options_.floor_w_m2;
      if (followed) {
        accept(w);
        continue;
      }
      Open left{w.observer, w.k0, km, w.depth + 1, w.e0, w.em};
      Open right{w.observer, km, w.k1, w.depth + 1, w.em, w.e1};
      left.parent_followed = right.parent_followed = smooth;
      next.push_back(left);
      next.push_back(right);
    }
    return next;
  }

  // Each interval's bound: the swept beam of the interval over the ball its observer sweeps
  // in the target's frame, one culled integrator per distinct interval.
  void bound(std::vector<Open>& open) {
    tbb::enumerable_thread_specific<std::vector<Candidate>> kept_lists;
    forEachGroup(
        open, [](const Open& w) { return std::pair(w.k0, w.k1); },
        [&](std::size_t first, std::size_t last) {
          const double t0 = grid_.at(open[first].k0), t1 = grid_.at(open[first].k1);
          const FacetIntegrator integrator = reference_.withBeam(motion_.sweptBeam(t0, t1));
          std::vector<Candidate>& kept = kept_lists.local();
          for (std::size_t i = first; i < last; ++i) {
            Open& w = open[i];
            const BallBound b =
                boundOverInterval(integrator, motion_, t0, t1, observers_[w.observer], 0.0,
                                  options_.floor_w_m2, target_radius_m_, kept);
            w.upper_w_m2 = b.upper_w_m2;
            w.narrow_w_m2 = b.narrow_w_m2;
          }
        });
  }

  // Evaluates E at time key(w) for each of @p work, one integrator per distinct time, and
  // stores it with store(w, E) and in the observer's samples.
  template <class KeyFn, class StoreFn>
  void sample(std::vector<Open>& work, KeyFn key, StoreFn store) {
    std::sort(work.begin(), work.end(), [&](const Open& a, const Open& b) {
      return key(a) != key(b) ? key(a) < key(b) : a.observer < b.observer;
    });
    if (counter_ != nullptr) counter_->items_scheduled += work.size();
    tbb::enumerable_thread_specific<IntegratorWorkspace> workspaces;
    std::vector<ObserverResult> results(work.size());
    forEachGroup(work, key, [&](std::size_t first, std::size_t last) {
      const double t = grid_.at(key(work[first]));
      const FacetIntegrator integrator = reference_.withBeam(motion_.beamAt(t));
      tbb::parallel_for(tbb::blocked_range<std::size_t>(first, last, 4),
                        [&](const tbb::blocked_range<std::size_t>& range) {
                          IntegratorWorkspace& ws = workspaces.local();
                          std::int64_t evaluations = 0;
                          for (std::size_t i = range.begin(); i != range.end(); ++i) {
                            const Vec3 x = motion_.toTargetFrame(
                                t, motion_.observerAt(t, observers_[work[i].observer]));
                            results[i] = integrator.adaptive(x, ws);
                            evaluations += results[i].evaluations;
                          }
                          if (counter_ != nullptr) {
                            counter_->items_done += range.size();
                            counter_->evaluations += evaluations;
                          }
                        });
    });
    for (std::size_t i = 0; i < work.size(); ++i) {
      store(work[i], results[i].irradiance_w_m2);
      ExposureHistory& h = histories_[work[i].observer];
      h.evaluations += results[i].evaluations;
      h.converged = h.converged && results[i].converged;
      samples_[work[i].observer].push_back({key(work[i]), results[i].irradiance_w_m2});
    }
  }

  [[nodiscard]] double length(const Open& w) const { return grid_.at(w.k1) - grid_.at(w.k0); }
  // The interval's exposure through its three samples, and through its ends alone.
  [[nodiscard]] double halves(const Open& w) const {
    return 0.25 * (w.e0 + 2.0 * w.em + w.e1) * length(w);
  }
  [[nodiscard]] double whole(const Open& w) const { return 0.5 * (w.e0 + w.e1) * length(w); }

  // Whether halving the interval changed neither its exposure nor its peak by more than the
  // tolerance (the floor's worth, where that is more). An interval whose change is within a
  // 64th of the tolerance of the observer's whole exposure (@p estimate_j_m2) passes whatever
  // its own share: where the irradiance jumps (a facet's shadow switching on), the change is
  // a fixed part of the interval's own exposure however short it gets, but it shrinks with the
  // interval against the whole, and a jump hides no peak. Each jump so accepted costs at most
  // that 64th.
  [[nodiscard]] bool changeWithinTolerance(const Open& w, double estimate_j_m2) const {
    const double dt = length(w);
    const double change = std::abs(halves(w) - whole(w)) / 3.0;
    if (change <= options_.tolerance * estimate_j_m2 / 64.0) return true;
    const double largest = std::max({w.e0, w.em, w.e1});
    const double gap = parabolaTop(w.e0, w.em, w.e1) - largest;
    return change <= std::max(options_.tolerance * halves(w), options_.floor_w_m2 * dt) &&
           gap <= std::max(options_.tolerance * largest, options_.floor_w_m2);
  }

  void acceptDark(const Open& w) {
    histories_[w.observer].error_j_m2 += w.upper_w_m2 * length(w);
    accepted_j_m2_[w.observer] += whole(w);
  }

  void accept(const Open& w) {
    histories_[w.observer].error_j_m2 += std::abs(halves(w) - whole(w)) / 3.0;
    accepted_j_m2_[w.observer] += halves(w);
  }

  std::vector<ExposureHistory> finish() {
    for (std::size_t o = 0; o < observers_.size(); ++o) {
      std::vector<Sample>& s = samples_[o];
      std::sort(s.begin(), s.end(), [](const Sample& a, const Sample& b) { return a.k < b.k; });
      ExposureHistory& h = histories_[o];
      h.time_s.reserve(s.size());
      h.irradiance_w_m2.reserve(s.size());
      for (const Sample& sample : s) {
        h.time_s.push_back(grid_.at(sample.k));
        h.irradiance_w_m2.push_back(sample.irradiance_w_m2);
      }
      totalUp(h);
    }
    return std::move(histories_);
  }

  const FacetIntegrator& reference_;
  const Motion& motion_;
  std::span<const Vec3> observers_;
  ExposureOptions options_;
  WorkCounter* counter_;
  TimeGrid grid_;
  double target_radius_m_ = 0.0;
  std::vector<std::vector<Sample>> samples_;
  std::vector<ExposureHistory> histories_;
  std::vector<double> accepted_j_m2_;  // per observer: the intervals accepted so far
};

}  // namespace

std::vector<std::uint8_t> litByBound(const FacetIntegrator& reference, const Motion& motion,
                                     const FieldSpec& lattice, const ExposureOptions& options) {
  constexpr int kTimeLevels = 4;  // an initial interval and its halves, to three levels
  const int first = options.initial_intervals;
  const double start = motion.spec().start_s, duration = motion.durationS();
  // The swept integrators of every interval of every level, level l holding first × 2^l.
  std::vector<std::vector<std::unique_ptr<FacetIntegrator>>> swept(kTimeLevels);
  const double target_radius_m = targetRadiusM(reference.target(), motion.spec().pivot_m);
  auto bounds = [&](int level, int index) {
    const double n = static_cast<double>(first << level);
    return std::pair(start + duration * (index / n), start + duration * ((index + 1) / n));
  };
  for (int level = 0; level < kTimeLevels; ++level) {
    swept[level].resize(static_cast<std::size_t>(first) << level);
    tbb::parallel_for(std::size_t{0}, swept[level].size(), [&](std::size_t i) {
      const auto [t0, t1] = bounds(level, static_cast<int>(i));
      swept[level][i] =
          std::make_unique<FacetIntegrator>(reference.withBeam(motion.sweptBeam(t0, t1)));
    });
  }
  tbb::enumerable_thread_specific<std::vector<Candidate>> kept_lists;
  // Whether some instant of interval (level, index) may light the ball above the floor.
  std::function<bool(int, int, const Vec3&, double, std::vector<Candidate>&)> mayLight =
      [&](int level, int index, const Vec3& centre, double radius, std::vector<Candidate>& kept) {
        const auto [t0, t1] = bounds(level, index);
        const FacetIntegrator& integrator = *swept[level][static_cast<std::size_t>(index)];
        const BallBound b = boundOverInterval(integrator, motion, t0, t1, centre, radius,
                                              options.floor_w_m2, target_radius_m, kept);
        if (b.upper_w_m2 <= options.floor_w_m2) return false;
        if (level + 1 == kTimeLevels) return true;
        return mayLight(level + 1, 2 * index, centre, radius, kept) ||
               mayLight(level + 1, 2 * index + 1, centre, radius, kept);
      };

  const std::array<int, 3> n = lattice.nodes();
  const auto at = [&](int i, int j, int k) {
    return (static_cast<std::size_t>(k) * static_cast<std::size_t>(n[1]) +
            static_cast<std::size_t>(j)) *
               static_cast<std::size_t>(n[0]) +
           static_cast<std::size_t>(i);
  };
  std::vector<std::uint8_t> lit(at(0, 0, n[2]), 0);
  // A plane's blocks are squares (its one layer of nodes), a box's cubes.
  const int depth = lattice.plane ? 0 : 1;
  struct Block {
    int i = 0, j = 0, k = 0, size = 0;  // its lower corner node and its edge in cells
  };
  std::vector<Block> blocks;
  const int top = lattice.block_voxels;
  for (int k = 0; k == 0 || k + 1 < n[2]; k += top)
    for (int j = 0; j + 1 < n[1]; j += top)
      for (int i = 0; i + 1 < n[0]; i += top) blocks.push_back({i, j, k, top});
  while (!blocks.empty()) {
    std::vector<std::uint8_t> lit_block(blocks.size(), 0);
    tbb::parallel_for(std::size_t{0}, blocks.size(), [&](std::size_t b) {
      const Block& c = blocks[b];
      const int far = c.size * depth;
      const Vec3 centre = 0.5 * (lattice.position(c.i, c.j, c.k) +
                                 lattice.position(c.i + c.size, c.j + c.size, c.k + far));
      const double radius = lattice.voxel_m * 0.5 * c.size * std::sqrt(2.0 + depth);
      std::vector<Candidate>& kept = kept_lists.local();
      for (int index = 0; index < first; ++index) {
        if (mayLight(0, index, centre, radius, kept)) {
          lit_block[b] = 1;
          return;
        }
      }
    });
    std::vector<Block> next;
    for (std::size_t b = 0; b < blocks.size(); ++b) {
      if (lit_block[b] == 0) continue;
      const Block& c = blocks[b];
      if (c.size == 1) {
        for (int dk = 0; dk <= depth; ++dk)
          for (int dj = 0; dj <= 1; ++dj)
            for (int di = 0; di <= 1; ++di) lit[at(c.i + di, c.j + dj, c.k + dk)] = 1;
        continue;
      }
      const int h = c.size / 2;
      for (int dk = 0; dk <= depth; ++dk)
        for (int dj = 0; dj <= 1; ++dj)
          for (int di = 0; di <= 1; ++di)
            next.push_back({c.i + di * h, c.j + dj * h, c.k + dk * h, h});
    }
    blocks = std::move(next);
  }
  return lit;
}

std::vector<ExposureHistory> integrateExposures(const FacetIntegrator& reference,
                                                const Motion& motion,
                                                std::span<const Vec3> observers_m,
                                                const ExposureOptions& options,
                                                WorkCounter* counter, PointExchange* exchange) {
  if (exchange == nullptr || exchange->size() <= 1) {
    return ExposureRun(reference, motion, observers_m, options, counter).run();
  }
  std::vector<ExposureHistory> out(observers_m.size());
  shareObservers(
      *exchange, observers_m.size(),
      [&](std::span<const std::size_t> mine, WireWriter& to) {
        std::vector<Vec3> mine_m;
        for (std::size_t o : mine) mine_m.push_back(observers_m[o]);
        for (const ExposureHistory& h :
             ExposureRun(reference, motion, mine_m, options, counter).run()) {
          putHistory(to, h);
        }
      },
      [&](std::size_t o, WireReader& from) { out[o] = getHistory(from); });
  return out;
}

std::vector<ExposureHistory> uniformExposures(const FacetIntegrator& reference,
                                              const Motion& motion,
                                              std::span<const Vec3> observers_m, int steps) {
  const std::size_t n = observers_m.size();
  const auto samples = static_cast<std::size_t>(steps) + 1;
  std::vector<ObserverResult> results(samples * n);
  tbb::enumerable_thread_specific<IntegratorWorkspace> workspaces;
  const double start = motion.spec().start_s, duration = motion.durationS();
  auto time = [&](std::size_t j) {
    return start + duration * (static_cast<double>(j) / static_cast<double>(steps));
  };
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, samples, 1),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      IntegratorWorkspace& ws = workspaces.local();
                      for (std::size_t j = range.begin(); j != range.end(); ++j) {
                        const double t = time(j);
                        const FacetIntegrator integrator = reference.withBeam(motion.beamAt(t));
                        for (std::size_t o = 0; o < n; ++o) {
                          const Vec3 x =
                              motion.toTargetFrame(t, motion.observerAt(t, observers_m[o]));
                          results[j * n + o] = integrator.adaptive(x, ws);
                        }
                      }
                    });
  std::vector<ExposureHistory> out(n);
  for (std::size_t o = 0; o < n; ++o) {
    ExposureHistory& h = out[o];
    for (std::size_t j = 0; j < samples; ++j) {
      const ObserverResult& r = results[j * n + o];
      h.time_s.push_back(time(j));
      h.irradiance_w_m2.push_back(r.irradiance_w_m2);
      h.evaluations += r.evaluations;
      h.converged = h.converged && r.converged;
    }
    totalUp(h);
  }
  return out;
}

}  // namespace glint
