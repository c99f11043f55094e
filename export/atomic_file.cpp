#include "export/atomic_file.h"

#include <dirent.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cerrno>
#include <cstring>
#include <mutex>
#include <random>
#include <regex>
#include <set>
#include <streambuf>
#include <system_error>

namespace glint {
namespace {

// The temporaries not yet committed, and what else an interrupted run must take away, for the
// interrupt handler: fixed storage it can read without allocating. A slot is 0 free, 1 being
// filled, or live: 2 a temporary (unlinked and counted), 3 another file (a lock file:
// unlinked), 4 a folder the run made (removed if it is empty once the files are gone), 5 a
// staging folder (removed with all it holds, and counted).
constexpr int kSlots = 1024;
constexpr int kTemporary = 2;
constexpr int kOtherFile = 3;
constexpr int kMadeFolder = 4;
constexpr int kTree = 5;
constexpr std::size_t kPathBytes = 4096;
struct Slot {
  std::atomic<int> state{0};
  char path[kPathBytes];
};
std::array<Slot, kSlots> g_slots;

int registerTemporary(const std::string& path, int kind = kTemporary) {
  if (path.size() >= kPathBytes) return -1;
  for (int i = 0; i < kSlots; ++i) {
    int expected = 0;
    Slot& s = g_slots[static_cast<std::size_t>(i)];
    if (!s.state.compare_exchange_strong(expected, 1, std::memory_order_acq_rel)) continue;
    std::memcpy(s.path, path.c_str(), path.size() + 1);
    s.state.store(kind, std::memory_order_release);
    return i;
  }
  return -1;  // more than kSlots at once: left to removeStaleTemporaries()
}

void unregisterTemporary(int slot) {
  if (slot >= 0) g_slots[static_cast<std::size_t>(slot)].state.store(0, std::memory_order_release);
}

// An OutputSet's moves as the interrupt handler undoes them, one entry a move: its strings are
// made before the list is published and never change after; `state` is 0 not begun (or
// undone), 1 begun.
struct UndoEntry {
  std::atomic<int> state{0};
  bool folder = false;
  bool had_old = false;  // something stood at the target before (set before state 1)
  std::string target;
  std::string backup;  // where the earlier file or folder waits
  std::string trash;   // a folder's: where a new folder goes to be taken away with its staging
};
struct UndoList {
  std::unique_ptr<UndoEntry[]> entries;
  std::size_t count = 0;
  std::atomic<bool> complete{false};  // every move done: only the earlier files are to go
};
constexpr int kUndoLists = 8;
std::array<std::atomic<UndoList*>, kUndoLists> g_undo{};

// A signal may reach any thread, also while another creates a temporary or moves an output.
// The handler raises g_interrupted and then waits for every such step in flight, and a step
// starts only when the flag is down: so each file either is created and registered before the
// handler reads the registry, or never created, and each move is wholly done and recorded, or
// not begun. Sequentially consistent, as the argument needs.
std::atomic<bool> g_interrupted{false};
std::atomic<int> g_creating{0};
// A command's outputs are all in place (an OutputSet committed): an interrupt from then on
// finds the command's answer complete, and must not report the folder as it was.
std::atomic<bool> g_outputs_in_place{false};

// The handler is removing the temporaries and will exit: an error caused by its work (a
// temporary gone before its rename) must not race its exit status and message with one of our
// own. Returns if there is no interrupt.
void awaitInterruptExit() {
  if (!g_interrupted.load()) return;
  for (;;) ::pause();
}

// A step the handler must find wholly done or not begun (see g_creating), for the life of
// this object; with an interrupt under way, the constructor waits for its exit instead.
class UninterruptedStep {
 public:
  UninterruptedStep() {
    // The handler must not run on this thread inside the step, where it would wait for itself.
    sigset_t interrupts;
    sigemptyset(&interrupts);
    for (int sig : {SIGINT, SIGTERM, SIGHUP}) sigaddset(&interrupts, sig);
    ::pthread_sigmask(SIG_BLOCK, &interrupts, &previous_);
    g_creating.fetch_add(1);
    if (g_interrupted.load()) {
      g_creating.fetch_sub(1);
      awaitInterruptExit();  // do nothing now
    }
  }
  ~UninterruptedStep() {
    const int error = errno;
    g_creating.fetch_sub(1);
    ::pthread_sigmask(SIG_SETMASK, &previous_, nullptr);
    errno = error;
  }
  UninterruptedStep(const UninterruptedStep&) = delete;
  UninterruptedStep& operator=(const UninterruptedStep&) = delete;

