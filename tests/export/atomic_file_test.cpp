// Output files in a folder others may write to: the temporary cannot be predicted or
// redirected, a target that is not a regular file (a link, a device, a FIFO) is refused
// rather than replaced or followed, and temporaries of processes that died are swept. A set of
// outputs appears together or not at all, however its commit is cut short.
#include "export/atomic_file.h"

#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "support/files.h"

namespace glint {
namespace {

namespace fs = std::filesystem;

fs::path freshFolder(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("glint_atomic_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::string contents(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// A pid that existed and is gone: a child that has exited and been reaped.
pid_t deadPid() {
  const pid_t child = ::fork();
  if (child == 0) ::_exit(0);
  int status = 0;
  ::waitpid(child, &status, 0);
  return child;
}

TEST(AtomicFile, TemporaryIsANewFileUnderAnUnpredictableName) {
  const fs::path dir = freshFolder("names");
  AtomicFile a(dir / "summary.json");
  AtomicFile b(dir / "summary.json");
  EXPECT_NE(a.temporaryPath(), b.temporaryPath()) << "two writers never share a temporary";
  const std::string prefix = ".summary.json.glint-" + std::to_string(::getpid()) + "-";
  for (const AtomicFile* f : {&a, &b}) {
    const std::string name = f->temporaryPath().filename().string();
    EXPECT_EQ(name.rfind(prefix, 0), 0u) << name;
    EXPECT_EQ(name.size(), prefix.size() + 8) << name << ": 8 random characters";
    struct stat st {};
    ASSERT_EQ(::lstat(f->temporaryPath().c_str(), &st), 0);
    EXPECT_TRUE(S_ISREG(st.st_mode)) << "created, not opened through anything planted";
  }
}

TEST(AtomicFile, ALinkAtTheTargetIsRefusedNeitherFollowedNorReplaced) {
  // Someone who can write to a shared output folder plants summary.json → a file of the user's
  // elsewhere; or the user's own link stands there. glint writes through neither and leaves
  // the link as it is.
  const fs::path dir = freshFolder("link");
  const fs::path outside = freshFolder("link_outside") / "precious.txt";
  std::ofstream(outside) << "keep me";
  fs::create_symlink(outside, dir / "summary.json");
  try {
    AtomicFile f(dir / "summary.json");
    ADD_FAILURE() << "a link at the target was accepted";
  } catch (const OutputError& e) {
    EXPECT_NE(std::string(e.what()).find("summary.json is a symbolic link, not a regular file"),
              std::string::npos)
        << e.what();
  }
  EXPECT_TRUE(fs::is_symlink(dir / "summary.json")) << "the link itself stays";
  EXPECT_EQ(contents(outside), "keep me") << "the file the link points to is untouched";
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 1)
      << "no temporary was left beside the link";
  fs::remove_all(dir);
  fs::remove_all(outside.parent_path());
}

// The kinds of file rename() would replace by a regular one: each made in the test's own
// folder (the character device is /dev/null's numbers, 1:3, so nothing reads or writes a real
// device if the refusal failed; root may mknod).
TEST(AtomicFile, ADeviceFifoOrFolderAtTheTargetIsRefusedAndStays) {
  const fs::path dir = freshFolder("special");
  ASSERT_EQ(::mknod((dir / "null").c_str(), S_IFCHR | 0666, ::makedev(1, 3)), 0)
      << "mknod needs root, which the tests run as";
  ASSERT_EQ(::mkfifo((dir / "fifo").c_str(), 0666), 0);
  fs::create_directory(dir / "folder");
  const std::pair<const char*, const char*> cases[] = {
      {"null", "a character device"}, {"fifo", "a FIFO"}, {"folder", "a folder"}};
  for (const auto& [name, kind] : cases) {
    try {
      AtomicFile f(dir / name);
      ADD_FAILURE() << name << " was accepted as an output";
    } catch (const OutputError& e) {
      EXPECT_NE(std::string(e.what()).find(std::string(name) + " is " + kind), std::string::npos)
          << e.what();
    }
  }
  struct stat st {};
  ASSERT_EQ(::lstat((dir / "null").c_str(), &st), 0);
  EXPECT_TRUE(S_ISCHR(st.st_mode)) << "the device node is still a device";
  EXPECT_TRUE(fs::is_fifo(dir / "fifo"));
  EXPECT_TRUE(fs::is_directory(dir / "folder"));
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 3)
      << "no temporary was left";
  fs::remove_all(dir);
}

TEST(AtomicFile, ATargetThatBecomesAFifoDuringTheRunIsLeftAndNothingWritten) {
  const fs::path dir = freshFolder("late_fifo");
  AtomicFile f(dir / "out.csv");
  f.stream() << "x,y,z\n";
  ASSERT_EQ(::mkfifo((dir / "out.csv").c_str(), 0666), 0);
  EXPECT_THROW(f.commit(), OutputError) << "the rename would have replaced the FIFO";
  EXPECT_TRUE(fs::is_fifo(dir / "out.csv"));
  EXPECT_FALSE(fs::exists(f.temporaryPath())) << "the temporary was removed";
  fs::remove_all(dir);
}

TEST(AtomicFile, UncommittedTemporaryIsRemoved) {
  const fs::path dir = freshFolder("uncommitted");
  fs::path temporary;
  {
    AtomicFile f(dir / "out.csv");
    f.stream() << "partial";
    temporary = f.temporaryPath();
    EXPECT_TRUE(fs::exists(temporary));
  }
  EXPECT_FALSE(fs::exists(temporary));
  EXPECT_TRUE(fs::is_empty(dir)) << "nothing left, not even an empty target";
}

TEST(AtomicFile, SeeksBackLikeAFileForOpenExr) {
  // OpenEXR writes its line offset table last and seeks back to it.
  const fs::path dir = freshFolder("seek");
  AtomicFile f(dir / "map.exr");
  std::ostream& out = f.stream();
  out << "0123456789";
  EXPECT_EQ(out.tellp(), std::streampos(10));
  out.seekp(2);
  out << "ab";
  out.seekp(0, std::ios::end);
  out << "Z";
  f.commit();
  EXPECT_EQ(contents(dir / "map.exr"), "01ab456789Z");
}

TEST(AtomicFile, StaleTemporariesOfDeadProcessesAreSweptNeverFollowed) {
  const fs::path dir = freshFolder("stale");
  const fs::path outside = freshFolder("stale_outside") / "precious.txt";
  std::ofstream(outside) << "keep me";
  const std::string dead = std::to_string(deadPid());
  const std::string alive = std::to_string(::getppid());
  std::ofstream(dir / (".summary.json.glint-" + dead + "-AbCdEf12")) << "stale";
  std::ofstream(dir / ("irradiance.vdb.tmp." + dead)) << "stale, glint 0.1's name";
  fs::create_symlink(outside, dir / (".blocks.vtu.glint-" + dead + "-ZyXwVu98"));
  std::ofstream(dir / (".target.vtp.glint-" + alive + "-AbCdEf12")) << "another glint at work";
  std::ofstream(dir / "notes.txt") << "the user's";
  EXPECT_EQ(removeStaleTemporaries(dir), 3);
  EXPECT_TRUE(fs::exists(dir / (".target.vtp.glint-" + alive + "-AbCdEf12")))
      << "a live process's temporary stays";
  EXPECT_TRUE(fs::exists(dir / "notes.txt"));
  EXPECT_EQ(contents(outside), "keep me") << "a link is unlinked, its target untouched";
  EXPECT_FALSE(fs::exists(dir / ("irradiance.vdb.tmp." + dead)));
}

// Temporaries left in @p dir: `.<name>.glint-<pid>-<random>`.
std::vector<std::string> temporariesIn(const fs::path& dir) {
  std::vector<std::string> found;
  for (const auto& entry : fs::directory_iterator(dir)) {
    const std::string name = entry.path().filename().string();
    if (name.find(".glint-") != std::string::npos) found.push_back(name);
  }
  return found;
}

// The interrupt handler runs on whichever thread the signal reaches, possibly while another
// thread is between creating a temporary and registering it. Writers on three threads create
// and commit files without pause; each trial signals them after a different delay, so the
// signal lands at every point of a creation over the trials (a file is some 20 µs of work).
// The handler's message says how many temporaries it removed: a trial where it removed any is
// one whose signal landed while a file was being created. A third of the trials must be such,
// or the test would pass without having tested that (measured on 2 cores: 89-96 of 150 idle,
// 65-79 beside three busy loops; 33-36 when a planted 2 ms delay kept the writers mostly
// outside a creation).
TEST(AtomicFile, ASignalOnAnyThreadDuringCreationLeavesNoTemporary) {
  const fs::path dir = freshFolder("signal");
  constexpr int kTrials = 150;
  int interrupted = 0, mid_creation = 0;
  for (int trial = 0; trial < kTrials; ++trial) {
    for (int id = 0; id < 3; ++id) fs::remove(dir / ("out" + std::to_string(id) + ".txt"));
    int ready[2], err[2];
    ASSERT_EQ(::pipe(ready), 0);
    ASSERT_EQ(::pipe(err), 0);
    const pid_t child = ::fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
      if (::dup2(err[1], STDERR_FILENO) < 0) ::_exit(5);
      installInterruptCleanup();
      const char byte = 1;
      if (::write(ready[1], &byte, 1) != 1) ::_exit(4);
      auto writer = [&dir](int id) {
        try {
          for (long k = 0;; ++k) {
            AtomicFile f(dir / ("out" + std::to_string(id) + ".txt"));
            f.stream() << k;
            f.commit();
          }
        } catch (const std::exception& e) {
          std::fprintf(stderr, "writer %d: %s\n", id, e.what());
          ::_exit(3);
        }
      };
      std::thread a(writer, 1);
      std::thread b(writer, 2);
      writer(0);
    }
    ::close(err[1]);
    char byte = 0;
    ASSERT_EQ(::read(ready[0], &byte, 1), 1) << "the child has its handler in place";
    ::close(ready[0]);
    ::close(ready[1]);
    // Every writer at work (each has committed a file), however loaded the machine: a signal
    // before that could land nowhere near a creation. Then a delay spread over the trials.
    int status = 0;
    bool ended = false;  // a writer that failed ends the child: no waiting for it then
    for (int id = 0; id < 3 && !ended; ++id) {
      while (!ended && !fs::exists(dir / ("out" + std::to_string(id) + ".txt"))) {
        ended = ::waitpid(child, &status, WNOHANG) == child;
        std::this_thread::yield();
      }
    }
    if (!ended) {
      ::usleep(static_cast<useconds_t>(37 * trial));
      ::kill(child, SIGTERM);
      ::waitpid(child, &status, 0);
    }
    std::string message;
    char chunk[256];
    for (ssize_t n; (n = ::read(err[0], chunk, sizeof chunk)) > 0;)
      message.append(chunk, static_cast<std::size_t>(n));
    ::close(err[0]);
    ASSERT_TRUE(WIFEXITED(status)) << "trial " << trial << ": the handler exits, status " << status;
    ASSERT_EQ(WEXITSTATUS(status), 128 + SIGTERM) << "trial " << trial << ": " << message;
    ++interrupted;
    const std::string said = "interrupted by SIGTERM; removed ";
    const std::size_t at = message.find(said);
    ASSERT_NE(at, std::string::npos)
        << "trial " << trial << ": the handler's message, not '" << message << "'";
    const int removed = std::stoi(message.substr(at + said.size()));
    EXPECT_LE(removed, 3) << "trial " << trial << ": one temporary per writer at most";
    if (removed > 0) ++mid_creation;
    const std::vector<std::string> left = temporariesIn(dir);
    ASSERT_TRUE(left.empty()) << "trial " << trial << " left " << left.size()
                              << " temporaries, the first " << left.front();
  }
  EXPECT_EQ(interrupted, kTrials);
  EXPECT_GE(mid_creation, kTrials / 3)
      << "only " << mid_creation << " of " << kTrials
      << " signals landed while a file was being created: the test did not test that";
}

// An earlier run's outputs: a folder of blocks, its index, a map and a summary.
void plantEarlierRun(const fs::path& dir) {
  fs::create_directories(dir / "blocks");
  std::ofstream(dir / "blocks" / "old_0.vti") << "earlier block";
  std::ofstream(dir / "index.vthb") << "earlier index";
  std::ofstream(dir / "map.exr") << "earlier map";
  std::ofstream(dir / "summary.json") << "earlier summary";
}

// A folder of blocks and its index written whole into @p scratch, as VTK writes an AMR data set
// (export/vtk_files.h), for @p set to move beside its files.
void stageBlocks(OutputSet& set, const fs::path& dir, const fs::path& scratch) {
  fs::create_directories(scratch / "blocks");
  std::ofstream(scratch / "blocks" / "new_0.vti") << "new block";
  std::ofstream(scratch / "index.vthb") << "new index";
  set.addStaged(scratch / "blocks", dir / "blocks", scratch);
  set.addStaged(scratch / "index.vthb", dir / "index.vthb", scratch);
}

TEST(OutputSet, EveryOutputAppearsTogetherSummaryLastAndNothingIsLeftAside) {
  const fs::path dir = freshFolder("set_commit");
  plantEarlierRun(dir);
  const fs::path scratch = dir / (".index.vthb.glint-" + std::to_string(::getpid()) + "-Abcdefgh");
  {
    OutputSet set;
    set.open(dir / "summary.json", true).stream() << "new summary";
    set.open(dir / "map.exr").stream() << "new map";
    set.open(dir / "new.csv").stream() << "new table";
    stageBlocks(set, dir, scratch);
    bool paused = false;
    set.commit([&] {
      paused = true;
      EXPECT_EQ(contents(dir / "map.exr"), "new map") << "the first output is in place";
      EXPECT_EQ(contents(dir / "summary.json"), "earlier summary") << "summary.json comes last";
    });
    EXPECT_TRUE(paused) << "after_first is called between the first move and the next";
  }
  fs::remove_all(scratch);  // the caller's (StagedAmr's), emptied of the earlier blocks
  const std::map<std::string, std::string> expected = {
      {"blocks", "/"},        {"blocks/new_0.vti", "new block"}, {"index.vthb", "new index"},
      {"map.exr", "new map"}, {"new.csv", "new table"},          {"summary.json", "new summary"}};
  EXPECT_EQ(test::folderContents(dir), expected)
      << "every output replaced, no earlier file kept aside";
  fs::remove_all(dir);
}

TEST(OutputSet, AMoveThatFailsHalfWayPutsBackEveryEarlierFile) {
  const fs::path dir = freshFolder("set_half_way");
  plantEarlierRun(dir);
  const std::map<std::string, std::string> before = test::folderContents(dir);
  const fs::path scratch = dir / (".index.vthb.glint-" + std::to_string(::getpid()) + "-Abcdefgh");
  {
    OutputSet set;
    set.open(dir / "summary.json", true).stream() << "new summary";
    stageBlocks(set, dir, scratch);
    set.open(dir / "new.csv").stream() << "new table";
    AtomicFile& map = set.open(dir / "map.exr");
    map.stream() << "new map";
    try {
      // The blocks go first; then the index, the table; the map's temporary is gone by then,
      // so its rename fails with three outputs in place, two of them over earlier ones.
      set.commit([&] { fs::remove(map.temporaryPath()); });
      ADD_FAILURE() << "a move failed and the commit said nothing";
    } catch (const OutputError& e) {
      const std::string said = e.what();
      EXPECT_NE(said.find("cannot write " + (dir / "map.exr").string()), std::string::npos) << said;
      EXPECT_NE(said.find("the outputs already in place were taken back"), std::string::npos)
          << said;
    }
  }
  fs::remove_all(scratch);
  EXPECT_EQ(test::folderContents(dir), before)
      << "the folder is as it was: the earlier files back, the "
         "new ones gone, nothing aside";
  fs::remove_all(dir);
}

// SIGTERM lands after the first output (a folder replacing an earlier one) is in place: the
// handler puts the earlier folder back and takes away the rest.
TEST(OutputSet, AnInterruptBetweenTwoMovesLeavesTheFolderAsItWas) {
  const fs::path dir = freshFolder("set_interrupt");
  plantEarlierRun(dir);
  const std::map<std::string, std::string> before = test::folderContents(dir);
  int ready[2], err[2];
  ASSERT_EQ(::pipe(ready), 0);
  ASSERT_EQ(::pipe(err), 0);
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    if (::dup2(err[1], STDERR_FILENO) < 0) ::_exit(5);
    installInterruptCleanup();
    try {
      const fs::path scratch =
          dir / (".index.vthb.glint-" + std::to_string(::getpid()) + "-Abcdefgh");
      fs::create_directories(scratch);
      removeOnInterrupt(scratch, InterruptCleanup::RemoveTree);  // as StagedAmr does
      OutputSet set;
      stageBlocks(set, dir, scratch);
      set.open(dir / "map.exr").stream() << "new map";
      set.open(dir / "summary.json", true).stream() << "new summary";
      set.commit([&] {
        const char byte = 1;
        if (::write(ready[1], &byte, 1) != 1) ::_exit(4);
        for (;;) ::pause();
      });
    } catch (const std::exception& e) {
      std::fprintf(stderr, "%s\n", e.what());
    }
    ::_exit(3);
  }
  ::close(err[1]);
  ::close(ready[1]);
  char byte = 0;
  ASSERT_EQ(::read(ready[0], &byte, 1), 1) << "the child paused after its first move";
  ::close(ready[0]);
  EXPECT_EQ(contents(dir / "blocks" / "new_0.vti"), "new block") << "the first move was made";
  ::kill(child, SIGTERM);
  int status = 0;
  ::waitpid(child, &status, 0);
  std::string message;
  char chunk[256];
  for (ssize_t n; (n = ::read(err[0], chunk, sizeof chunk)) > 0;)
    message.append(chunk, static_cast<std::size_t>(n));
  ::close(err[0]);
  ASSERT_TRUE(WIFEXITED(status)) << status;
  EXPECT_EQ(WEXITSTATUS(status), 128 + SIGTERM) << message;
  // The two temporaries, the staging folder (with the new index in it) and the earlier
  // blocks back.
  EXPECT_NE(message.find("interrupted by SIGTERM; removed 3 unfinished output file(s) and put "
                         "back 1 earlier one(s)"),
            std::string::npos)
      << message;
  EXPECT_EQ(test::folderContents(dir), before) << "the folder is as it was";
  fs::remove_all(dir);
}

