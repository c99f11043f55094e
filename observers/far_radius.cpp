// Where the far field begins: the first-order far radius brought in by checking E r² against
// I(ω) directly, sphere by sphere (verifyFarRadius()).
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <limits>
#include <numbers>
#include <optional>

#include "observers/far_field.h"

namespace glint {
namespace {

struct Direction {
  int face = 0;
  int i = 0, j = 0;  // lattice point; a located top has none (i < 0)
  Vec3 unit{1.0, 0.0, 0.0};
  double intensity_w_sr = 0.0;
};

std::vector<Direction> checkedDirections(const FarField& map) {
  std::vector<Direction> out;
  const auto row = static_cast<std::uint32_t>(map.spec().face_pixels + 1);
  for (int f = 0; f < FarField::kFaces; ++f) {
    for (const std::uint32_t p : map.faces()[static_cast<std::size_t>(f)].integrated) {
      const int i = static_cast<int>(p % row), j = static_cast<int>(p / row);
      out.push_back({f, i, j, map.latticeDirection(f, i, j), map.latticeIntensity(f, i, j)});
    }
  }
  for (const FarField::Peak& top : map.located()) {
    out.push_back({0, -1, -1, top.direction, top.intensity_w_sr});
  }
  return out;
}

// The worst share of the allowance on one sphere, and the direction where it is.
struct Worst {
  double share = 0.0;
  Vec3 direction{1.0, 0.0, 0.0};
  std::int64_t evaluations = 0;
  // Its place in the directions checked: of equal shares (a symmetric target's mirror twins)
  // the first is the worst, whichever thread or process read it.
  std::size_t index = std::numeric_limits<std::size_t>::max();