 private:
  sigset_t previous_{};
};

// open(2) with O_CREAT | O_EXCL of a temporary, registered for the handler. Returns the file
// descriptor, or -1 with errno set (the slot is then -1).
int createRegistered(const std::filesystem::path& path, int& slot) {
  const UninterruptedStep step;
  slot = registerTemporary(path.string());
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0666);
  const int error = errno;
  if (fd < 0) {
    unregisterTemporary(slot);
    slot = -1;
  }
  errno = error;
  return fd;
}

// Removes the folder @p name under @p parent (a descriptor, or AT_FDCWD) with all it holds,
// @p depth levels deep at most; links are unlinked, never followed. Only system calls, for the
// interrupt handler too. Returns whether the folder is gone.
bool removeTree(int parent, const char* name, int depth) {
  const int fd = ::openat(parent, name, O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC);
  if (fd < 0) return false;
  // Entries removed while the folder is read may shift the rest: read it again from the start
  // until a pass removes nothing.
  for (bool removed = true; removed;) {
    removed = false;
    if (::lseek(fd, 0, SEEK_SET) != 0) break;
    alignas(8) char buf[2048];
    for (ssize_t n; (n = ::getdents64(fd, buf, sizeof buf)) > 0;) {
      for (ssize_t at = 0; at < n;) {
        const auto* e = reinterpret_cast<const struct dirent64*>(buf + at);
        at += e->d_reclen;
        const char* entry = e->d_name;
        if (std::strcmp(entry, ".") == 0 || std::strcmp(entry, "..") == 0) continue;
        if (::unlinkat(fd, entry, 0) == 0 ||
            (depth > 0 && (e->d_type == DT_DIR || errno == EISDIR) &&
             removeTree(fd, entry, depth - 1))) {
          removed = true;
        }
      }
    }
  }
  ::close(fd);
  return ::unlinkat(parent, name, AT_REMOVEDIR) == 0;
}

// How deep a staging folder goes: a VTK data set's blocks, and an earlier one kept aside.
constexpr int kTreeDepth = 4;

bool exists(const char* path) {
  struct stat st {};
  return ::lstat(path, &st) == 0;
}

// Undoes one begun move of an OutputSet (system calls only: the handler's too). Counts what it
// put back and what new output it took away.
void undoMove(const UndoEntry& e, int& restored, int& removed) {
  const char* target = e.target.c_str();
  if (!e.folder) {
    // The earlier file kept aside (a link to it, or itself) goes back over whatever stands at
    // the target; where it was never kept aside, the target is still the earlier file.
    if (e.had_old) {
      // rename(2) of a link over the file it links to succeeds and does nothing: the link then
      // goes by itself.
      if (::rename(e.backup.c_str(), target) == 0) {
        ::unlink(e.backup.c_str());
        ++restored;
      }
    } else if (::unlink(target) == 0) {
      ++removed;
    }
    return;
  }
  // A folder cannot be renamed over one that holds files: the new one goes into the staging
  // folder first (taken away with it), then the earlier one comes back.
  if (exists(e.backup.c_str())) {
    ::rename(target, e.trash.c_str());
    if (::rename(e.backup.c_str(), target) == 0) ++restored;
  } else if (!e.had_old && ::rename(target, e.trash.c_str()) == 0) {
    ++removed;
  }
}

// write(2) of a C string and of a small number: all a signal handler may use.
void say(const char* s) {
  const std::size_t n = std::strlen(s);
  ssize_t ignored = ::write(STDERR_FILENO, s, n);
  (void)ignored;
}
void sayNumber(int n) {
  char digits[16];
  int k = 0;
  do {
    digits[k++] = static_cast<char>('0' + n % 10);
    n /= 10;
  } while (n > 0 && k < 15);
  char out[16];
  for (int i = 0; i < k; ++i) out[i] = digits[k - 1 - i];
  out[k] = '\0';
  say(out);
}

extern "C" void onInterrupt(int sig) {
  g_interrupted.store(true);
  while (g_creating.load() > 0) {
    // A creation in flight: one open(2) on another thread, soon registered.
  }
  int removed = 0;
  int restored = 0;
  bool unfinished = false;  // a set of outputs not wholly in place, or a file still being written
  // The outputs moved into place go first (an earlier file comes back from aside, a new folder
  // goes into its staging folder), then the temporaries and staging folders.
  for (const std::atomic<UndoList*>& slot : g_undo) {
    const UndoList* list = slot.load();
    if (list == nullptr) continue;
    const bool complete = list->complete.load();
    unfinished = unfinished || !complete;
    for (std::size_t i = list->count; i-- > 0;) {
      const UndoEntry& e = list->entries[i];
      if (e.state.load() != 1) continue;
      if (!complete) {
        undoMove(e, restored, removed);
      } else if (!e.folder && e.had_old) {
        ::unlink(e.backup.c_str());  // a folder's waits in its staging folder, which goes next
      }
    }
  }
  int folders = 0;
  for (Slot& s : g_slots) {
    const int state = s.state.load(std::memory_order_acquire);
    if (state == kTemporary) unfinished = true;
    if (state == kTemporary && ::unlink(s.path) == 0) ++removed;
    if (state == kTree && removeTree(AT_FDCWD, s.path, kTreeDepth)) ++removed;
    if (state == kOtherFile) ::unlink(s.path);
    if (state == kMadeFolder) ++folders;
  }
  // Folders inside one another empty from the deepest: one pass per level at most.
  for (int pass = 0; pass < folders; ++pass) {
    bool progress = false;
    for (Slot& s : g_slots) {
      if (s.state.load(std::memory_order_acquire) == kMadeFolder && ::rmdir(s.path) == 0) {
        s.state.store(0, std::memory_order_release);
        progress = true;
      }
    }
    if (!progress) break;
  }
  say("\nglint: interrupted by ");
  say(sig == SIGINT ? "SIGINT" : sig == SIGTERM ? "SIGTERM" : "SIGHUP");
  if (g_outputs_in_place.load() && !unfinished) {
    // Only what was kept aside went (the staging folders hold nothing else by now).
    say(" after its outputs were in place: they are complete; what it would have printed after "
        "them was not printed (summary.json holds a run's warnings)\n");
    ::_exit(0);
  }
  say("; removed ");
  sayNumber(removed);
  say(" unfinished output file(s)");
  if (restored > 0) {
    say(" and put back ");
    sayNumber(restored);
    say(" earlier one(s) they were replacing");
  }
  say("\n");
  ::_exit(128 + sig);
}

// `.<name>.glint-<pid>-<8 random characters>`, and the `<name>.tmp.<pid>` of glint 0.1.
const std::regex kTemporaryName(R"(\..+\.glint-([0-9]+)-[A-Za-z0-9]{8}|.+\.tmp\.([0-9]+))");

std::string randomSuffix() {
  static constexpr char kAlphabet[] =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789";
  thread_local std::mt19937_64 rng{std::random_device{}()};
  std::string s(8, 'x');
  for (char& c : s) c = kAlphabet[rng() % (sizeof kAlphabet - 1)];
  return s;
}

// The folder @p target is in ("." for a bare name).
std::filesystem::path folderOf(const std::filesystem::path& target) {
  std::filesystem::path folder = target.parent_path();
  return folder.empty() ? std::filesystem::path(".") : folder;
}

// A new temporary's name beside @p target: `.<name>.glint-<pid>-<8 random characters>`, which
// kTemporaryName knows, in the same folder (so that a rename never crosses file systems).
std::filesystem::path temporaryBeside(const std::filesystem::path& target) {
  std::string name(1, '.');
  name.append(target.filename().string()).append(".glint-");
  name.append(std::to_string(::getpid())).append(1, '-').append(randomSuffix());
  return folderOf(target) / name;
}

// Each folder is swept of stale temporaries once per process.
void sweepOnce(const std::filesystem::path& folder) {
  static std::mutex mutex;
  static std::set<std::string> swept;
  {
    std::lock_guard<std::mutex> lock(mutex);
    if (!swept.insert(folder.string()).second) return;
  }
  removeStaleTemporaries(folder);
}

// Refuses a target that exists and is not a regular file (see the class's comment).
void requireReplaceable(const std::filesystem::path& target) {
  if (const auto kind = nonRegularKind(target)) {
    throw OutputError(target.string() + " is " + *kind +
                      ", not a regular file: glint writes only regular files and never "
                      "replaces anything else; name a new or regular file");
  }
}

}  // namespace

