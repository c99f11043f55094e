#include "pipeline/base/memory_budget.h"

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>

#include "pipeline/base/input_error.h"

namespace glint {
namespace {

// A number from the first line of a file (a cgroup limit), or nothing ("max", missing).
std::optional<std::uint64_t> firstNumber(const char* path) {
  std::ifstream in(path);
  std::string word;
  if (!(in >> word) || word.empty() || word.find_first_not_of("0123456789") != std::string::npos)
    return std::nullopt;
  try {
    return std::stoull(word);
  } catch (const std::exception&) {
    return std::nullopt;
  }
}

}  // namespace

std::uint64_t machineMemoryBytes() {
  const long pages = ::sysconf(_SC_PHYS_PAGES);
  const long page = ::sysconf(_SC_PAGE_SIZE);
  std::uint64_t bytes = pages > 0 && page > 0
                            ? static_cast<std::uint64_t>(pages) * static_cast<std::uint64_t>(page)
                            : std::uint64_t{4} << 30;
  // A container's limit (cgroup v2, then v1) counts where it is lower than the machine's.
  for (const char* limit :
       {"/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory/memory.limit_in_bytes"}) {
    if (const auto cap = firstNumber(limit); cap && *cap > 0) bytes = std::min(bytes, *cap);
  }
  return bytes;
}

std::uint64_t defaultMemoryBudgetBytes() { return machineMemoryBytes() / 4 * 3; }

std::optional<std::uint64_t> parseByteSize(std::string_view text) {
  const std::string s(text);
  std::size_t used = 0;
  double x = 0.0;
  try {
    x = std::stod(s, &used);
  } catch (const std::exception&) {
    return std::nullopt;
  }
  std::string unit = s.substr(used);
  for (char& c : unit) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  if (unit.size() > 1 && unit.back() == 'B') unit.pop_back();  // "GB"
  if (unit.size() > 1 && unit.back() == 'I') unit.pop_back();  // "GiB"
  double scale = 1.0;
  if (unit == "K")
    scale = 1024.0;
  else if (unit == "M")
    scale = 1024.0 * 1024.0;
  else if (unit == "G")
    scale = 1024.0 * 1024.0 * 1024.0;
  else if (unit == "T")
    scale = 1024.0 * 1024.0 * 1024.0 * 1024.0;
  else if (!unit.empty() && unit != "B")
    return std::nullopt;
  const double bytes = x * scale;
  if (!(bytes >= 1.0 && bytes < 1.8e19)) return std::nullopt;
  return static_cast<std::uint64_t>(bytes);
}

std::string formatBytes(double bytes) {
  const char* units[] = {"bytes", "KB", "MB", "GB", "TB", "PB", "EB"};
  int u = 0;
  while (bytes >= 1024.0 && u < 6) {
    bytes /= 1024.0;
    ++u;
  }
  char text[32];
  std::snprintf(text, sizeof text, u == 0 ? "%.0f %s" : "%.3g %s", bytes, units[u]);
  return text;
}

std::uint64_t residentBytes() {
  std::ifstream in("/proc/self/statm");
  std::uint64_t size = 0, resident = 0;
  if (!(in >> size >> resident)) return 0;
  return resident * static_cast<std::uint64_t>(::sysconf(_SC_PAGE_SIZE));
}

void requireWithinBudget(const std::string& what, std::uint64_t floor_bytes,
                         std::uint64_t budget_bytes, std::string_view advice) {
  if (floor_bytes <= budget_bytes) return;
  throw InputError(what + " needs at least " + formatBytes(static_cast<double>(floor_bytes)) +
                   " of memory, more than the budget of " +
                   formatBytes(static_cast<double>(budget_bytes)) + " (--memory); " +
                   std::string(advice));
}

MemoryWatch::MemoryWatch(std::uint64_t budget_bytes) : budget_bytes_(budget_bytes) {
  // Sampled here first, so the flag never waits on the thread's schedule to reflect a budget
  // passed before the work starts.
  sample();
  thread_ = std::thread([this] {
    for (;;) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      if (stopping_.load()) return;
      sample();
    }
  });
}

void MemoryWatch::sample() {
  const std::uint64_t now = residentBytes();
  if (now > peak_bytes_.load()) peak_bytes_.store(now);
  if (now > budget_bytes_) exceeded_.store(true);
  samples_.fetch_add(1);
}

bool MemoryWatch::admit(std::uint64_t bytes) const {
  const std::uint64_t would = residentBytes() + bytes;
  if (would <= budget_bytes_) return true;
  if (would > refused_at_bytes_.load()) refused_at_bytes_.store(would);
  exceeded_.store(true);
  return false;
}

MemoryWatch::~MemoryWatch() {
  stopping_.store(true);
  thread_.join();
}

void MemoryWatch::noteHeld(std::string what, std::uint64_t bytes, std::string advice) {
  held_.push_back({std::move(what), bytes, std::move(advice)});
}

void MemoryWatch::check(const std::string& what, std::string_view advice) const {
  if (!exceeded()) return;
  std::string held;
  for (const Held& h : held_) {
    if (h.bytes < peakBytes() / 4) continue;
    held += " Of that, " + h.what + " holds about " + formatBytes(static_cast<double>(h.bytes)) +
            " from the start: " + h.advice + ".";
  }
  const std::uint64_t refused = refused_at_bytes_.load();
  const std::string reached =
      refused > peakBytes()
          ? "stopped where its next step would have taken the resident memory to " +
                formatBytes(static_cast<double>(refused))
          : "stopped when the resident memory reached " +
                formatBytes(static_cast<double>(peakBytes()));
  throw InputError(what + ": " + reached + ", beyond the budget of " +
                   formatBytes(static_cast<double>(budget_bytes_)) +
                   " (--memory); nothing was written." + held + " " + std::string(advice));
}

}  // namespace glint
