#pragma once
/// @file
/// @brief Output files that appear whole or not at all, safe in a shared folder and on
/// interruption.

#include <filesystem>
#include <memory>
#include <optional>
#include <ostream>
#include <stdexcept>
#include <string>

namespace glint {

/// @brief A failure to write an output file (the message names the file).
class OutputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// @brief Writes @c target through a temporary file beside it, renamed over the target by
/// commit().
///
/// - Whole or nothing: a run that fails before commit() leaves no partial file (the
///   destructor removes the temporary), and so does SIGINT, SIGTERM or SIGHUP once
///   installInterruptCleanup() is in place.
/// - Safe in a folder others can write to: the temporary is created with O_CREAT | O_EXCL |
///   O_NOFOLLOW under an unpredictable name (`.<name>.glint-<pid>-<random>`), so a link planted
///   in advance can neither redirect the write nor be followed; rename() then replaces the
///   target itself, never a file a link at the target points to.
/// - Never replaces what is not a regular file: a target that exists as a device, FIFO,
///   socket, folder or symbolic link is refused, when constructed and again just before the
///   rename (rename() would put a file where `/dev/null` or a user's link was).
/// - A process killed outright (SIGKILL) leaves its temporaries; the next AtomicFile in that
///   folder removes those whose process is gone.
class AtomicFile {
 public:
  /// @throw OutputError when the target exists and is not a regular file, or when the
  /// temporary cannot be created (missing folder, permissions).
  explicit AtomicFile(std::filesystem::path target);
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  /// @brief Where to write the content.
  std::ostream& stream();

  /// @brief Flushes, checks every write succeeded, and renames the temporary to the target.
  /// @throw OutputError on any failure (disk full, ...); the temporary is then removed.
  void commit();

  /// @brief The temporary's path (for tests).
  [[nodiscard]] const std::filesystem::path& temporaryPath() const { return temporary_; }

 private:
  // Removes the temporary and throws OutputError(message), after an interrupt's exit if one
  // is under way.
  [[noreturn]] void abandon(const std::string& message);

  struct Stream;
  std::filesystem::path target_;
  std::filesystem::path temporary_;
  std::unique_ptr<Stream> out_;
  int slot_ = -1;  // in the interrupt cleanup's registry
  bool committed_ = false;
};

/// @brief What @p path is when it exists and is not a regular file ("a character device", "a
/// FIFO", "a folder", "a symbolic link", ...; a link is not followed), else nothing: the
/// paths an output must never replace.
std::optional<std::string> nonRegularKind(const std::filesystem::path& path);

/// @brief Installs handlers for SIGINT, SIGTERM and SIGHUP that remove every uncommitted
/// AtomicFile temporary, say so on standard error and exit with 128 + the signal's number
/// (130, 143, 129). For the program's main(); idempotent.
void installInterruptCleanup();

/// @brief What else the interrupt handler takes away besides the temporaries.
enum class InterruptCleanup {
  RemoveFile,        ///< a file of the run's own (a folder's lock file)
  RemoveEmptyFolder  ///< a folder the run made, if it is empty once the files are gone
};

/// @brief Has the interrupt handler remove @p path as @p what says, until forgetOnInterrupt()
/// with the returned slot (-1 when the registry is full: then nothing is removed).
int removeOnInterrupt(const std::filesystem::path& path, InterruptCleanup what);

/// @brief Undoes removeOnInterrupt(); -1 is ignored.
void forgetOnInterrupt(int slot);

/// @brief Removes the temporaries of processes that no longer exist from @p folder (links and
/// files alike are unlinked, never followed; a staging folder of theirs goes whole). Returns
/// how many were removed.
int removeStaleTemporaries(const std::filesystem::path& folder);

}  // namespace glint
