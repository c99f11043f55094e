#pragma once
/// @file
/// @brief Irradiance at a list of observer points, computed in parallel over the points.

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <span>
#include <stdexcept>
#include <vector>

#include "facets/integrator.h"

namespace glint {

/// @brief Progress of a long computation, updated by worker threads and read by a reporter.
struct WorkCounter {
  std::atomic<std::size_t> items_done{0};
  std::atomic<std::int64_t> evaluations{0};
  /// Items known so far, where the total is not known in advance (the adaptive field learns
  /// its points level by level).
  std::atomic<std::size_t> items_scheduled{0};
  /// Raised by whoever watches the run (pipeline/memory_budget.h); the work then stops at its
  /// next item and throws WorkStopped from outside its parallel loops.
  const std::atomic<bool>* stop = nullptr;

  [[nodiscard]] bool stopRequested() const {
    return stop != nullptr && stop->load(std::memory_order_relaxed);
  }
};

/// @brief The processes that share one field's point evaluations (an MPI job: pipeline/cluster.h).
/// Each evaluates its share of every level's new points and all receive every value, so every
/// process holds the same field, as one process would have computed it.
class PointExchange {
 public:
  virtual ~PointExchange() = default;
  [[nodiscard]] virtual int rank() const = 0;
  [[nodiscard]] virtual int size() const = 0;
  /// @brief Collective: every process passes its own bytes and receives every process's, in
  /// rank order. Called by all processes the same number of times.
  virtual std::vector<std::vector<std::byte>> allGather(std::span<const std::byte> mine) = 0;
};

/// @brief The work was stopped through WorkCounter::stop; the one who raised it says why.
class WorkStopped : public std::runtime_error {
 public:
  WorkStopped() : std::runtime_error("stopped on request") {}
};

/// @brief Which integration every point gets.
struct PointScheme {
  bool uniform = false;   ///< false: adaptive (the default); true: the uniform twin
  int uniform_level = 0;  ///< subdivision level of the uniform twin
};

/// @brief E at each of @p points_m (world coordinates), in input order, with TBB across
/// points. Each thread reuses one workspace, so no allocation happens per point once the
/// workspaces have grown. Results do not depend on the number of threads.
/// @param counter optional; advanced as points complete.
std::vector<ObserverResult> evaluatePoints(const FacetIntegrator& integrator,
                                           std::span<const Vec3> points_m,
                                           const PointScheme& scheme,
                                           WorkCounter* counter = nullptr);

}  // namespace glint
