#pragma once
/// @file
/// @brief What `glint batch` reports: each scenario's record (result.json), the study's
/// scenarios.csv, its aggregated maps (`box.vdb`, `<plane>.exr`), summary.json and the lines
/// on the terminal (docs/batch.md).

#include <cstddef>
#include <filesystem>
#include <map>
#include <nlohmann/json_fwd.hpp>
#include <ostream>
#include <string>
#include <vector>

#include "observers/far_field.h"
#include "observers/field.h"
#include "pipeline/input/study.h"
#include "pipeline/report/hazard_report.h"
#include "pipeline/setup/study_maps.h"

namespace glint {

class OutputSet;

/// @brief A scenario's `parameters` in its result.json (and so its row of scenarios.csv); the
/// surface state by its material's name in @p study's scene.
nlohmann::json scenarioParametersJson(const Study& study, const Scenario& s);

/// @brief One region's entry of a scenario's result.json: its peak ratio, hazardous points and
/// extent, counts, the per-pulse peak and the aided figures where the scene has them.
nlohmann::json scenarioRegionJson(const StudyLattice& r, const FieldStats& stats,
                                  const HazardSpec& h, const HazardousPoints& hazardous);

struct EngagementRegion;

/// @brief One region's entry of an engagement scenario's result.json: the region's summary
/// entry as glint run gives it (engagementRegionJson()), with the figures every region's entry has,
/// judged by the worst window: its peak ratio, and the hazardous points and area as the study
/// counted them (@p hazardous) as its area or volume.
nlohmann::json scenarioEngagementRegionJson(const StudyLattice& r, const EngagementRegion& region,
                                            const HazardSpec& h, const HazardousPoints& hazardous);

/// @brief One scenario's values over an engagement's region, as the study adds them: its peak
/// irradiance and worst windows' ratios (aided, with an aid).
RegionValues engagementValues(const EngagementRegion& region, const HazardSpec& h);

/// @brief The far field's entry of a scenario's result.json (with farHazardJson()).
nlohmann::json scenarioFarFieldJson(const FarField& far, const FarHazard& hazard,
                                    const HazardSpec& h);

/// @brief scenarios.csv: one row per scenario record, in index order (docs/batch.md lists the
/// columns).
std::string scenariosCsv(const std::vector<StudyLattice>& lattices,
                         const std::map<std::size_t, nlohmann::json>& records, bool far_field,
                         bool reach, bool aided);

/// @brief Whether a study's region @p r has geo-referenced maps: a plane flat enough, in a scene
/// with a site.
bool studyMapOnTheEarth(const Study& study, const StudyLattice& r);

/// @brief Writes one region's aggregated map to @p path (StudyLattice::studyFile()): maximum
/// irradiance and hazard ratio, coverage probability, and with an optical aid the aided ratio
/// and coverage; on the Earth, its geo-referenced maps beside it. Each file is opened in
/// @p outputs, and appears when they are committed.
/// @throw OutputError when a file cannot be written.
void writeStudyMap(OutputSet& outputs, const std::filesystem::path& path, const StudyLattice& r,
                   const Study& study, std::size_t scenarios);

/// @brief summary.json of a study: the limits, quantiles over the scenarios of each region's
/// peak ratio and extent, the areas or volumes hazardous in any and in half the scenarios, the
/// far field's NOHD and the hazard reach (aided too, with an aid).
nlohmann::json batchSummaryJson(const Study& study, const std::vector<StudyLattice>& lattices,
                                const std::map<std::size_t, nlohmann::json>& records,
                                std::size_t resumed, int ranks, double wall_s);

/// @brief The study's closing lines on the terminal, from its @p summary.
void printBatchSummary(std::ostream& err, const nlohmann::json& summary,
                       const std::vector<StudyLattice>& lattices,
                       const std::filesystem::path& out_dir, double wall_s);

}  // namespace glint
