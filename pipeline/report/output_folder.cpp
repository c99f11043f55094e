#include "pipeline/report/output_folder.h"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <ctime>
#include <map>
#include <sstream>
#include <system_error>

#include "export/atomic_file.h"
#include "pipeline/base/input_error.h"
#include "pipeline/input/input_files.h"

namespace glint {
namespace {

namespace fs = std::filesystem;

std::string errnoText(int error) {
  return std::error_code(error, std::generic_category()).message();
}

std::string hostName() {
  char buf[256] = {};
  if (::gethostname(buf, sizeof buf - 1) != 0) return "unknown";
  return buf;
}

std::string utcNow() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  char buf[64] = {};
  if (::gmtime_r(&now, &tm) == nullptr ||
      std::strftime(buf, sizeof buf, "%Y-%m-%d %H:%M:%S UTC", &tm) == 0) {
    return "unknown time";
  }
  return buf;
}

// What the holder wrote (key=value lines), read from @p fd. A holder that has not yet written
// leaves it empty; a file someone else wrote says whatever it says, quoted printably.
std::map<std::string, std::string> holderOf(int fd) {
  char buf[1024];
  const ssize_t n = ::pread(fd, buf, sizeof buf, 0);
  std::map<std::string, std::string> fields;
  if (n <= 0) return fields;
  std::istringstream in(std::string(buf, static_cast<std::size_t>(n)));
  for (std::string line; std::getline(in, line);) {
    const auto eq = line.find('=');
    if (eq == std::string::npos) continue;
    fields.emplace(line.substr(0, eq), printable(line.substr(eq + 1)));
  }
  return fields;
}

std::string inUseMessage(const fs::path& folder, const std::map<std::string, std::string>& h) {
  auto field = [&](const char* key) {
    const auto it = h.find(key);
    return it == h.end() ? std::string() : it->second;
  };
  std::string who = "another glint process";
  if (!field("pid").empty()) {
    who = "glint process " + field("pid");
    if (!field("host").empty()) who += " on host " + field("host");
    std::string detail = field("command");
    if (!field("since").empty())
      detail += (detail.empty() ? "since " : ", since ") + field("since");
    if (!detail.empty()) who += " (" + detail + ")";
  }
  return folder.string() + " is in use by " + who +
         "; wait for it to finish, or choose another output folder";
}

}  // namespace

FolderLock::FolderLock(const fs::path& folder, std::string_view command)
    : folder_(folder), file_(folder / kFileName) {
  // A releasing holder removes the file: the one opened here may be gone from the folder by the
  // time it is locked, and a lock on it would then exclude nobody. Such a race is rare; a
  // handful of attempts is plenty.
  for (int attempt = 0; attempt < 16 && fd_ < 0; ++attempt) {
    const int fd =
        ::open(file_.c_str(), O_RDWR | O_CREAT | O_NOFOLLOW | O_CLOEXEC | O_NONBLOCK, 0644);
    if (fd < 0) {
      throw OutputError(folder_.string() + ": cannot open the lock file " + file_.string() + ": " +
                        errnoText(errno) +
                        (errno == ELOOP ? " (it is a symbolic link; remove it)" : ""));
    }
    struct stat held {};
    if (::fstat(fd, &held) != 0 || !S_ISREG(held.st_mode)) {
      ::close(fd);
      throw OutputError(file_.string() + ": the lock file is not a regular file; remove it");
    }
    if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
      const int error = errno;
      if (error == EWOULDBLOCK) {
        const auto holder = holderOf(fd);
        ::close(fd);
        throw OutputError(inUseMessage(folder_, holder));
      }
      ::close(fd);
      throw OutputError(folder_.string() + ": cannot lock " + file_.string() + ": " +
                        errnoText(error) + " (does the file system support locks?)");
    }
    struct stat named {};
    if (::stat(file_.c_str(), &named) == 0 && named.st_dev == held.st_dev &&
        named.st_ino == held.st_ino) {
      fd_ = fd;
    } else {
      ::close(fd);
    }
  }
  if (fd_ < 0) throw OutputError(folder_.string() + ": cannot take the lock " + file_.string());
  interrupt_slot_ = removeOnInterrupt(file_, InterruptCleanup::RemoveFile);
  std::ostringstream who;
  who << "pid=" << ::getpid() << "\nhost=" << hostName() << "\nsince=" << utcNow()
      << "\ncommand=" << command << "\n";
  const std::string text = who.str();
  // The holder's name only helps the message of a refused process: a failure to write it is no
  // reason to stop (the lock itself is held).
  if (::ftruncate(fd_, 0) == 0) {
    const ssize_t ignored = ::pwrite(fd_, text.data(), text.size(), 0);
    (void)ignored;
  }
}