// A file system that refuses a byte (here EFBIG: a file-size limit, which needs no mount) in
// the middle of a library's writer: one OutputError naming the file and the reason, whatever the
// library made of it, and no temporary left.
TEST(AtomicFile, AWriteTheFileSystemRefusesIsAnOutputErrorNamingTheFileAndTheReason) {
  const fs::path dir = freshFolder("refused");
  int err[2];
  ASSERT_EQ(::pipe(err), 0);
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    ::close(err[0]);
    std::string said = "no exception";
    ::signal(SIGXFSZ, SIG_IGN);  // the write fails with EFBIG instead of ending the process
    const rlimit limit{200000, 200000};
    if (::setrlimit(RLIMIT_FSIZE, &limit) != 0) ::_exit(4);
    try {
      AtomicFile f(dir / "map.exr");
      f.write([](std::ostream& out) {
        const std::string block(1 << 16, 'x');
        for (int i = 0; i < 8; ++i)
          out.write(block.data(), static_cast<std::streamsize>(block.size()));
        if (!out) throw std::runtime_error("the library's own words for a bad stream");
      });
    } catch (const OutputError& e) {
      said = std::string("OutputError: ") + e.what();
    } catch (const std::exception& e) {
      said = std::string("another exception: ") + e.what();
    }
    if (::write(err[1], said.data(), said.size()) < 0) ::_exit(5);
    ::_exit(0);
  }
  ::close(err[1]);
  std::string said;
  char chunk[256];
  for (ssize_t n; (n = ::read(err[0], chunk, sizeof chunk)) > 0;)
    said.append(chunk, static_cast<std::size_t>(n));
  ::close(err[0]);
  int status = 0;
  ::waitpid(child, &status, 0);
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << status;
  EXPECT_EQ(said, "OutputError: cannot write " + (dir / "map.exr").string() + ": File too large");
  EXPECT_TRUE(fs::is_empty(dir)) << "the temporary is removed";
  fs::remove_all(dir);
}

}  // namespace
}  // namespace glint
