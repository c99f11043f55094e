#pragma once
/// @file
/// @brief Output files that appear whole or not at all, safe in a shared folder and on
/// interruption.

#include <cstddef>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <ostream>
#include <stdexcept>
#include <string>
#include <vector>

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

  /// @brief Writes the content through @p content (a library's writer, as often as not): when
  /// the file system refuses a byte (disk full, EIO, EFBIG), whatever the library makes of it
  /// (an exception of its own, or nothing), and when the writer throws an OutputError of its
  /// own, the temporary is removed and one OutputError naming the file and the reason is thrown.
  void write(const std::function<void(std::ostream&)>& content);

  /// @brief Flushes and closes the temporary and checks that every write succeeded: the file is
  /// then whole and only its rename is left. Does nothing the second time.
  /// @throw OutputError naming the file and the reason; the temporary is then removed.
  void close();

  /// @brief close(), then renames the temporary over the target: one file alone (a set of
  /// outputs is an OutputSet's).
  /// @throw OutputError on any failure (disk full, ...); the temporary is then removed.
  void commit();

  /// @brief The temporary's path (for tests).
  [[nodiscard]] const std::filesystem::path& temporaryPath() const { return temporary_; }

 private:
  friend class OutputSet;

  // Removes the temporary and throws OutputError(message), after an interrupt's exit if one
  // is under way.
  [[noreturn]] void abandon(const std::string& message);
  // What the file system said when it refused a write: "cannot write TARGET: REASON".
  [[nodiscard]] std::string refusal() const;
  // The temporary is in place under the target's name (an OutputSet moved it).
  void moved();

  struct Stream;
  std::filesystem::path target_;
  std::filesystem::path temporary_;
  std::unique_ptr<Stream> out_;
  int slot_ = -1;  // in the interrupt cleanup's registry
  bool committed_ = false;
};

/// @brief A command's outputs, made visible together or not at all: a failed or interrupted
/// command leaves the folder as it was before it, an earlier run's files included.
///
/// - Each file is written to an AtomicFile temporary, and a library's folder of files to a
///   staging folder (addStaged()). commit() first closes every file and checks its every write
///   (a full disk stops it here, before anything is moved), then moves each over its final
///   name, in the order opened, those opened `last` (summary.json) after all the others.
/// - The file a move replaces is kept aside under a temporary's name (a hard link, or the file
///   itself renamed where the file system has no links; a folder inside its staging folder)
///   until every output is in place. A move that fails half way undoes the moves made and puts
///   each earlier file back; so does SIGINT, SIGTERM or SIGHUP, once installInterruptCleanup()
///   is in place, whenever it lands.
/// - A SIGKILL or a power cut during the moves (microseconds a file) can leave some new
///   outputs beside the earlier ones; summary.json, moved last, is then the earlier run's.
class OutputSet {
 public:
  OutputSet();
  /// @brief Removes what was not committed: the temporaries, and nothing in place.
  ~OutputSet();
  OutputSet(const OutputSet&) = delete;
  OutputSet& operator=(const OutputSet&) = delete;

  /// @brief Opens the AtomicFile of @p target, the set's own; @p last: moved in after every
  /// output not so marked (the file that says the command finished).
  /// @throw OutputError as AtomicFile's constructor.
  AtomicFile& open(std::filesystem::path target, bool last = false);

  /// @brief Adds @p staged, a file or folder a library wrote whole into @p scratch, a staging
  /// folder of the command's own beside @p target (the same file system), to be moved over
  /// @p target; a folder it replaces waits inside @p scratch. The caller keeps @p scratch
  /// until the set is committed or dropped, and then removes it.
  void addStaged(std::filesystem::path staged, std::filesystem::path target,
                 std::filesystem::path scratch);

  /// @brief Closes every file, then moves every output over its name (see the class); calls
  /// @p after_first once the first of several is in place and before the next (a test's pause
  /// point).
  /// @throw OutputError naming the file that could not be written or moved; the folder is
  /// then as it was before.
  void commit(const std::function<void()>& after_first = {});

 private:
  struct Pending;
  std::vector<std::unique_ptr<AtomicFile>> files_;
  std::vector<Pending> pending_;
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
  RemoveFile,         ///< a file of the run's own (a folder's lock file)
  RemoveEmptyFolder,  ///< a folder the run made, if it is empty once the files are gone
  RemoveTree          ///< a staging folder of the run's own, with all it holds
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
