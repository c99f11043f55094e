#pragma once
/// @file
/// @brief Progress of long runs on standard error.

#include <chrono>
#include <condition_variable>
#include <mutex>
#include <ostream>
#include <string>
#include <thread>

#include "observers/point_set.h"

namespace glint {

/// @brief The line a ProgressReporter prints for @p counter after @p elapsed_s: items done of
/// @p total (0: as many as scheduled so far) @p noun, or where the work goes in stages and steps
/// ("face 2 of 6, level 3: 40/100 reach points"), the step's own items, whose total does not
/// grow; evaluations, the time elapsed and, unless @p without_time_left (items of no like
/// cost, as a region's files), the time left (in the step under way).
std::string progressLine(const WorkCounter& counter, const std::string& noun, std::size_t total,
                         double elapsed_s, bool without_time_left = false);

/// @brief Reports a WorkCounter from a background thread: nothing for the first second, then
/// every half second (one self-overwriting line on a terminal; a line every 10 s otherwise):
/// items done, evaluations, elapsed time and the estimated time left (of the step under way,
/// where the work goes in steps: WorkCounter::beginStep()).
class ProgressReporter {
 public:
  /// @param total items in all; 0: as many as the counter has scheduled so far.
  /// @param without_time_left items of no like cost: no estimate of the time left.
  ProgressReporter(std::ostream& err, bool terminal, std::string noun, std::size_t total,
                   const WorkCounter& counter, bool without_time_left = false);
  ~ProgressReporter();
  ProgressReporter(const ProgressReporter&) = delete;
  ProgressReporter& operator=(const ProgressReporter&) = delete;

  /// @brief Stops reporting and clears the progress line.
  void stop();

 private:
  void run();
  void print();

  std::ostream& err_;
  bool terminal_;
  std::string noun_;
  std::size_t total_;
  bool without_time_left_;
  const WorkCounter& counter_;
  std::chrono::steady_clock::time_point start_;
  std::mutex mutex_;
  std::condition_variable wake_;
  bool stopping_ = false;
  bool printed_ = false;
  std::thread thread_;
};

}  // namespace glint
