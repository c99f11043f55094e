#pragma once
/// @file
/// @brief The hazard of an exposure that varies in time (an engagement: a glint sweeping past an
/// eye), judged as the standards judge a varying exposure: for every exposure duration t, the
/// largest radiant exposure any window of length t collects, against the MPE for t
/// (ANSI Z136.1-2014 8.2.3 applies the same to the windows of a pulse train; docs/hazard.md):
/// rules 1 and 2 of the repetitive-pulse rules. Rule 3 and the verdict that joins them are
/// hazard/exposure_train.h's.

#include <span>

#include "hazard/hazard.h"

namespace glint {

/// @brief The worst window of an irradiance history.
struct WindowHazard {
  /// max over t of H_max(t) / MPE(t), an upper bound within 0.1 % of that maximum (MPE(t) as
  /// radiant exposure; the search over t brackets the maximum, see worstWindow()).
  double ratio = 0.0;
  double duration_s = 0.0;     ///< the t of the largest ratio found
  double start_s = 0.0;        ///< where that window starts
  double exposure_j_m2 = 0.0;  ///< H_max(t): what the window collects
  double mpe_j_m2 = 0.0;       ///< the MPE for t as radiant exposure
};

/// @brief The worst window of the irradiance piecewise linear through (@p time_s,
/// @p irradiance_w_m2), for durations from 1 ns (where the MPE table starts) to @p longest_s,
/// under @p hazard's wavelength, standard and tissue (its pulse is not used: a continuous laser).
/// @pre times increasing, irradiance ≥ 0, longest_s within the MPE table (≤ 30 000 s).
WindowHazard worstWindow(std::span<const double> time_s, std::span<const double> irradiance_w_m2,
                         const HazardSpec& hazard, double longest_s);

/// @brief The largest radiant exposure (J/m²) any window of @p duration_s collects from the
/// piecewise-linear irradiance, and where that window starts (the irradiance is 0 outside the
/// samples' span).
struct WindowExposure {
  double exposure_j_m2 = 0.0;
  double start_s = 0.0;
};
WindowExposure largestWindowExposure(std::span<const double> time_s,
                                     std::span<const double> irradiance_w_m2, double duration_s);

/// @brief How long (s) the piecewise-linear irradiance is at or above @p threshold_w_m2.
double timeAtOrAbove(std::span<const double> time_s, std::span<const double> irradiance_w_m2,
                     double threshold_w_m2);

}  // namespace glint
