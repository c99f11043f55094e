#include "pipeline/base/progress.h"

#include <algorithm>
#include <cstdint>
#include <cstdio>

#include "pipeline/base/number_format.h"

namespace glint {

ProgressReporter::ProgressReporter(std::ostream& err, bool terminal, std::string noun,
                                   std::size_t total, const WorkCounter& counter,
                                   bool without_time_left)
    : err_(err),
      terminal_(terminal),
      noun_(std::move(noun)),
      total_(total),
      without_time_left_(without_time_left),
      counter_(counter),
      start_(std::chrono::steady_clock::now()),
      thread_([this] { run(); }) {}

ProgressReporter::~ProgressReporter() { stop(); }

void ProgressReporter::stop() {
  {
    std::lock_guard lock(mutex_);
    if (stopping_) return;
    stopping_ = true;
  }
  wake_.notify_all();
  thread_.join();
  if (printed_ && terminal_) err_ << "\r\033[K" << std::flush;
}

void ProgressReporter::run() {
  using namespace std::chrono_literals;
  std::unique_lock lock(mutex_);
  if (wake_.wait_for(lock, 1s, [this] { return stopping_; })) return;
  const auto period = terminal_ ? std::chrono::milliseconds(500) : std::chrono::milliseconds(10000);
  do {
    print();
  } while (!wake_.wait_for(lock, period, [this] { return stopping_; }));
}

std::string progressLine(const WorkCounter& counter, const std::string& noun, std::size_t total,
                         double elapsed_s, bool without_time_left) {
  const int step = counter.step.load();
  const char* step_noun = "step";
  std::size_t done = counter.items_done.load();
  if (total == 0) total = counter.items_scheduled.load();
  std::string line = "glint: ";
  char buf[256];
  if (const int stage = counter.stage.load(); stage > 0) {
    std::snprintf(buf, sizeof buf, "%s %d of %d, ", counter.stage_noun.load(), stage,
                  counter.stages.load());
    line += buf;
  }
  if (step > 0) {
    // Work in steps: the step's own count (its total is known when it begins), and the time
    // left in it only, since the later steps' items are not known yet.
    const int at_most = counter.steps_at_most.load();
    step_noun = counter.step_noun.load();
    if (at_most > 0) {
      std::snprintf(buf, sizeof buf, "%s %d of at most %d: ", step_noun, step, at_most);
    } else {
      std::snprintf(buf, sizeof buf, "%s %d: ", step_noun, step);
    }
    line += buf;
    total = counter.step_items.load();
    done = std::min(total, done - std::min(done, counter.step_done_before.load()));
  }
  const double fraction = total > 0 ? static_cast<double>(done) / static_cast<double>(total) : 0.0;
  std::snprintf(buf, sizeof buf, "%zu/%zu %s (%.0f%%), ", done, total, noun.c_str(),
                100.0 * fraction);
  line += buf;
  // Work without integrations (a footprint's rows) says nothing of them.
  if (const std::int64_t evaluations = counter.evaluations.load(); evaluations > 0) {
    std::snprintf(buf, sizeof buf, "%.3g evaluations, ", static_cast<double>(evaluations));
    line += buf;
  }
  line += formatDuration(elapsed_s) + " elapsed";
  if (fraction > 0.0 && fraction < 1.0 && !without_time_left) {
    const auto began = std::chrono::steady_clock::time_point(
        std::chrono::nanoseconds(counter.step_began_ns.load()));
    const double in_step =
        step > 0 ? std::chrono::duration<double>(std::chrono::steady_clock::now() - began).count()
                 : elapsed_s;
    line += ", about " + formatDuration(in_step * (1.0 - fraction) / fraction) + " left" +
            (step > 0 ? " in this " + std::string(step_noun) : std::string());
  }
  return line;
}

void ProgressReporter::print() {
  const double elapsed =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  const std::string line = progressLine(counter_, noun_, total_, elapsed, without_time_left_);
  if (terminal_) {
    err_ << "\r\033[K" << line << std::flush;
  } else {
    err_ << line << '\n' << std::flush;
  }
  printed_ = true;
}

}  // namespace glint
