#pragma once
/// @file
/// @brief What `glint points` reports of an engagement (docs/engagement.md): each observer's
/// exposure, peak, time above the MPE and worst window as table columns, the irradiance
/// histories as a time series, and the summary on the terminal.

#include <ostream>
#include <span>
#include <vector>

#include "export/points_csv.h"
#include "hazard/exposure_window.h"
#include "observers/exposure.h"
#include "pipeline/scene.h"

namespace glint {

/// @brief Each observer's history and its verdict.
struct EngagementResults {
  std::vector<ExposureHistory> histories;
  std::vector<ExposureVerdict> verdicts;
  double seconds = 0.0;
};

/// @brief Judges every history of @p histories under the scene's hazard and engagement.
EngagementResults judgeEngagement(std::vector<ExposureHistory> histories, const Scene& scene);

/// @brief The table's columns after x, y, z: `exposure_j_m2`, `exposure_error_j_m2`,
/// `peak_irradiance_w_m2`, `peak_time_s`, `time_above_mpe_s`, `hazard_ratio` (the worst
/// window), `worst_window_s`, `worst_window_start_s`, `worst_window_exposure_j_m2`,
/// `worst_window_mpe_j_m2`, `aided_hazard_ratio` (with an optical aid), `stare_hazard_ratio`,
/// `time_samples`, `evaluations`, `converged`.
std::vector<CsvColumn> engagementColumns(const EngagementResults& results,
                                         const HazardSpec& hazard);

/// @brief Every sample of every history: `observer,time_s,irradiance_w_m2`, observers numbered
/// from 1 in the points file's order, times increasing.
/// @throw OutputError where a sample is not finite (before anything is written).
void writeTimeSeriesCsv(std::ostream& out, const EngagementResults& results);

/// @brief The terminal summary: the span and its sampling, the worst observer and its window,
/// the per-pose stare verdict beside it, and a warning for observers that did not converge.
void printEngagementSummary(std::ostream& err, const Scene& scene, std::span<const Vec3> points,
                            const EngagementResults& results, int threads);

}  // namespace glint
