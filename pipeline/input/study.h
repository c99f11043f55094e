#pragma once
/// @file
/// @brief A batch study: a base scene and the scenarios made from it by sweeps of the target's
/// orientation and material, seeded laser pointing jitter and a trajectory of target poses
/// (docs/batch.md).

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "facets/vec3.h"
#include "pipeline/input/scene.h"

namespace glint {

/// @brief A pose of the target: turned about the study's pivot (yaw about z, then pitch about
/// the turned y, then roll about the turned x: R = Rz(yaw) Ry(pitch) Rx(roll)) and moved by
/// offset_m.
struct Pose {
  double time_s = 0.0;
  Vec3 offset_m{0.0};
  double yaw_deg = 0.0;
  double pitch_deg = 0.0;
  double roll_deg = 0.0;
};

/// @brief One scenario: the base scene with these changes.
struct Scenario {
  std::size_t index = 0;
  Pose pose;  ///< from the trajectory (identity without one)
  /// The swept orientation, applied before the pose: the target turns by R_pose · R_sweep.
  double yaw_deg = 0.0;
  double pitch_deg = 0.0;
  double roll_deg = 0.0;
  std::optional<double> sigma;                 ///< swept σ; unset: as in the scene
  std::optional<double> specular_reflectance;  ///< swept; unset: as in the scene
  /// Swept surface state: the base scene's material of this index stands in for the swept
  /// material(s), lobes, ABg, table and all (before σ and reflectance); unset: as in the scene.
  std::optional<std::size_t> surface_state;
  int jitter_sample = -1;  ///< −1: no jitter
  /// Pointing error: the laser's direction d becomes d + tan(u) e_u + tan(v) e_v, normalised,
  /// with e_u = anyPerpendicular(d) and e_v = d × e_u.
  double jitter_u_rad = 0.0;
  double jitter_v_rad = 0.0;
};

/// @brief A loaded, validated study.
struct Study {
  std::string source;  ///< the study file as given, for messages
  std::string description;
  std::filesystem::path scene_path;  ///< the base scene (relative to the study file)
  std::string scene_text;            ///< its bytes
  Scene base;
  Vec3 pivot_m{0.0};     ///< centre of the target's turns (default: mean of object centres)
  std::string material;  ///< the material the σ and reflectance sweeps change ("": all)
  double jitter_sigma_rad = 0.0;
  std::uint64_t jitter_seed = 0;
  /// Key `pointing_jitter.precision`: instead of a sample count, run jitter samples in rounds
  /// until every point's coverage interval (at coverage_confidence) is at most twice this wide,
  /// or max_samples are run. Unset: `samples`, all at once.
  std::optional<double> precision_half_width;
  int first_round_samples = 32;  ///< the first round's jitter samples; each next doubles them
  int max_samples = 0;           ///< the jitter samples scenarios are made for
  /// Scenarios per jitter sample (the other parameters' combinations): 1 with a precision, so
  /// that the first k samples are the first k scenarios and a round adds scenarios after those
  /// already run.
  std::size_t scenarios_per_sample = 1;
  /// Key `coverage`: the confidence of the coverage maps' intervals (each point's, and the
  /// whole map's at once), and the probability the summary's hazardous region is stated for.
  double coverage_confidence = 0.95;
  double coverage_probability = 0.5;
  std::vector<Scenario> scenarios;
  /// FNV-1a of the study's and the base scene's bytes: a resumed study must match it.
  std::string fnv1a64;
};

/// @brief The combinations of other parameters that share each jitter sample of @p study: its
/// scenarios per sample when it has jitter, else 1 (every scenario a case of its own). Above
/// 1, a study's coverage intervals keep each combination's counts apart
/// (pipeline/setup/study_maps.h).
std::size_t jitterSharingCombinations(const Study& study);

/// @brief The combination scenario @p s belongs to (< jitterSharingCombinations()).
std::size_t combinationOf(const Study& study, const Scenario& s);

/// @brief The number of scenarios each round of @p study runs up to (cumulative): all of them
/// at once without a precision, else the first round's samples doubling up to max_samples.
std::vector<std::size_t> studyRounds(const Study& study);

/// @brief Reads a study file and its base scene, expands its scenarios and validates every
/// scenario's scene, so that a bad value stops the study before any work.
/// With @p memory_budget_bytes > 0 the base scene's meshes and terrain are held to it as
/// loadScene() holds them.
/// @throw InputError naming the file and JSON pointer (or the scenario) of the first problem.
Study loadStudy(const std::filesystem::path& path, std::uint64_t memory_budget_bytes = 0);

/// @brief Validates study JSON text; @p dir is where its `scene` path starts from.
Study parseStudy(std::string_view json_text, const std::string& source,
                 const std::filesystem::path& dir, std::uint64_t memory_budget_bytes = 0);

/// @brief The scene file of one scenario: the base scene's JSON with objects turned and moved,
/// materials and the laser's direction changed, the record a scenario's folder keeps
/// (`glint run` can run it alone; parsed, it is scenarioScene()'s scene).
std::string scenarioSceneJson(const Study& study, const Scenario& scenario);

/// @brief The validated scene of one scenario, made from the base scene in memory: its loaded
/// meshes turned, not read again; named "<study> scenario <index>" in messages.
/// @throw InputError naming the scenario when its changes make the scene invalid.
Scene scenarioScene(const Study& study, const Scenario& scenario);

/// @brief The rotation of a pose's angles applied to @p v (see Pose).
Vec3 rotateYawPitchRoll(const Vec3& v, double yaw_deg, double pitch_deg, double roll_deg);

}  // namespace glint
