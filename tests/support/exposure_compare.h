#pragma once
// How far one set of engagement histories is from a reference (tests and the engagement bench).
#include <algorithm>
#include <cmath>
#include <vector>

#include "observers/exposure.h"

namespace glint::test {

/// @brief The largest relative errors of exposure and of peak irradiance of @p h against
/// @p reference, over the observers whose reference peak is above 1 % of the brightest.
struct ExposureErrors {
  double exposure = 0.0;
  double peak = 0.0;
  [[nodiscard]] bool within(double relative) const {
    return exposure < relative && peak < relative;
  }
};

inline ExposureErrors exposureErrors(const std::vector<ExposureHistory>& h,
                                     const std::vector<ExposureHistory>& reference) {
  double brightest = 0.0;
  for (const ExposureHistory& r : reference) brightest = std::max(brightest, r.peak_w_m2);
  ExposureErrors e;
  for (std::size_t i = 0; i < h.size(); ++i) {
    if (reference[i].peak_w_m2 < 0.01 * brightest) continue;
    e.exposure =
        std::max(e.exposure, std::abs(h[i].exposure_j_m2 / reference[i].exposure_j_m2 - 1));
    e.peak = std::max(e.peak, std::abs(h[i].peak_w_m2 / reference[i].peak_w_m2 - 1));
  }
  return e;
}

/// @brief The samples of all of @p h.
inline std::size_t sampleCount(const std::vector<ExposureHistory>& h) {
  std::size_t n = 0;
  for (const ExposureHistory& e : h) n += e.time_s.size();
  return n;
}

}  // namespace glint::test
