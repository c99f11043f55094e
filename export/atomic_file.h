#pragma once
/// @file
/// @brief Output files that appear whole or not at all.

#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>

namespace glint {

/// @brief A failure to write an output file (the message names the file).
class OutputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// @brief Writes @c target through a temporary file beside it, renamed over the target by
/// commit(). A run that fails before commit() leaves no partial file: the destructor removes
/// the temporary.
class AtomicFile {
 public:
  /// @throw OutputError when the temporary cannot be created (missing folder, permissions).
  explicit AtomicFile(std::filesystem::path target);
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  /// @brief Where to write the content.
  std::ostream& stream() { return out_; }

  /// @brief Flushes, checks every write succeeded, and renames the temporary to the target.
  /// @throw OutputError on any failure (disk full, ...); the temporary is then removed.
  void commit();

 private:
  std::filesystem::path target_;
  std::filesystem::path temporary_;
  std::ofstream out_;
  bool committed_ = false;
};

}  // namespace glint