std::optional<std::string> nonRegularKind(const std::filesystem::path& path) {
  struct stat st {};
  if (::lstat(path.c_str(), &st) != 0) return std::nullopt;  // nothing there (or unreachable)
  switch (st.st_mode & S_IFMT) {
    case S_IFREG:
      return std::nullopt;
    case S_IFCHR:
      return "a character device";
    case S_IFBLK:
      return "a block device";
    case S_IFIFO:
      return "a FIFO";
    case S_IFSOCK:
      return "a socket";
    case S_IFDIR:
      return "a folder";
    case S_IFLNK:
      return "a symbolic link";
    default:
      return "not a regular file";
  }
}

// A streambuf over a file descriptor that remembers whether any write failed.
struct AtomicFile::Stream {
  class Buf : public std::streambuf {
   public:
    explicit Buf(int fd) : fd_(fd) { setp(buffer_.data(), buffer_.data() + buffer_.size()); }
    [[nodiscard]] bool failed() const { return failed_; }
    [[nodiscard]] int error() const { return error_; }  // the errno of the first failure
    int_type overflow(int_type c) override {
      if (!flush()) return traits_type::eof();
      if (!traits_type::eq_int_type(c, traits_type::eof())) {
        *pptr() = traits_type::to_char_type(c);
        pbump(1);
      }
      return traits_type::not_eof(c);
    }
    int sync() override { return flush() ? 0 : -1; }
    // OpenEXR writes its line offsets last and seeks back for them (tellp, seekp).
    pos_type seekoff(off_type off, std::ios_base::seekdir dir,
                     std::ios_base::openmode which) override {
      if ((which & std::ios_base::out) == 0 || !flush()) return pos_type(off_type(-1));
      const int whence = dir == std::ios_base::beg   ? SEEK_SET
                         : dir == std::ios_base::cur ? SEEK_CUR
                                                     : SEEK_END;
      const off_t at = ::lseek(fd_, static_cast<off_t>(off), whence);
      return at < 0 ? pos_type(off_type(-1)) : pos_type(static_cast<off_type>(at));
    }
    pos_type seekpos(pos_type pos, std::ios_base::openmode which) override {
      return seekoff(off_type(pos), std::ios_base::beg, which);
    }

