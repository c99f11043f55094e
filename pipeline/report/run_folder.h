#pragma once
/// @file
/// @brief A `glint run` output folder that may hold an earlier run's outputs: another scene's
/// are refused (as a batch folder is), and the earlier run's files that this run will not
/// rewrite are named, so no stale map passes for a new one.

#include <filesystem>
#include <string>
#include <vector>

namespace glint {

/// @brief What an earlier run left in @p folder, judged by its summary.json.
struct EarlierRun {
  bool present = false;            ///< the folder holds a glint summary.json
  std::string scene_path;          ///< the scene it ran (absolute), or "" when unknown
  std::vector<std::string> files;  ///< the outputs it listed (empty for older runs)
};

/// @brief Reads @p folder's summary.json, if any (a damaged one counts as none).
EarlierRun earlierRun(const std::filesystem::path& folder);

/// @brief The absolute, normalised path that identifies a scene file in summary.json.
std::string sceneIdentity(const std::filesystem::path& scene_file);

/// @brief Refuses a folder whose earlier run was of another scene file.
/// @throw OutputError naming the folder, that scene and what to do.
void requireSameScene(const std::filesystem::path& folder, const EarlierRun& earlier,
                      const std::filesystem::path& scene_file);

/// @brief The earlier run's outputs still in @p folder that @p writing does not include.
std::vector<std::string> staleOutputs(const std::filesystem::path& folder,
                                      const EarlierRun& earlier,
                                      const std::vector<std::string>& writing);

}  // namespace glint
