#pragma once
/// @file
/// @brief A run's wall time by phase, so that summary.json accounts for every second of it.

#include <chrono>
#include <string>
#include <utility>
#include <vector>

namespace glint {

/// @brief The wall time of a run from its start, and of each named phase in the order they
/// first began (a phase timed twice adds up). What no phase holds is the run's overhead, shown
/// as such: a phase that is missing shows as a gap, not as time spent elsewhere.
class PhaseClock {
 public:
  using Clock = std::chrono::steady_clock;

  /// @brief Times a phase from its construction to its destruction (or stop()).
  class Scope {
   public:
    Scope(PhaseClock& clock, std::string name)
        : clock_(&clock), name_(std::move(name)), start_(Clock::now()) {}
    ~Scope() { stop(); }
    Scope(const Scope&) = delete;
    Scope& operator=(const Scope&) = delete;
    void stop() {
      if (clock_ == nullptr) return;
      clock_->add(name_, std::chrono::duration<double>(Clock::now() - start_).count());
      clock_ = nullptr;
    }

   private:
    PhaseClock* clock_;
    std::string name_;
    Clock::time_point start_;
  };

  /// @brief A phase named @p name, timed until the scope ends.
  [[nodiscard]] Scope phase(std::string name) { return {*this, std::move(name)}; }
  /// @brief Adds @p seconds to the phase @p name (the first of that name sets its place).
  void add(const std::string& name, double seconds);
  /// @brief Since the clock was made (s).
  [[nodiscard]] double elapsedSeconds() const {
    return std::chrono::duration<double>(Clock::now() - start_).count();
  }
  /// @brief The phases, in the order they first began: name and seconds.
  [[nodiscard]] const std::vector<std::pair<std::string, double>>& phases() const {
    return phases_;
  }

 private:
  Clock::time_point start_ = Clock::now();
  std::vector<std::pair<std::string, double>> phases_;
};

}  // namespace glint