   private:
    bool flush() {
      const char* p = pbase();
      while (p < pptr()) {
        const ssize_t n = ::write(fd_, p, static_cast<std::size_t>(pptr() - p));
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) {
          if (!failed_) error_ = n < 0 ? errno : ENOSPC;  // 0 bytes taken: no room
          failed_ = true;
          break;
        }
        p += n;
      }
      setp(buffer_.data(), buffer_.data() + buffer_.size());
      return !failed_;
    }
    int fd_;
    bool failed_ = false;
    int error_ = 0;
    std::array<char, 1 << 16> buffer_{};
  };

  explicit Stream(int f) : fd(f), buf(f), out(&buf) {}
  int fd;
  Buf buf;
  std::ostream out;
};

AtomicFile::AtomicFile(std::filesystem::path target) : target_(std::move(target)) {
  requireReplaceable(target_);
  sweepOnce(folderOf(target_));
  int fd = -1;
  for (int attempt = 0; attempt < 100 && fd < 0; ++attempt) {
    temporary_ = temporaryBeside(target_);
    fd = createRegistered(temporary_, slot_);
    if (fd < 0 && errno != EEXIST) break;
  }
  if (fd < 0) {
    const int error = errno;
    awaitInterruptExit();
    throw OutputError("cannot create " + target_.string() + ": " +
                      std::error_code(error, std::generic_category()).message() +
                      " (is the folder there and writable?)");
  }
  out_ = std::make_unique<Stream>(fd);
}

