#include "pipeline/report/run_folder.h"

#include <algorithm>
#include <nlohmann/json.hpp>

#include "export/atomic_file.h"
#include "pipeline/base/output_names.h"
#include "pipeline/input/json_reader.h"

namespace glint {

namespace fs = std::filesystem;

EarlierRun earlierRun(const fs::path& folder) {
  EarlierRun e;
  std::error_code ec;
  const fs::path summary = folder / output_names::kSummary;
  if (!fs::is_regular_file(summary, ec)) return e;
  try {
    const nlohmann::json j = nlohmann::json::parse(readUserFile(summary, "summary"));
    if (j.contains("scene_path")) {
      e.scene_path = j.at("scene_path").get<std::string>();
    } else if (j.contains("scene_file")) {
      // Before scene_path was written: scene_file as given, relative to where glint ran.
      e.scene_path = sceneIdentity(j.at("scene_file").get<std::string>());
    }
    if (j.contains("files")) e.files = j.at("files").get<std::vector<std::string>>();
    e.present = true;
  } catch (const std::exception&) {
    return EarlierRun{};  // not a summary glint can read: not a run to compare with
  }
  return e;
}

std::string sceneIdentity(const fs::path& scene_file) {
  std::error_code ec;
  const fs::path resolved = fs::weakly_canonical(fs::absolute(scene_file, ec), ec);
  return (ec ? fs::absolute(scene_file).lexically_normal() : resolved).string();
}

void requireSameScene(const fs::path& folder, const EarlierRun& earlier,
                      const fs::path& scene_file) {
  if (!earlier.present || earlier.scene_path.empty()) return;
  if (earlier.scene_path == sceneIdentity(scene_file)) return;
  throw OutputError(folder.string() + " holds the outputs of another scene (" + earlier.scene_path +
                    "); choose another folder with -o, or remove them");
}

std::vector<std::string> staleOutputs(const fs::path& folder, const EarlierRun& earlier,
                                      const std::vector<std::string>& writing) {
  std::vector<std::string> stale;
  for (const std::string& name : earlier.files) {
    if (std::find(writing.begin(), writing.end(), name) != writing.end()) continue;
    // A listed name is the earlier run's own file: one that tries to leave the folder is not.
    const fs::path p(name);
    if (p.has_parent_path() || p.is_absolute() || name.empty()) continue;
    std::error_code ec;
    if (fs::exists(folder / p, ec)) stale.push_back(name);
  }
  return stale;
}

}  // namespace glint
