#include "pipeline/base/phase_clock.h"

#include <algorithm>

namespace glint {

void PhaseClock::add(const std::string& name, double seconds) {
  const auto it =
      std::find_if(phases_.begin(), phases_.end(), [&](const auto& p) { return p.first == name; });
  if (it != phases_.end()) {
    it->second += seconds;
  } else {
    phases_.emplace_back(name, seconds);
  }
}

}  // namespace glint