AtomicFile::~AtomicFile() {
  if (committed_) return;
  if (out_ && out_->fd >= 0) ::close(out_->fd);
  std::error_code ignored;
  std::filesystem::remove(temporary_, ignored);
  unregisterTemporary(slot_);
}

std::ostream& AtomicFile::stream() { return out_->out; }

std::string AtomicFile::refusal() const {
  const int error = out_->buf.error();
  return "cannot write " + target_.string() +
         (error != 0 ? ": " + std::error_code(error, std::generic_category()).message() : "");
}

void AtomicFile::write(const std::function<void(std::ostream&)>& content) {
  try {
    content(out_->out);
  } catch (const OutputError& e) {
    // A refused byte is the reason, however the library put it; else the writer's own words.
    abandon(out_->buf.failed() ? refusal() : target_.string() + ": " + e.what());
  } catch (...) {
    if (out_->buf.failed()) abandon(refusal());
    throw;  // not the file system's doing: a fault of glint's, reported as such
  }
  if (out_->buf.failed()) abandon(refusal());  // no need to go on computing the others
}

void AtomicFile::close() {
  if (out_->fd < 0) return;
  out_->out.flush();
  const bool written = static_cast<bool>(out_->out) && !out_->buf.failed();
  const bool closed = ::close(out_->fd) == 0;
  const int close_error = errno;
  out_->fd = -1;
  if (!written) abandon(refusal());
  if (!closed) {
    abandon("cannot write " + target_.string() + ": " +
            std::error_code(close_error, std::generic_category()).message());
  }
}

void AtomicFile::commit() {
  close();
  // Again at the last moment: a FIFO or a link may have appeared while the run computed.
  if (const auto kind = nonRegularKind(target_)) {
    abandon(target_.string() + " became " + *kind +
            " while glint ran; it was left as it is and nothing was written there");
  }
  std::error_code ec;
  std::filesystem::rename(temporary_, target_, ec);
  if (ec) abandon("cannot write " + target_.string() + ": " + ec.message());
  moved();
}

void AtomicFile::moved() {
  unregisterTemporary(slot_);
  committed_ = true;
}

void AtomicFile::abandon(const std::string& message) {
  awaitInterruptExit();
  std::error_code ignored;
  std::filesystem::remove(temporary_, ignored);
  unregisterTemporary(slot_);
  committed_ = true;  // nothing left for the destructor
  throw OutputError(message);
}

void installInterruptCleanup() {
  struct sigaction action {};
  action.sa_handler = onInterrupt;
  sigemptyset(&action.sa_mask);
  for (int sig : {SIGINT, SIGTERM, SIGHUP}) {
    sigaddset(&action.sa_mask, sig);  // one handler at a time
  }
  for (int sig : {SIGINT, SIGTERM, SIGHUP}) ::sigaction(sig, &action, nullptr);
}

