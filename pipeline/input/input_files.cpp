#include "pipeline/input/input_files.h"

#include <sys/stat.h>

#include "export/atomic_file.h"
#include "pipeline/input/scene.h"

namespace glint {
namespace {

namespace fs = std::filesystem;

// The file a path names, links followed (an output is compared with what it would replace).
bool identify(const fs::path& path, dev_t& device, ino_t& inode) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return false;
  device = st.st_dev;
  inode = st.st_ino;
  return true;
}

}  // namespace

void InputFiles::add(const fs::path& path, const std::string& role) {
  File f{0, 0, path, role};
  if (identify(path, f.device, f.inode)) files_.push_back(std::move(f));
}

void InputFiles::addScene(const fs::path& path, const Scene& scene) {
  add(path, "scene file");
  for (const ObjectSpec& o : scene.objects) {
    if (o.mesh()) add(o.mesh()->file, "mesh file");
  }
  for (const fs::path& table : scene.material_table_files) {
    if (!table.empty()) add(table, "BRDF table");
  }
}

void InputFiles::requireNotAnInput(const fs::path& output) const {
  dev_t device = 0;
  ino_t inode = 0;
  if (!identify(output, device, inode)) return;  // a new file
  for (const File& f : files_) {
    if (f.device == device && f.inode == inode) {
      throw OutputError(output.string() + " is the " + f.role + " " + f.path.string() +
                        ": glint never writes over its own input; name another output");
    }
  }
}

void InputFiles::requireNotHeldBy(const fs::path& folder) const {
  dev_t device = 0;
  ino_t inode = 0;
  if (!identify(folder, device, inode)) return;  // not there yet: it holds nothing
  for (const File& f : files_) {
    std::error_code ec;
    const fs::path resolved = fs::canonical(f.path, ec);
    if (ec) continue;
    // Up the input's real folders, each compared by identity with the output folder.
    for (fs::path p = resolved.parent_path();; p = p.parent_path()) {
      dev_t d = 0;
      ino_t i = 0;
      if (identify(p, d, i) && d == device && i == inode) {
        throw OutputError(folder.string() + " holds the " + f.role + " " + f.path.string() +
                          ": glint writes and replaces files in its output folder, so it "
                          "must not be one that holds an input; choose another with -o");
      }
      if (p == p.root_path() || p.empty()) break;
    }
  }
}

}  // namespace glint
