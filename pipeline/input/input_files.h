#pragma once
/// @file
/// @brief The files a command reads, known by device and inode, so that no output replaces
/// one of them, whatever name the output is given (`./P.csv`, `../run/P.csv`, a hard link).

#include <sys/types.h>

#include <filesystem>
#include <string>
#include <vector>

namespace glint {

struct Scene;

/// @brief A command's inputs: the scene (and the meshes it names), a points file, a study.
class InputFiles {
 public:
  /// @brief Adds @p path as @p role ("scene file", "points file", ...); a path that cannot
  /// be reached is skipped (its reader reports it).
  void add(const std::filesystem::path& path, const std::string& role);

  /// @brief Adds the scene file @p path and every mesh file @p scene names.
  void addScene(const std::filesystem::path& path, const Scene& scene);

  /// @brief Refuses an output file that is one of the inputs.
  /// @throw OutputError naming both, before anything is written.
  void requireNotAnInput(const std::filesystem::path& output) const;

  /// @brief Refuses an output folder that holds an input, at any depth: glint writes, replaces
  /// and (batch --fresh) removes files there.
  /// @throw OutputError naming the folder and the input.
  void requireNotHeldBy(const std::filesystem::path& folder) const;

 private:
  struct File {
    dev_t device;
    ino_t inode;
    std::filesystem::path path;
    std::string role;
  };
  std::vector<File> files_;
};

}  // namespace glint