int removeOnInterrupt(const std::filesystem::path& path, InterruptCleanup what) {
  return registerTemporary(path.string(), what == InterruptCleanup::RemoveFile   ? kOtherFile
                                          : what == InterruptCleanup::RemoveTree ? kTree
                                                                                 : kMadeFolder);
}

void forgetOnInterrupt(int slot) { unregisterTemporary(slot); }

int removeStaleTemporaries(const std::filesystem::path& folder) {
  int removed = 0;
  std::error_code ec;
  for (std::filesystem::directory_iterator it(folder, ec), end; !ec && it != end;
       it.increment(ec)) {
    const std::string name = it->path().filename().string();
    std::smatch m;
    if (!std::regex_match(name, m, kTemporaryName)) continue;
    const std::string digits = m[1].matched ? m[1].str() : m[2].str();
    if (digits.size() > 9) continue;
    const auto pid = static_cast<pid_t>(std::stol(digits));
    if (pid <= 0 || pid == ::getpid()) continue;
    // Only a process that provably no longer exists: pids are reused, and a live one may be
    // another glint writing into the same folder.
    if (::kill(pid, 0) == 0 || errno != ESRCH) continue;
    // A folder: a staged AMR data set (export/vtk_files.h), removed whole; remove_all()
    // removes links inside it, never what they point to.
    std::error_code ignored;
    if (it->symlink_status(ignored).type() == std::filesystem::file_type::directory) {
      if (std::filesystem::remove_all(it->path(), ignored) > 0) ++removed;
      continue;
    }
    if (::unlink(it->path().c_str()) == 0) ++removed;  // a link itself, never its target
  }
  return removed;
}

// --- OutputSet

namespace {

namespace fs = std::filesystem;

std::string errnoText(int error) {
  return std::error_code(error, std::generic_category()).message();
}

// An OutputSet's moves, published for the interrupt handler for this object's life.
class PublishedUndo {
 public:
  explicit PublishedUndo(UndoList& list) {
    for (std::atomic<UndoList*>& slot : g_undo) {
      UndoList* expected = nullptr;
      if (slot.compare_exchange_strong(expected, &list)) {
        slot_ = &slot;
        return;
      }
    }
    throw std::logic_error("OutputSet: more sets committing at once than the handler can hold");
  }
  ~PublishedUndo() {
    // Within a step: the handler either has read the list already or never will.
    const UninterruptedStep step;
    slot_->store(nullptr);
  }
  PublishedUndo(const PublishedUndo&) = delete;
  PublishedUndo& operator=(const PublishedUndo&) = delete;

 private:
  std::atomic<UndoList*>* slot_ = nullptr;
};

// Refuses a file target that is not a regular file (AtomicFile's rule), at the last moment.
void requireStillReplaceable(const std::string& target) {
  if (const auto kind = nonRegularKind(target)) {
    throw OutputError(target + " became " + *kind +
                      " while glint ran; it was left as it is and nothing was written there");
  }
}

// Moves @p staged over @p e's target, keeping the earlier file or folder aside: one step, which
// the handler finds undone or wholly done and recorded in @p e.
void moveInto(UndoEntry& e, const std::string& staged) {
  const UninterruptedStep step;
  const char* target = e.target.c_str();
  if (!e.folder) requireStillReplaceable(e.target);
  e.had_old = exists(target);
  e.state.store(1);
  if (e.had_old) {
    // A hard link keeps the earlier file in place until the new one replaces it; a file system
    // without links (or one refusing this one) has it renamed aside instead.
    const bool aside = (!e.folder && ::link(target, e.backup.c_str()) == 0) ||
                       ::rename(target, e.backup.c_str()) == 0;
    if (!aside) {
      const int error = errno;
      throw OutputError("cannot replace " + e.target +
                        ": cannot keep the earlier one aside: " + errnoText(error));
    }
  }
  if (::rename(staged.c_str(), target) != 0) {
    const int error = errno;
    throw OutputError("cannot write " + e.target + ": " + errnoText(error));
  }
}

}  // namespace

