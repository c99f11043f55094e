#include "pipeline/base/number_format.h"

#include <cmath>
#include <cstdio>

namespace glint {

std::string formatNumber(const char* fmt, double x) {
  char buf[64];
  std::snprintf(buf, sizeof buf, fmt, x);
  return buf;
}

std::string formatDuration(double seconds) {
  char buf[64];
  if (seconds < 60.0) {
    std::snprintf(buf, sizeof buf, "%.2f s", seconds);
  } else if (seconds < 3600.0) {
    std::snprintf(buf, sizeof buf, "%d min %02d s", static_cast<int>(seconds / 60.0),
                  static_cast<int>(std::fmod(seconds, 60.0)));
  } else {
    std::snprintf(buf, sizeof buf, "%d h %02d min", static_cast<int>(seconds / 3600.0),
                  static_cast<int>(std::fmod(seconds, 3600.0) / 60.0));
  }
  return buf;
}

}  // namespace glint
