#pragma once
// A small file system of the test's own to fill: a tmpfs mounted inside the test's folder (the
// tests run as root) and unmounted when done. A tmpfs counts whole 4 KiB pages against its
// size, so a test can fill it to the page.
#include <sys/mount.h>

#include <cerrno>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <string>
#include <utility>

namespace glint::test {

/// @brief The pages of 4 KiB a file of @p bytes takes on a tmpfs.
inline std::uint64_t tmpfsPages(std::uintmax_t bytes) { return (bytes + 4095) / 4096; }

/// @brief The pages every file under @p dir takes on a tmpfs.
inline std::uint64_t tmpfsPagesUnder(const std::filesystem::path& dir) {
  std::uint64_t pages = 0;
  for (const auto& e : std::filesystem::recursive_directory_iterator(dir)) {
    if (e.is_regular_file()) pages += tmpfsPages(e.file_size());
  }
  return pages;
}

/// @brief A tmpfs of a given number of pages mounted at a folder for this object's life.
class SmallDisk {
 public:
  /// @brief Mounts it at @p dir (made if missing); mounted() says whether that worked.
  SmallDisk(std::filesystem::path dir, std::uint64_t pages) : dir_(std::move(dir)) {
    std::filesystem::create_directories(dir_);
    const std::string options = "size=" + std::to_string(pages * 4096) + ",mode=0755";
    if (::mount("tmpfs", dir_.c_str(), "tmpfs", 0, options.c_str()) == 0) {
      mounted_ = true;
    } else {
      why_ = std::strerror(errno);
    }
  }
  ~SmallDisk() {
    if (mounted_) ::umount2(dir_.c_str(), MNT_DETACH);
  }
  SmallDisk(const SmallDisk&) = delete;
  SmallDisk& operator=(const SmallDisk&) = delete;

  [[nodiscard]] bool mounted() const { return mounted_; }
  /// @brief Why it could not be mounted.
  [[nodiscard]] const std::string& why() const { return why_; }

  /// @brief Gives it @p pages in all, its files kept. Returns whether that worked.
  bool resize(std::uint64_t pages) {
    const std::string options = "size=" + std::to_string(pages * 4096);
    return ::mount("tmpfs", dir_.c_str(), "tmpfs", MS_REMOUNT, options.c_str()) == 0;
  }

 private:
  std::filesystem::path dir_;
  bool mounted_ = false;
  std::string why_;
};

}  // namespace glint::test