struct OutputSet::Pending {
  AtomicFile* file = nullptr;  // null for a staged path
  fs::path staged;
  fs::path target;
  fs::path scratch;
  bool last = false;
};

OutputSet::OutputSet() = default;
OutputSet::~OutputSet() = default;  // the files' own destructors remove their temporaries

AtomicFile& OutputSet::open(fs::path target, bool last) {
  files_.push_back(std::make_unique<AtomicFile>(std::move(target)));
  AtomicFile& f = *files_.back();
  pending_.push_back({&f, f.temporary_, f.target_, {}, last});
  return f;
}

void OutputSet::addStaged(fs::path staged, fs::path target, fs::path scratch) {
  pending_.push_back({nullptr, std::move(staged), std::move(target), std::move(scratch), false});
}

void OutputSet::commit(const std::function<void()>& after_first) {
  if (committed_) throw std::logic_error("OutputSet::commit: already committed");
  std::vector<const Pending*> order;
  for (const Pending& p : pending_) {
    if (!p.last) order.push_back(&p);
  }
  for (const Pending& p : pending_) {
    if (p.last) order.push_back(&p);
  }
  // Every file whole before anything moves: a full disk stops the set here.
  for (const Pending* p : order) {
    if (p->file != nullptr) p->file->close();
  }
  UndoList list;
  list.entries = std::make_unique<UndoEntry[]>(order.size());
  list.count = order.size();
  for (std::size_t i = 0; i < order.size(); ++i) {
    const Pending& p = *order[i];
    UndoEntry& e = list.entries[i];
    e.target = p.target.string();
    std::error_code ec;
    e.folder =
        p.file == nullptr && fs::symlink_status(p.staged, ec).type() == fs::file_type::directory;
    if (e.folder) {
      e.backup = (p.scratch / (".previous-" + p.target.filename().string())).string();
      e.trash = (p.scratch / (".undone-" + p.target.filename().string())).string();
    } else {
      // A temporary's name: one a killed run leaves is swept as its temporaries are.
      e.backup = temporaryBeside(p.target).string();
      requireStillReplaceable(e.target);  // before anything moves
    }
  }

  const PublishedUndo published(list);
  std::size_t begun = 0;
  try {
    for (; begun < order.size(); ++begun) {
      moveInto(list.entries[begun], order[begun]->staged.string());
      if (order[begun]->file != nullptr) order[begun]->file->moved();
      if (begun == 0 && order.size() > 1 && after_first) after_first();
    }
  } catch (...) {
    // Back as it was: each begun move undone, the last begun first.
    std::string kept_aside;
    for (std::size_t i = std::min(begun + 1, order.size()); i-- > 0;) {
      UndoEntry& e = list.entries[i];
      const UninterruptedStep step;
      if (e.state.load() != 1) continue;
      int restored = 0, removed = 0;
      undoMove(e, restored, removed);
      e.state.store(0);
      if (exists(e.backup.c_str()) && !e.folder) {
        kept_aside += "; the earlier " + e.target + " could not be put back: it is " + e.backup;
      }
    }
    try {
      throw;
    } catch (const OutputError& error) {
      throw OutputError(
          error.what() +
          (begun > 0 ? "; the outputs already in place were taken back" : std::string()) +
          kept_aside);
    }
  }
  {
    // In place together: from here an interrupt only takes away what was kept aside.
    const UninterruptedStep step;
    list.complete.store(true);
    g_outputs_in_place.store(true);
  }
  committed_ = true;
  for (std::size_t i = 0; i < list.count; ++i) {
    const UndoEntry& e = list.entries[i];
    std::error_code ignored;
    if (e.folder) {
      fs::remove_all(e.backup, ignored);
    } else if (e.had_old) {
      ::unlink(e.backup.c_str());  // what cannot go is litter, swept as a dead run's temporary
    }
  }
}

}  // namespace glint