  [[nodiscard]] bool worseThan(const Worst& other) const {
    return share > other.share || (share == other.share && index < other.index);
  }
};

// The intensity at distance @p r_m whose irradiance is the lowest hazardous one (W/sr).
double hazardAt(const FarFieldSpec& spec, double r_m) {
  return spec.hazard_threshold_w_m2 * r_m * r_m;
}

// The integrator that reads E r² at distance @p r_m: a share of the allowance's tolerance and
// floor.
FacetIntegrator checkIntegrator(const FarField& map, const FacetIntegrator& integrator,
                                double r_m) {
  const FarFieldSpec& spec = map.spec();
  return integrator
      .withAccuracy(kFarRadiusReadShare * spec.tolerance,
                    kFarRadiusReadShare *
                        std::max(spec.floor_w_sr, spec.tolerance * hazardAt(spec, r_m)) /
                        (r_m * r_m))
      .withReturnExtinction(0.0);
}

// One sphere's check over directions first, first + stride, ... (a process's share).
Worst checkSphere(const FarField& map, const FacetIntegrator& at,
                  const std::vector<Direction>& dirs, double radius_m, std::size_t first,
                  std::size_t stride, WorkCounter* counter) {
  // Processes sharing the check agree on nothing but its result: one that stopped alone would
  // leave the others waiting, so a shared check runs to its end.
  const bool stoppable = counter != nullptr && stride == 1;
  const FarFieldSpec& spec = map.spec();
  const double a = map.ball().radius_m;
  const double parallax_rad = a / std::max(radius_m - a, 1e-300);
  // Lattice steps are 2/N rad apart at a face's centre and closer elsewhere: counting them at
  // the centre's spacing keeps the square inside the cone.
  const int steps = std::min(kFarRadiusReferenceSteps,
                             static_cast<int>(parallax_rad * spec.face_pixels / 2.0) + 1);
  const bool capped = steps == kFarRadiusReferenceSteps;
  const double hazard_w_sr = hazardAt(spec, radius_m);
  const std::size_t count = dirs.size() > first ? (dirs.size() - first + stride - 1) / stride : 0;
  // Every direction reads the brightest lattice point in its square: scanned, (2 steps + 1)²
  // reads each; from a window of the sphere's half-width, one read each once its two running
  // maxima (a few passes over every direction) are built. The cheaper of the two.
  const double side = 2.0 * steps + 1.0, lattice = spec.face_pixels + 1.0;
  std::optional<FarField::BrightestWindow> window;
  if (static_cast<double>(count) * side * side > 4.0 * FarField::kFaces * lattice * lattice) {
    window.emplace(map, steps);
  }
  tbb::enumerable_thread_specific<IntegratorWorkspace> workspaces;
  tbb::enumerable_thread_specific<Worst> worst;
  const double r2 = radius_m * radius_m;
  tbb::parallel_for(std::size_t{0}, count, [&](std::size_t k) {
    if (stoppable && counter->stopRequested()) return;
    if (counter != nullptr) counter->items_done.fetch_add(1, std::memory_order_relaxed);
    const Direction& d = dirs[first + k * stride];
    const double brightest_w_sr = d.i < 0  ? d.intensity_w_sr
                                  : window ? window->at(d.face, d.i, d.j)
                                           : map.brightestWithin(d.face, d.i, d.j, steps);
    // Dark within its whole parallax cone: every ray that reaches this observer leaves the
    // target in a direction where the intensity is at most the floor. Each lit point's own
    // light is part of the intensity in its direction, so only a focusing target gathers more,
    // at most the floor × (the cone / the lobe's width)²: 400 for σ = 0.003 at 16 lit radii.
    // The floor is a thousandth of the hazard's intensity at the innermost sphere
    // (farFieldSpec()), so such a direction is not hazardous unless the target focuses more
    // than a thousandfold, and is not read.
    if (!capped && brightest_w_sr <= spec.floor_w_sr) return;
    const ObserverResult o =
        at.adaptive(map.ball().centre_m + radius_m * d.unit, workspaces.local());
    const double near_w_sr = o.irradiance_w_m2 * r2;
    // The allowance: the tolerance × the brightest direction the parallax reaches or the
    // hazard's intensity at this distance, whichever is more, and the floor.
    const double allowance =
        spec.tolerance * std::max(brightest_w_sr, hazard_w_sr) + spec.floor_w_sr;
    // A located top's intensity is an upper estimate (its error and the rise its last step
    // allows are added): the near field may fall short of it, never pass it.
    const double departure_w_sr =
        d.i < 0 ? near_w_sr - d.intensity_w_sr : std::abs(near_w_sr - d.intensity_w_sr);
    double share = std::max(0.0, departure_w_sr) / allowance;
    if (!std::isfinite(share)) share = std::numeric_limits<double>::infinity();
    Worst& w = worst.local();
    w.evaluations += o.evaluations;
    const Worst here{share, d.unit, 0, first + k * stride};
    if (here.worseThan(w)) {
      w.share = here.share;
      w.direction = here.direction;
      w.index = here.index;
    }
    if (counter != nullptr)
      counter->evaluations.fetch_add(o.evaluations, std::memory_order_relaxed);
  });
  if (stoppable && counter->stopRequested()) throw WorkStopped();
  Worst all;
  for (const Worst& w : worst) {
    all.evaluations += w.evaluations;
    if (w.worseThan(all)) {
      all.share = w.share;
      all.direction = w.direction;
      all.index = w.index;
    }
  }
  return all;
}

// Every process's worst: the worst of them, of equal ones the first checked (so all agree, and
// with one process).
Worst gatherWorst(const Worst& mine, PointExchange* exchange) {
  if (exchange == nullptr) return mine;
  // The index as a double, exact below 2⁵³ directions; −1 where a process read none.
  constexpr std::size_t kNone = std::numeric_limits<std::size_t>::max();
  std::array<double, 6> packed = {mine.share,
                                  mine.direction.x,
                                  mine.direction.y,
                                  mine.direction.z,
                                  static_cast<double>(mine.evaluations),
                                  mine.index == kNone ? -1.0 : static_cast<double>(mine.index)};
  std::vector<std::byte> bytes(sizeof(packed));
  std::memcpy(bytes.data(), packed.data(), sizeof(packed));
  Worst all;
  bool first = true;
  for (const std::vector<std::byte>& theirs : exchange->allGather(bytes)) {
    std::memcpy(packed.data(), theirs.data(), sizeof(packed));
    all.evaluations += static_cast<std::int64_t>(packed[4]);
    const Worst theirs_worst{packed[0], Vec3(packed[1], packed[2], packed[3]), 0,
                             packed[5] < 0.0 ? kNone : static_cast<std::size_t>(packed[5])};
    if (first || theirs_worst.worseThan(all)) {
      all.share = theirs_worst.share;
      all.direction = theirs_worst.direction;
      all.index = theirs_worst.index;
      first = false;
    }
  }
  return all;
}

}  // namespace

FarRadiusCheck verifyFarRadius(const FarField& map, const FacetIntegrator& integrator,
                               WorkCounter* counter, PointExchange* exchange) {
  const auto start = std::chrono::steady_clock::now();
  const FarFieldSpec& spec = map.spec();
  FarRadiusCheck check;
  const double innermost_m = spec.innermost_far_radius_m;
  const double first_m =
      spec.first_order_far_radius_m > 0.0 ? spec.first_order_far_radius_m : spec.far_radius_m;
  // Nothing to check unless the floor lets the check go at least one sphere in.
  if (!(innermost_m > 0.0) || !(0.5 * first_m >= innermost_m)) return check;
  if (exchange != nullptr && exchange->size() <= 1) exchange = nullptr;
  const std::vector<Direction> dirs = checkedDirections(map);
  check.directions = static_cast<std::int64_t>(dirs.size());
  const std::size_t first = exchange != nullptr ? static_cast<std::size_t>(exchange->rank()) : 0;
  const std::size_t stride = exchange != nullptr ? static_cast<std::size_t>(exchange->size()) : 1;
  // Halving from the first radius to the innermost, and one between at the end.
  const int spheres_at_most = static_cast<int>(std::floor(std::log2(first_m / innermost_m))) + 2;
  const auto sphere = [&](double r) {
    if (counter != nullptr) {
      const std::size_t mine =
          dirs.size() > first ? (dirs.size() - first + stride - 1) / stride : 0;
      counter->items_scheduled.fetch_add(mine);
      counter->beginStep("sphere", static_cast<int>(check.spheres.size()) + 1, spheres_at_most,
                         mine);
    }
    const Worst w = gatherWorst(
        checkSphere(map, checkIntegrator(map, integrator, r), dirs, r, first, stride, counter),
        exchange);
    check.evaluations += w.evaluations;
    check.spheres.push_back({r, w.share, w.direction, w.share <= 1.0});
    return check.spheres.back().holds;
  };
  // By halves inward while each sphere holds; where one fails, the sphere between it and the
  // last that held, a factor √2 from each, settles the radius to that factor.
  for (double r = first_m; r >= innermost_m; r *= 0.5) {
    if (!sphere(r)) {
      const double between_m = r * std::numbers::sqrt2;
      if (check.radius_m > 0.0 && between_m >= innermost_m && sphere(between_m)) {
        check.radius_m = between_m;
      }
      break;
    }
    check.radius_m = r;
  }
  check.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return check;
}

}  // namespace glint
