#pragma once
/// @file
/// @brief The memory a run may use: a budget (`--memory`, or three quarters of what the
/// machine or its cgroup has), an estimate checked before allocating, and a watch that stops
/// the run, with a message, when its resident memory passes the budget.

#include <atomic>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

namespace glint {

/// @brief Physical memory of the machine, or the cgroup's limit when lower (bytes).
std::uint64_t machineMemoryBytes();

/// @brief The default budget: three quarters of machineMemoryBytes(), leaving room for the
/// system and for the output writers' buffers.
std::uint64_t defaultMemoryBudgetBytes();

/// @brief "512M", "4G", "1.5GiB", "2e9" (bytes); K, M, G, T are powers of 1024.
/// @return nothing for text that is not a positive finite size.
std::optional<std::uint64_t> parseByteSize(std::string_view text);

/// @brief "1.5 GB"-style text (powers of 1024, three significant digits).
std::string formatBytes(double bytes);

/// @brief Resident memory of this process now (bytes), 0 where it cannot be read.
std::uint64_t residentBytes();

/// @brief Refuses, before anything is allocated, work whose memory floor exceeds the budget.
/// @throw InputError naming @p what, the estimate, the budget and what to change.
void requireWithinBudget(const std::string& what, std::uint64_t floor_bytes,
                         std::uint64_t budget_bytes, std::string_view advice);

/// @brief Samples the resident memory once when constructed and then every 20 ms on a thread
/// of its own; once it passes the budget, stopFlag() turns true (the field builders poll it
/// and stop).
class MemoryWatch {
 public:
  /// @brief Takes the first sample before returning: a process already past the budget has
  /// exceeded() true at once.
  explicit MemoryWatch(std::uint64_t budget_bytes);
  ~MemoryWatch();
  MemoryWatch(const MemoryWatch&) = delete;
  MemoryWatch& operator=(const MemoryWatch&) = delete;

  [[nodiscard]] const std::atomic<bool>& stopFlag() const { return exceeded_; }
  [[nodiscard]] bool exceeded() const { return exceeded_.load(); }
  [[nodiscard]] std::uint64_t budgetBytes() const { return budget_bytes_; }
  [[nodiscard]] std::uint64_t peakBytes() const { return peak_bytes_.load(); }
  /// @brief Asked before one step allocates @p bytes at once: false, and stopFlag() true, where
  /// the resident memory now plus them passes the budget. An allocation filled faster than one
  /// sample every 20 ms would pass the budget by its whole size before the watch could see it.
  [[nodiscard]] bool admit(std::uint64_t bytes) const;
  /// @brief How many samples have been taken (the constructor's first among them).
  [[nodiscard]] std::uint64_t samples() const { return samples_.load(); }
  /// @brief Names something the command holds throughout (the terrain) and its estimate: a stop
  /// where it is a quarter or more of the resident memory says so, with @p advice, so that the
  /// message does not blame only what was being computed. Call before the work starts.
  void noteHeld(std::string what, std::uint64_t bytes, std::string advice);
  /// @throw InputError if the budget was passed, naming @p what was being computed, then what
  /// noteHeld() named where it counts, and ending with @p advice.
  void check(const std::string& what, std::string_view advice =
                                          "Raise --memory, or coarsen voxel_m or pixel_m, or "
                                          "shrink the box") const;

 private:
  void sample();

  std::uint64_t budget_bytes_;
  // Observations, raised by admit() as by the sampling thread.
  mutable std::atomic<bool> exceeded_{false};
  mutable std::atomic<std::uint64_t> refused_at_bytes_{0};  ///< resident + what admit() refused
  std::atomic<bool> stopping_{false};
  std::atomic<std::uint64_t> peak_bytes_{0};
  std::atomic<std::uint64_t> samples_{0};
  std::thread thread_;
  struct Held {
    std::string what;
    std::uint64_t bytes = 0;
    std::string advice;
  };
  std::vector<Held> held_;
};

}  // namespace glint
