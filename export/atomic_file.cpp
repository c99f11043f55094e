#include "export/atomic_file.h"

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
// unlinked), 4 a folder the run made (removed if it is empty once the files are gone).
constexpr int kSlots = 1024;
constexpr int kTemporary = 2;
constexpr int kOtherFile = 3;
constexpr int kMadeFolder = 4;
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

// A signal may reach any thread, also while another creates a temporary. The handler raises
// g_interrupted and then waits for every creation in flight, and a creation starts only when
// the flag is down: so each file either is created and registered before the handler reads the
// registry, or never created. Sequentially consistent, as the argument needs.
std::atomic<bool> g_interrupted{false};
std::atomic<int> g_creating{0};

// The handler is removing the temporaries and will exit: an error caused by its work (a
// temporary gone before its rename) must not race its exit status and message with one of our
// own. Returns if there is no interrupt.
void awaitInterruptExit() {
  if (!g_interrupted.load()) return;
  for (;;) ::pause();
}

// open(2) with O_CREAT | O_EXCL of a temporary, registered for the handler. Returns the file
// descriptor, or -1 with errno set (the slot is then -1).
int createRegistered(const std::filesystem::path& path, int& slot) {
  // The handler must not run on this thread inside the window, where it would wait for itself.
  sigset_t interrupts;
  sigset_t previous;
  sigemptyset(&interrupts);
  for (int sig : {SIGINT, SIGTERM, SIGHUP}) sigaddset(&interrupts, sig);
  ::pthread_sigmask(SIG_BLOCK, &interrupts, &previous);
  g_creating.fetch_add(1);
  if (g_interrupted.load()) {
    g_creating.fetch_sub(1);
    awaitInterruptExit();  // create nothing now
  }
  slot = registerTemporary(path.string());
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0666);
  const int error = errno;
  if (fd < 0) {
    unregisterTemporary(slot);
    slot = -1;
  }
  g_creating.fetch_sub(1);
  ::pthread_sigmask(SIG_SETMASK, &previous, nullptr);
  errno = error;
  return fd;
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
  int folders = 0;
  for (Slot& s : g_slots) {
    const int state = s.state.load(std::memory_order_acquire);
    if (state == kTemporary && ::unlink(s.path) == 0) ++removed;
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
  say("; removed ");
  sayNumber(removed);
  say(" unfinished output file(s); files already complete are kept\n");
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
    std::array<char, 1 << 16> buffer_{};
  };

  explicit Stream(int f) : fd(f), buf(f), out(&buf) {}
  int fd;
  Buf buf;
  std::ostream out;
};

AtomicFile::AtomicFile(std::filesystem::path target) : target_(std::move(target)) {
  requireReplaceable(target_);
  // Same folder as the target, so the final rename never crosses file systems.
  std::filesystem::path folder = target_.parent_path();
  if (folder.empty()) folder = ".";
  sweepOnce(folder);
  std::string stem(1, '.');
  stem.append(target_.filename().string()).append(".glint-");
  stem.append(std::to_string(::getpid())).append(1, '-');
  int fd = -1;
  for (int attempt = 0; attempt < 100 && fd < 0; ++attempt) {
    temporary_ = folder / (stem + randomSuffix());
    fd = createRegistered(temporary_, slot_);
    if (fd < 0 && errno != EEXIST) break;
  }
  if (fd < 0) {
    awaitInterruptExit();
    throw OutputError("cannot create " + target_.string() + " (is the folder there and writable?)");
  }
  out_ = std::make_unique<Stream>(fd);
}

AtomicFile::~AtomicFile() {
  if (committed_) return;
  if (out_) ::close(out_->fd);
  std::error_code ignored;
  std::filesystem::remove(temporary_, ignored);
  unregisterTemporary(slot_);
}

std::ostream& AtomicFile::stream() { return out_->out; }

void AtomicFile::commit() {
  out_->out.flush();
  const bool written = static_cast<bool>(out_->out) && !out_->buf.failed();
  const bool closed = ::close(out_->fd) == 0;
  out_->fd = -1;
  if (!written || !closed) abandon("cannot write " + target_.string());
  // Again at the last moment: a FIFO or a link may have appeared while the run computed.
  if (const auto kind = nonRegularKind(target_)) {
    abandon(target_.string() + " became " + *kind +
            " while glint ran; it was left as it is and nothing was written there");
  }
  std::error_code ec;
  std::filesystem::rename(temporary_, target_, ec);
  if (ec) abandon("cannot write " + target_.string() + ": " + ec.message());
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
  return registerTemporary(path.string(),
                           what == InterruptCleanup::RemoveFile ? kOtherFile : kMadeFolder);
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

}  // namespace glint