FolderLock::~FolderLock() {
  // Removed while still locked: whoever opens the name next makes a new file, and whoever opened
  // this one meanwhile sees it gone once it gets the lock.
  forgetOnInterrupt(interrupt_slot_);
  ::unlink(file_.c_str());
  ::close(fd_);
}

void requireFolderNotHeld(const fs::path& folder) {
  const fs::path file = folder / FolderLock::kFileName;
  const int fd = ::open(file.c_str(), O_RDONLY | O_NOFOLLOW | O_CLOEXEC | O_NONBLOCK);
  if (fd < 0) return;  // no lock file (or none this process may read): nobody holds the folder
  // A shared lock is refused exactly while a holder has its exclusive one; taken, it is let go
  // at once, so that this check excludes nobody.
  const bool held = ::flock(fd, LOCK_SH | LOCK_NB) != 0 && errno == EWOULDBLOCK;
  const auto holder = held ? holderOf(fd) : std::map<std::string, std::string>{};
  ::close(fd);
  if (held) throw OutputError(inUseMessage(folder, holder));
}

void CreatedFolders::create(const fs::path& folder) {
  fs::path target = folder.lexically_normal();
  if (!target.has_filename()) target = target.parent_path();  // "D/" → "D"
  std::vector<fs::path> missing;
  std::error_code ec;
  for (fs::path p = target; !p.empty() && !fs::exists(fs::symlink_status(p, ec));
       p = p.parent_path()) {
    missing.push_back(p);
    if (p == p.parent_path()) break;
  }
  for (auto it = missing.rbegin(); it != missing.rend(); ++it) {
    if (::mkdir(it->c_str(), 0777) == 0) {
      made_.push_back(*it);
      interrupt_slots_.push_back(removeOnInterrupt(*it, InterruptCleanup::RemoveEmptyFolder));
      continue;
    }
    const int error = errno;
    // Made meanwhile by someone else: theirs, not to be removed by this run.
    if (error == EEXIST && fs::is_directory(*it, ec)) continue;
    throw OutputError(it->string() + ": cannot create the folder: " + errnoText(error));
  }
  if (!fs::is_directory(target, ec)) {
    throw OutputError(target.string() +
                      ": cannot create the folder: something else of that name is there");
  }
}

bool CreatedFolders::made(const fs::path& folder) const {
  fs::path target = folder.lexically_normal();
  if (!target.has_filename()) target = target.parent_path();
  return std::find(made_.begin(), made_.end(), target) != made_.end();
}

CreatedFolders::~CreatedFolders() {
  for (int slot : interrupt_slots_) forgetOnInterrupt(slot);
}

void CreatedFolders::removeEmpty() noexcept {
  for (int slot : interrupt_slots_) forgetOnInterrupt(slot);
  interrupt_slots_.clear();
  for (auto it = made_.rbegin(); it != made_.rend(); ++it) ::rmdir(it->c_str());
  made_.clear();
}

OutputFolder::OutputFolder(const fs::path& folder, const InputFiles& inputs,
                           std::string_view command,
                           std::function<void(const OutputFolder&)> before_release)
    : folder_(folder), before_release_(std::move(before_release)), on_failure_([this] {
        if (before_release_) before_release_(*this);
        lock_.reset();  // the lock file goes before the folder holding it can
        created_.removeEmpty();
      }) {
  inputs.requireNotHeldBy(folder_);
  created_.create(folder_);
  lock_.emplace(folder_, command);
}

}  // namespace glint
