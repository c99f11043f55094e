#include "pipeline/base/progress.h"

#include <cstdio>

#include "pipeline/base/number_format.h"

namespace glint {

ProgressReporter::ProgressReporter(std::ostream& err, bool terminal, std::string noun,
                                   std::size_t total, const WorkCounter& counter)
    : err_(err),
      terminal_(terminal),
      noun_(std::move(noun)),
      total_(total),
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

void ProgressReporter::print() {
  const double elapsed =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  const std::size_t done = counter_.items_done.load();
  const std::size_t total = total_ > 0 ? total_ : counter_.items_scheduled.load();
  const double fraction = total > 0 ? static_cast<double>(done) / static_cast<double>(total) : 0.0;
  char buf[256];
  std::snprintf(buf, sizeof buf, "glint: %zu/%zu %s (%.0f%%), %.3g evaluations, %s elapsed", done,
                total, noun_.c_str(), 100.0 * fraction,
                static_cast<double>(counter_.evaluations.load()), formatDuration(elapsed).c_str());
  std::string line = buf;
  if (fraction > 0.0 && fraction < 1.0) {
    line += ", about " + formatDuration(elapsed * (1.0 - fraction) / fraction) + " left";
  }
  if (terminal_) {
    err_ << "\r\033[K" << line << std::flush;
  } else {
    err_ << line << '\n' << std::flush;
  }
  printed_ = true;
}

}  // namespace glint
