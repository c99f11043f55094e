#include "observers/point_set.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

namespace glint {

std::vector<ObserverResult> evaluatePoints(const FacetIntegrator& integrator,
                                           std::span<const Vec3> points_m,
                                           const PointScheme& scheme, WorkCounter* counter) {
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
