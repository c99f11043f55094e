#pragma once
/// @file
/// @brief Irradiance at a list of observer points, computed in parallel over the points.

#include <atomic>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <functional>
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
  /// Raised by whoever watches the run (pipeline/base/memory_budget.h); the work then stops at its
  /// next item and throws WorkStopped from outside its parallel loops.
  const std::atomic<bool>* stop = nullptr;
  /// Asked before a step allocates this many bytes at once (a face's lattice read into arrays):
  /// false where the budget cannot hold them, and `stop` raised; none: every step admitted.
  std::function<bool(std::uint64_t)> admit_bytes;

  /// Work done in steps whose items are known only as each begins (a field's levels, the far
  /// radius's spheres): the step under way (from 1; 0: none), at most how many there are (0:
  /// not known), its items, and items_done when it began. A reporter shows the step's own
  /// count, whose total does not grow.
  std::atomic<int> step{0};
  std::atomic<int> steps_at_most{0};
  std::atomic<std::size_t> step_items{0};
  std::atomic<std::size_t> step_done_before{0};
  std::atomic<std::int64_t> step_began_ns{0};  ///< steady_clock, since its epoch
  std::atomic<const char*> step_noun{"step"};  ///< what a step is ("level", "sphere")

  /// Steps within stages (a face of six, each computed level by level): the stage under way
  /// (from 1; 0: none) and how many there are.
  std::atomic<int> stage{0};
  std::atomic<int> stages{0};
  std::atomic<const char*> stage_noun{"stage"};

  /// @brief Stage @p k (from 1) of @p count, a @p noun, begins; its steps count from 1 again.
  void beginStage(const char* noun, int k, int count) {
    stage_noun.store(noun);
    stages.store(count);
    stage.store(k);
    step.store(0);
  }

  /// @brief No stage or step is under way any more: the items count as one whole again.
  void endStages() {
    stage.store(0);
    step.store(0);
  }

  /// @brief Step @p k (from 1) of at most @p at_most (0: not known), a @p noun, begins with
  /// @p items items.
  void beginStep(const char* noun, int k, int at_most, std::size_t items) {
    step_noun.store(noun);
    step_began_ns.store(std::chrono::duration_cast<std::chrono::nanoseconds>(
                            std::chrono::steady_clock::now().time_since_epoch())
                            .count());
    step_done_before.store(items_done.load());
    step_items.store(items);
    steps_at_most.store(at_most);
    step.store(k);
  }

  /// @brief Whether a step may allocate @p bytes at once (admit_bytes).
  [[nodiscard]] bool admits(std::uint64_t bytes) const {
    return !admit_bytes || admit_bytes(bytes);
  }

  [[nodiscard]] bool stopRequested() const {
    return stop != nullptr && stop->load(std::memory_order_relaxed);
  }
};

/// @brief The processes that share one field's point evaluations (an MPI job:
/// pipeline/commands/cluster.h). Each evaluates its share of every level's new points and all
/// receive every value, so every process holds the same field, as one process would have computed
/// it.
class PointExchange {
 public:
  virtual ~PointExchange() = default;
  [[nodiscard]] virtual int rank() const = 0;
  [[nodiscard]] virtual int size() const = 0;
  /// @brief Collective: every process passes its own bytes and receives every process's, in
  /// rank order. Called by all processes the same number of times.
  virtual std::vector<std::vector<std::byte>> allGather(std::span<const std::byte> mine) = 0;
};

/// @brief Records written for another process (its machine's byte order: the processes of one
/// job share it).
class WireWriter {
 public:
  template <typename T>
  void put(T value) {
    const auto* p = reinterpret_cast<const std::byte*>(&value);
    bytes_.insert(bytes_.end(), p, p + sizeof value);
  }
  void append(std::span<const std::byte> bytes) {
    bytes_.insert(bytes_.end(), bytes.begin(), bytes.end());
  }
  [[nodiscard]] std::span<const std::byte> bytes() const { return bytes_; }

 private:
  std::vector<std::byte> bytes_;
};

/// @brief Records a process sent, read in the order they were written.
class WireReader {
 public:
  explicit WireReader(std::span<const std::byte> bytes) : bytes_(bytes) {}
  /// @throw std::runtime_error when the message ends before the value: a short message would
  /// leave an observer unlit, read as "no hazard".
  template <typename T>
  T get() {
    T value{};
    if (bytes_.size() - at_ < sizeof value)
      throw std::runtime_error("observer exchange: a process's message ended early");
    std::memcpy(&value, bytes_.data() + at_, sizeof value);
    at_ += sizeof value;
    return value;
  }
  [[nodiscard]] std::size_t left() const { return bytes_.size() - at_; }

 private:
  std::span<const std::byte> bytes_;
  std::size_t at_ = 0;
};

/// @brief Shares @p observers observers among the processes of @p exchange: on each,
/// @p compute gets its share (every size-th index from its rank on, in order) and writes each
/// one's record, in that order; then every process receives every record, and @p take reads
/// observer i's. Collective: every process calls it alike.
/// @throw WorkStopped when @p compute threw it on any process (every process stops here).
void shareObservers(PointExchange& exchange, std::size_t observers,
                    const std::function<void(std::span<const std::size_t>, WireWriter&)>& compute,
                    const std::function<void(std::size_t, WireReader&)>& take);

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
/// @param exchange optional: the processes of an MPI job share the points (shareObservers()),
/// and each returns them all, as one process would.
std::vector<ObserverResult> evaluatePoints(const FacetIntegrator& integrator,
                                           std::span<const Vec3> points_m,
                                           const PointScheme& scheme,
                                           WorkCounter* counter = nullptr,
                                           PointExchange* exchange = nullptr);

}  // namespace glint
