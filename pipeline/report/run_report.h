#pragma once
/// @file
/// @brief What `glint run` reports: summary.json's entries for the box, each plane and the far
/// field, and the lines on the terminal (docs/usage.md, "glint run").

#include <nlohmann/json_fwd.hpp>
#include <ostream>
#include <string>
#include <string_view>
#include <vector>

#include "export/field_files.h"
#include "facets/integrator.h"
#include "observers/far_field.h"
#include "observers/field.h"
#include "observers/reach.h"
#include "pipeline/base/phase_clock.h"
#include "pipeline/input/scene.h"
#include "pipeline/report/hazard_report.h"
#include "pipeline/setup/surface_check.h"

namespace glint {

/// @brief The entries every summary.json begins with: program, scene file and hash, schemes.
nlohmann::json runJson(const RunInfo& info);

/// @brief summary.json's `target`: what the culling made of the coarse facets.
nlohmann::json targetJson(const CullStats& cull);

/// @brief Each material of the scene by name: its model in words ("2 Beckmann lobes +
/// Lambertian"), its lobes (reflectance, σ) and its diffuse reflectance.
nlohmann::json materialsJson(const Scene& scene);

/// @brief summary.json's `meshes`: what became of each mesh's triangles (@p stats in the
/// order of the scene's meshes).
nlohmann::json meshesJson(const Scene& scene, const std::vector<MeshStats>& stats);

/// @brief summary.json's `surface_check`: how far the meshes' surface model moves the run's
/// brightest observers (checkSurfaceModel()).
nlohmann::json surfaceCheckJson(const Scene& scene, const SurfaceModelCheck& check);

/// @brief The surface check's line on the terminal (nothing for a scene without meshes).
void printSurfaceCheck(std::ostream& err, const Scene& scene, const SurfaceModelCheck& check);

/// @brief summary.json of the observer box (runJson() first): lattice, counts, blocks,
/// evaluations, peak, volumes above fractions of the peak, memory; the unconverged points
/// with what @p zone says of them.
nlohmann::json volumeSummaryJson(const ObserverField& field, const HazardZone& zone,
                                 const RunInfo& info, const CullStats& cull);

/// @brief The one-screen summary of the box. @p beyond_box: what the far field says of the
/// hazard beyond the box ("" without one).
void printVolume(std::ostream& err, const ObserverField& field, const Scene& scene,
                 const HazardZone& zone, const RunInfo& info, bool uniform,
                 const std::string& beyond_box);

/// @brief One plane's entry of summary.json's `planes`, with each level of @p h (`levels`).
nlohmann::json planeJson(const PlaneSpec& plane, const ObserverField& field, const HazardZone& zone,
                         const HazardSpec& h);

/// @brief One plane's lines on the terminal, a line per level of @p h.
void printPlane(std::ostream& err, const PlaneSpec& plane, const ObserverField& field,
                const HazardZone& zone, const HazardSpec& h);

/// @brief summary.json's `far_field`: the @p files written of it, the map, its far radius and
/// rule, counts, the peak and @p hazard's NOHD.
nlohmann::json farFieldJson(const FarField& field, const FarHazard& hazard,
                            const std::vector<std::string>& files, const HazardSpec& h);

/// @brief The far field's lines on the terminal, a line per level of @p h.
void printFarField(std::ostream& err, const FarField& field, const FarHazard& hazard,
                   const HazardSpec& h);

/// @brief The reach per threshold: the MPE's entry (distance, direction and its azimuth and
/// elevation, where it comes from, closed, farthest point, volume, the lit ball's volume), and
/// the aided MPE's under `aided`, each level's under `levels` (a scenario's result.json holds
/// this).
nlohmann::json reachSummaryJson(const std::vector<ReachSummary>& reach, const HazardSpec& h);

/// @brief summary.json's `hazard_reach`: per threshold (the MPE, the aided MPE, the levels) the
/// farthest hazardous point, its direction, whether the boundary is closed and the volume;
/// the lattice and its cost (@p seconds).
nlohmann::json reachJson(const NearReach& near, const std::vector<ReachSummary>& reach,
                         double seconds, const HazardSpec& h);

/// @brief The reach's line on the terminal (and the aided reach's and each level's). Where the
/// beam lights no facet (@p lit false) an empty reach is no verdict, and says so instead of
/// "nothing is hazardous".
void printReach(std::ostream& err, const NearReach& near, const std::vector<ReachSummary>& reach,
                double seconds, const HazardSpec& h, bool lit = true);

/// @brief summary.json's `timing`: the run's wall time until summary.json is written, each
/// phase's seconds in order, and what no phase holds.
nlohmann::json timingJson(const PhaseClock& clock);

/// @brief What the files of a run of @p scene record about it: the program, the scene file and
/// the hash of its text @p scene_text, the scheme ("adaptive" or "uniform"), the laser and MPE.
RunInfo runInfo(const Scene& scene, const std::string& scene_file, std::string_view scene_text,
                const std::string& scheme);

}  // namespace glint
