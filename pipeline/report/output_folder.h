#pragma once
/// @file
/// @brief A command's output folder for the length of a run: never one that holds an input, one
/// glint process at a time, and a failed run takes away the folders it made (docs/reliability.md:
/// what an output may replace, one run per folder).

#include <exception>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace glint {

/// @brief An exclusive lock on an output folder for the life of this object: flock(2) on the
/// folder's lock file, `FOLDER/.glint-lock`.
///
/// - The holder writes its PID, host name, start time (UTC) and command into the lock file, so
///   that a second process is refused with a message naming it.
/// - The kernel drops a flock with its process, so a lock file left by a process that was
///   killed is not held by anyone and blocks nothing: the next process takes it over.
/// - The lock file is removed when the lock is released. A process that opened it just before
///   is not fooled: after locking, the constructor checks that the path still names the file it
///   locked, and starts again if not.
/// - Across machines, as strong as the file system's locks (local file systems and NFSv4 lock
///   for every client; some cluster file systems need a mount option for flock).
/// An MPI job takes it on rank 0 alone: the other ranks write only what rank 0 hands them.
class FolderLock {
 public:
  /// @brief The lock file's name inside the folder.
  static constexpr const char* kFileName = ".glint-lock";

  /// @brief Takes the lock of @p folder (which must exist) for this process; @p command names
  /// what holds it ("glint batch") in another process's refusal.
  /// @throw OutputError "FOLDER is in use by glint process PID on host HOST (since TIME, glint
  /// batch)..." when another process holds it, or when the lock file cannot be made or is not
  /// a regular file (a link or a FIFO planted there is refused, never followed).
  FolderLock(const std::filesystem::path& folder, std::string_view command);
  /// @brief Removes the lock file and releases the lock.
  ~FolderLock();
  FolderLock(const FolderLock&) = delete;
  FolderLock& operator=(const FolderLock&) = delete;

  /// @brief The lock file.
  [[nodiscard]] const std::filesystem::path& file() const { return file_; }

 private:
  std::filesystem::path folder_;
  std::filesystem::path file_;
  int fd_ = -1;
  int interrupt_slot_ = -1;  ///< the lock file goes with an interrupted run's temporaries
};

/// @brief Refuses to write into @p folder while another process holds its FolderLock (a `glint
/// run` or `glint batch` writing there), as a command that writes single files there (`glint
/// points --out`) must: its file would land in a folder whose contents the holder is about to
/// replace. A folder with no lock file, or one nobody holds, passes.
/// @throw OutputError "FOLDER is in use by glint process PID …", as FolderLock's own refusal.
void requireFolderNotHeld(const std::filesystem::path& folder);

/// @brief The folders a run made itself (`mkdir -p` that remembers which levels were missing),
/// so that a run that fails can take them away again, and nothing else.
class CreatedFolders {
 public:
  CreatedFolders() = default;
  /// @brief Keeps the folders (a run that succeeded).
  ~CreatedFolders();
  CreatedFolders(const CreatedFolders&) = delete;
  CreatedFolders& operator=(const CreatedFolders&) = delete;

  /// @brief Makes @p folder and its missing parents, remembering each level this call made (a
  /// level another process made meanwhile is not remembered).
  /// @throw OutputError naming the level that cannot be made.
  void create(const std::filesystem::path& folder);

  /// @brief Whether this object made @p folder (as spelled to create(), or one of its parents).
  [[nodiscard]] bool made(const std::filesystem::path& folder) const;

  /// @brief Removes the folders it made, deepest first, each only if it is empty (rmdir(2): a
  /// folder holding anything stays, with everything in it). Never throws. So does an interrupt
  /// (SIGINT, SIGTERM, SIGHUP) while this object lives.
  void removeEmpty() noexcept;

 private:
  std::vector<std::filesystem::path> made_;  ///< in the order made: parents first
  /// An interrupted run's handler removes them too, if empty (export/atomic_file.h).
  std::vector<int> interrupt_slots_;
};

/// @brief Runs a cleanup when the scope it guards is left by an exception, and not when it ends
/// normally (std::uncaught_exceptions() at construction and destruction tell which). The
/// cleanup must not throw.
class OnFailure {
 public:
  explicit OnFailure(std::function<void()> cleanup)
      : cleanup_(std::move(cleanup)), exceptions_(std::uncaught_exceptions()) {}
  ~OnFailure() {
    if (cleanup_ && std::uncaught_exceptions() > exceptions_) cleanup_();
  }
  OnFailure(const OnFailure&) = delete;
  OnFailure& operator=(const OnFailure&) = delete;

 private:
  std::function<void()> cleanup_;
  int exceptions_;
};

class InputFiles;

/// @brief The output folder of `glint run` or `glint batch` while the run lasts: refused when it
/// holds one of @p inputs, made (remembering which levels), and locked (FolderLock). When the
/// run fails (an exception leaves the scope that owns this object), the lock is released and
/// the folders it made are removed if empty; @p before_release runs first, with the lock still
/// held, for a command's own files (a batch's unfinished scenarios).
///
/// Declare it before the command's AtomicFile outputs: they are destroyed first, their
/// temporaries gone before the folders are emptied.
class OutputFolder {
 public:
  /// @throw OutputError naming the input held, the folder that cannot be made, or the
  /// process that holds it.
  OutputFolder(const std::filesystem::path& folder, const InputFiles& inputs,
               std::string_view command,
               std::function<void(const OutputFolder&)> before_release = {});

  [[nodiscard]] const std::filesystem::path& path() const { return folder_; }
  /// @brief Makes a folder inside (and remembers it, as the folder itself).
  void create(const std::filesystem::path& sub) { created_.create(sub); }
  /// @brief Whether this run made @p folder.
  [[nodiscard]] bool made(const std::filesystem::path& folder) const {
    return created_.made(folder);
  }

 private:
  std::filesystem::path folder_;
  CreatedFolders created_;
  std::optional<FolderLock> lock_;
  std::function<void(const OutputFolder&)> before_release_;
  OnFailure on_failure_;  // last: destroyed first, while the lock is still held
};

}  // namespace glint
