#pragma once
/// @file
/// @brief What glint reports of an engagement (docs/engagement.md): for `glint points` each
/// observer's exposure, peak, time above the MPE, verdict and the rule that sets it (its worst
/// window, or its train of pulses) as table columns, the irradiance histories as a time series
/// and the summary on the terminal; for a region of `glint run` or a study's scenario, its
/// summary entry and its lines on the terminal.

#include <cstdint>
#include <nlohmann/json_fwd.hpp>
#include <ostream>
#include <span>
#include <string>
#include <vector>

#include "export/points_csv.h"
#include "pipeline/setup/engagement.h"

namespace glint {

/// @brief The table's columns after x, y, z: `exposure_j_m2`, `exposure_error_j_m2`,
/// `peak_irradiance_w_m2`, `peak_time_s`, `time_above_mpe_s`, `hazard_ratio` (the verdict),
/// `hazard_rule` (1, 2 or 3: which sets it; 0 nothing above the floor), `worst_window_ratio`,
/// `worst_window_s`, `worst_window_start_s`, `worst_window_exposure_j_m2`,
/// `worst_window_mpe_j_m2` (rules 1 and 2), `pulses`, `pulse_train_ratio`, `pulse_reduction`,
/// `pulse_window_s`, `pulse_window_exposure_j_m2`, `pulse_duration_s`, `pulse_exposure_j_m2`
/// (rule 3: the pulses counted, its ratio and reduction, and the pulse that sets it),
/// `aided_hazard_ratio` (with an optical aid), `stare_hazard_ratio`, per level of the scene
/// `<level>_peak_ratio` and `time_above_<level>_s`, `time_samples`, `evaluations`, `converged`.
std::vector<CsvColumn> engagementColumns(const EngagementResults& results,
                                         const HazardSpec& hazard);

/// @brief Every sample of every history: `observer,time_s,irradiance_w_m2,pulse`, observers
/// numbered from 1 in the points file's order, times increasing; `pulse` numbers from 1 the
/// pulses (or groups) rule 3 counted that the sample lies in, 0 between them.
/// @throw OutputError where a sample is not finite (before anything is written).
void writeTimeSeriesCsv(std::ostream& out, const EngagementResults& results);

/// @brief The terminal summary: the span and its sampling, the worst observer, its verdict and
/// the rule that sets it (its worst window, or its train of pulses), the per-pose stare verdict
/// beside it, and a warning for observers that did not converge.
void printEngagementSummary(std::ostream& err, const Scene& scene, std::span<const Vec3> points,
                            const EngagementResults& results, int threads);

/// @brief The summary's entry of one region named @p name, written to @p file: its lattice,
/// counts, worst point with its verdict and the rule that sets it, the hazardous area (a plane:
/// `hazardous_area_m2`, `stare_hazardous_area_m2`) or volume (the box: `hazard_volume_m3`, ...) by
/// the worst window and by the stare verdict.
nlohmann::json engagementRegionJson(const std::string& name, const std::string& file,
                                    const FieldSpec& spec, const EngagementRegion& region,
                                    const HazardSpec& hazard);

/// @brief The summary's `engagement`: the span, the motion's kinds and the time sampling.
nlohmann::json engagementJson(const EngagementSpec& engagement);

/// @brief One region's lines on the terminal, @p what naming it ("plane wall"), a line per level
/// of @p hazard.
void printEngagementRegion(std::ostream& err, const std::string& what, const FieldSpec& spec,
                           const EngagementRegion& region, const HazardSpec& hazard);

}  // namespace glint
