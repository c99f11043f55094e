#include "observers/point_set.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <string>

namespace glint {

void shareObservers(PointExchange& exchange, std::size_t observers,
                    const std::function<void(std::span<const std::size_t>, WireWriter&)>& compute,
                    const std::function<void(std::size_t, WireReader&)>& take) {
  // Every size-th observer from this rank on: neighbours in a points file or a lattice cost
  // alike, so interleaving balances the processes better than cutting the list in runs.
  const auto share = static_cast<std::size_t>(exchange.size());
  const auto rank = static_cast<std::size_t>(exchange.rank());
  std::vector<std::size_t> mine;
  for (std::size_t o = rank; o < observers; o += share) mine.push_back(o);
  WireWriter records;
  bool stopped = false;
  try {
    compute(mine, records);
  } catch (const WorkStopped&) {
    stopped = true;  // said to the others, so that every process stops here
  }
  WireWriter message;
  message.put<std::uint8_t>(stopped ? 1 : 0);
  message.append(records.bytes());
  const std::vector<std::vector<std::byte>> all = exchange.allGather(message.bytes());
  if (all.size() != share) throw std::runtime_error("observer exchange: a process is missing");
  for (const std::vector<std::byte>& from : all) {
    if (WireReader(from).get<std::uint8_t>() != 0) stopped = true;
  }
  if (stopped) throw WorkStopped();
  for (std::size_t p = 0; p < share; ++p) {
    WireReader from(all[p]);
    from.get<std::uint8_t>();
    for (std::size_t o = p; o < observers; o += share) take(o, from);
    if (from.left() != 0) {
      throw std::runtime_error("observer exchange: process " + std::to_string(p) +
                               " sent more than its observers' records");
    }
  }
}

std::vector<ObserverResult> evaluatePoints(const FacetIntegrator& integrator,
                                           std::span<const Vec3> points_m,
                                           const PointScheme& scheme, WorkCounter* counter,
                                           PointExchange* exchange) {
  if (exchange != nullptr && exchange->size() > 1) {
    std::vector<ObserverResult> results(points_m.size());
    shareObservers(
        *exchange, points_m.size(),
        [&](std::span<const std::size_t> mine, WireWriter& out) {
          std::vector<Vec3> mine_m;
          for (std::size_t o : mine) mine_m.push_back(points_m[o]);
          for (const ObserverResult& r : evaluatePoints(integrator, mine_m, scheme, counter)) {
            out.put(r.irradiance_w_m2);
            out.put(r.error_estimate_w_m2);
            out.put(r.evaluations);
            out.put<std::uint8_t>((r.converged ? 1 : 0) | (r.depth_limited ? 2 : 0));
          }
        },
        [&](std::size_t o, WireReader& in) {
          ObserverResult& r = results[o];
          r.irradiance_w_m2 = in.get<double>();
          r.error_estimate_w_m2 = in.get<double>();
          r.evaluations = in.get<std::int64_t>();
          const auto flags = in.get<std::uint8_t>();
          r.converged = (flags & 1) != 0;
          r.depth_limited = (flags & 2) != 0;
        });
    return results;
  }
  std::vector<ObserverResult> results(points_m.size());
  tbb::enumerable_thread_specific<IntegratorWorkspace> workspaces;
  // Observers differ in cost by orders of magnitude (a glint or none), so chunks stay small.
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, points_m.size(), 4),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      IntegratorWorkspace& ws = workspaces.local();
                      std::int64_t evaluations = 0;
                      for (std::size_t i = range.begin(); i != range.end(); ++i) {
                        // Before each point: one observer of a large target can take seconds
                        // and grow its workspace by hundreds of MB.
                        if (counter != nullptr && counter->stopRequested()) return;
                        results[i] = scheme.uniform
                                         ? integrator.uniform(points_m[i], scheme.uniform_level, ws)
                                         : integrator.adaptive(points_m[i], ws);
                        evaluations += results[i].evaluations;
                      }
                      if (counter != nullptr) {
                        counter->items_done += range.size();
                        counter->evaluations += evaluations;
                      }
                    });
  if (counter != nullptr && counter->stopRequested()) throw WorkStopped();
  return results;
}

}  // namespace glint
