// What an output may replace: never a device, a FIFO or a link (the system's /dev/full was
// once left a regular file), never one of the command's own inputs, whatever name it is given,
// and no output folder that holds an input. A command whose disk fills leaves its folder as it
// was, with one message naming the file.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "pipeline/report/output_folder.h"
#include "support/cli.h"
#include "support/files.h"
#include "support/small_disk.h"

namespace glint {
namespace {

namespace fs = std::filesystem;
using test::glint;
using test::Outcome;

using test::readFile;

using test::folderContents;
using test::SmallDisk;
using test::tmpfsPages;
using test::tmpfsPagesUnder;

std::size_t entries(const fs::path& dir) {
  return static_cast<std::size_t>(
      std::distance(fs::directory_iterator(dir), fs::directory_iterator()));
}

// A fresh folder per test holding a copy of the cylinder example and one observer.
class Outputs : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = test::freshTestFolder("glint_outputs_");
    scene_ = dir_ / "scene.json";
    fs::copy_file(fs::path(GLINT_EXAMPLES_DIR) / "cylinder.json", scene_);
    points_ = dir_ / "p.csv";
    std::ofstream(points_) << "x,y,z\n-3,0,0.1\n";
  }
  void TearDown() override { fs::remove_all(dir_); }

  Outcome points(const fs::path& out) const {
    return glint({"points", scene_.string(), "--points", points_.string(), "--out", out.string(),
                  "--quiet"});
  }

  fs::path dir_, scene_, points_;
};

TEST_F(Outputs, ADeviceFifoOrLinkNamedAsTheOutputIsRefusedAndLeftAsItWas) {
  // The character device has /dev/null's numbers (1:3), made here, never the system's node.
  const fs::path device = dir_ / "null";
  ASSERT_EQ(::mknod(device.c_str(), S_IFCHR | 0666, ::makedev(1, 3)), 0) << "tests run as root";
  const fs::path fifo = dir_ / "fifo";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0666), 0);
  const fs::path link = dir_ / "link.csv";
  fs::create_symlink(dir_ / "elsewhere.csv", link);
  const std::size_t before = entries(dir_);
  const std::pair<fs::path, const char*> cases[] = {
      {device, "a character device"}, {fifo, "a FIFO"}, {link, "a symbolic link"}};
  for (const auto& [out, kind] : cases) {
    const Outcome r = points(out);
    EXPECT_EQ(r.status, 2) << out << ": " << r.err;
    EXPECT_NE(r.err.find(out.string() + " is " + kind + ", not a regular file"), std::string::npos)
        << r.err;
    EXPECT_NE(r.err.find("--out -"), std::string::npos) << "says how to reach standard output";
  }
  struct stat st {};
  ASSERT_EQ(::lstat(device.c_str(), &st), 0);
  EXPECT_TRUE(S_ISCHR(st.st_mode)) << "the device node is still a device";
  EXPECT_EQ(::major(st.st_rdev), 1u);
  EXPECT_EQ(::minor(st.st_rdev), 3u);
  EXPECT_TRUE(fs::is_fifo(fifo));
  EXPECT_TRUE(fs::is_symlink(link));
  EXPECT_FALSE(fs::exists(dir_ / "elsewhere.csv")) << "nothing written through the link";
  EXPECT_EQ(entries(dir_), before) << "no temporary or other file was left";
}

TEST_F(Outputs, AnOutputThatIsAnInputIsRefusedWhateverItsName) {
  const std::string scene_text = readFile(scene_);
  const std::string points_text = readFile(points_);
  fs::create_hard_link(points_, dir_ / "hard_link.csv");
  const std::pair<fs::path, const char*> cases[] = {{points_, "is the points file"},
                                                    {dir_ / "." / "p.csv", "is the points file"},
                                                    {dir_ / "hard_link.csv", "is the points file"},
                                                    {scene_, "is the scene file"}};
  for (const auto& [out, says] : cases) {
    const Outcome r = points(out);
    EXPECT_EQ(r.status, 2) << out << ": " << r.err;
    EXPECT_NE(r.err.find(out.string() + " " + says), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("never writes over its own input"), std::string::npos) << r.err;
  }
  EXPECT_EQ(readFile(scene_), scene_text) << "the scene is intact";
  EXPECT_EQ(readFile(points_), points_text) << "the points file is intact";
  EXPECT_EQ(readFile(dir_ / "hard_link.csv"), points_text);

  // A mesh the scene names is an input too.
  const fs::path targets = fs::path(GLINT_EXAMPLES_DIR) / "targets";
  fs::copy_file(targets / "capsule.glb", dir_ / "capsule.glb");
  std::string mesh_scene = readFile(fs::path(GLINT_EXAMPLES_DIR) / "finned_missile.json");
  const std::string from = "\"file\": \"targets/finned_missile.glb\"";
  ASSERT_NE(mesh_scene.find(from), std::string::npos) << "the example names its mesh";
  mesh_scene.replace(mesh_scene.find(from), from.size(), "\"file\": \"capsule.glb\"");
  std::ofstream(scene_) << mesh_scene;
  const std::string mesh_bytes = readFile(dir_ / "capsule.glb");
  const Outcome r = points(dir_ / "capsule.glb");
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_NE(r.err.find("capsule.glb is the mesh file"), std::string::npos) << r.err;
  EXPECT_EQ(readFile(dir_ / "capsule.glb"), mesh_bytes) << "the mesh is intact";
}

TEST_F(Outputs, AnOutputFolderThatHoldsAnInputIsRefusedAtAnyDepth) {
  const std::size_t before = entries(dir_);
  for (const fs::path& out : {dir_, dir_.parent_path()}) {
    const Outcome r = glint({"run", scene_.string(), "-o", out.string(), "--quiet"});
    EXPECT_EQ(r.status, 2) << out << ": " << r.err;
    EXPECT_NE(r.err.find(out.string() + " holds the scene file " + scene_.string()),
              std::string::npos)
        << r.err;
  }
  // A study and its base scene: batch writes scenario folders and --fresh removes them there.
  const fs::path data = GLINT_TEST_DATA_DIR;
  fs::create_directories(dir_ / "study");
  fs::copy_file(data / "study.json", dir_ / "study" / "study.json");
  fs::copy_file(data / "study_scene.json", dir_ / "study" / "study_scene.json");
  const Outcome batch =
      glint({"batch", (dir_ / "study" / "study.json").string(), "-o", dir_.string(), "--fresh"});
  EXPECT_EQ(batch.status, 2) << batch.err;
  EXPECT_NE(batch.err.find(dir_.string() + " holds the study file"), std::string::npos)
      << batch.err;
  EXPECT_EQ(entries(dir_), before + 1) << "nothing was written beside the inputs";
}

TEST_F(Outputs, RunRefusesAFolderOfAnotherScenesOutputsAndNamesItsOwnStaleOnes) {
  // One coarse plane, no far field: a run of well under a second.
  nlohmann::json scene =
      nlohmann::json::parse(readFile(fs::path(GLINT_EXAMPLES_DIR) / "cylinder_planes.json"));
  scene["planes"][0]["pixel_m"] = 0.5;
  scene["planes"][0]["block_m"] = 4.0;
  scene["planes"][0]["name"] = "first";
  scene["far_field"] = {{"enabled", false}};
  fs::create_directories(dir_ / "scenes");
  const fs::path tiny = dir_ / "scenes" / "tiny.json";
  std::ofstream(tiny) << scene.dump();
  const fs::path out = dir_ / "out";
  const Outcome first = glint({"run", tiny.string(), "-o", out.string()});
  ASSERT_EQ(first.status, 0) << first.err;
  const nlohmann::json summary = nlohmann::json::parse(readFile(out / "summary.json"));
  EXPECT_EQ(summary.at("files"), nlohmann::json({"summary.json", "first.exr"})) << summary.dump();
  EXPECT_EQ(summary.at("scene_path"), fs::canonical(tiny).string());

  // The same scene, its plane renamed: the old map stays, and both the terminal and the
  // summary say it is not this run's.
  scene["planes"][0]["name"] = "second";
  std::ofstream(tiny) << scene.dump();
  const Outcome again = glint({"run", tiny.string(), "-o", out.string()});
  ASSERT_EQ(again.status, 0) << again.err;
  EXPECT_NE(again.err.find("keeps first.exr from an earlier run of this scene"), std::string::npos)
      << again.err;
  EXPECT_EQ(nlohmann::json::parse(readFile(out / "summary.json")).at("earlier_files_kept"),
            nlohmann::json({"first.exr"}));

  // Another scene file, even with the same content: refused, and the folder is as it was.
  const fs::path other = dir_ / "scenes" / "other.json";
  fs::copy_file(tiny, other);
  const std::string before = readFile(out / "summary.json");
  const Outcome refused = glint({"run", other.string(), "-o", out.string(), "--quiet"});
  EXPECT_EQ(refused.status, 2) << refused.err;
  EXPECT_NE(refused.err.find(out.string() + " holds the outputs of another scene (" +
                             fs::canonical(tiny).string() + ")"),
            std::string::npos)
      << refused.err;
  EXPECT_EQ(readFile(out / "summary.json"), before);
  EXPECT_EQ(entries(out), 3u) << "summary.json, first.exr, second.exr and nothing else";
}

TEST_F(Outputs, RunHoldsItsFolderAndAFailedRunTakesAwayOnlyTheFoldersItMade) {
  // Another glint holds the folder (this process, through the same lock): refused, naming it.
  const fs::path held = dir_ / "held";
  fs::create_directories(held);
  {
    const FolderLock lock(held, "glint run");
    const Outcome r = glint({"run", scene_.string(), "-o", held.string(), "--quiet"});
    EXPECT_EQ(r.status, 2) << r.err;
    EXPECT_NE(
        r.err.find(held.string() + " is in use by glint process " + std::to_string(::getpid())),
        std::string::npos)
        << r.err;
    EXPECT_EQ(entries(held), 1u) << "nothing but the holder's lock file";
  }
  EXPECT_EQ(entries(held), 0u) << "the holder removed its lock file";

  // A run that fails (here: far beyond a 1 MB budget) after making out/deeper: both go, and
  // a folder that was there before stays.
  const fs::path made = dir_ / "new" / "deeper";
  const Outcome failed =
      glint({"run", scene_.string(), "-o", made.string(), "--memory", "1M", "--quiet"});
  EXPECT_EQ(failed.status, 2) << failed.err;
  EXPECT_FALSE(fs::exists(dir_ / "new")) << "the folders the failed run made were left";
  const Outcome failed_in_held =
      glint({"run", scene_.string(), "-o", held.string(), "--memory", "1M", "--quiet"});
  EXPECT_EQ(failed_in_held.status, 2) << failed_in_held.err;
  EXPECT_TRUE(fs::is_directory(held)) << "a folder the run did not make stays";
  EXPECT_EQ(entries(held), 0u) << "and holds no temporary or lock file";
}

// A folder a run holds is the run's to fill: a points table written into it meanwhile could
// land among files the run is about to replace (issue 64: `--out DIR/summary.json`).
TEST_F(Outputs, PointsAreNotWrittenIntoAFolderARunHolds) {
  const fs::path held = dir_ / "held";
  fs::create_directories(held);
  {
    const FolderLock lock(held, "glint run");
    const Outcome r = points(held / "summary.json");
    EXPECT_EQ(r.status, 2) << r.err;
    EXPECT_NE(r.err.find(held.string() + " is in use by glint process " +
                         std::to_string(::getpid()) + " on host"),
              std::string::npos)
        << r.err;
    EXPECT_EQ(entries(held), 1u) << "nothing but the holder's lock file";
  }
  const Outcome free = points(held / "summary.json");
  EXPECT_EQ(free.status, 0) << "once the run let the folder go: " << free.err;
  EXPECT_TRUE(fs::is_regular_file(held / "summary.json"));
}

// The full-disk tests fill a tmpfs of their own, mounted in the test's folder. They run as
// root, as every test does; where no tmpfs can be mounted they fail, never skip: a claim left
// untested is not a claim that holds.
#define REQUIRE_MOUNTED(disk)                                                    \
  ASSERT_TRUE((disk).mounted()) << "cannot mount a tmpfs here (" << (disk).why() \
                                << "): the full-disk tests need root and CAP_SYS_ADMIN"

// The message a full disk must give: one line, exit status 2, the file and the reason.
void expectFullDiskMessage(const Outcome& r, const fs::path& file) {
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_EQ(r.err, "glint: error: cannot write " + file.string() + ": No space left on device\n");
}

TEST_F(Outputs, AFullDiskLeavesNoFileOfTheRun) {
  // Two coarse planes and a coarse far field: five files, about 2 s a run.
  nlohmann::json scene =
      nlohmann::json::parse(readFile(fs::path(GLINT_EXAMPLES_DIR) / "cylinder_planes.json"));
  scene["planes"][0]["pixel_m"] = 0.5;
  scene["planes"][0]["block_m"] = 4.0;
  scene["planes"][0]["name"] = "first";
  scene["planes"][1] = scene["planes"][0];
  scene["planes"][1]["name"] = "second";
  scene["planes"][1]["origin"][2] = 0.0;
  scene["far_field"] = {{"face_pixels", 32}};
  const fs::path tiny = dir_ / "tiny.json";
  std::ofstream(tiny) << scene.dump();
  const fs::path measured = dir_ / "measured";
  const Outcome first = glint({"run", tiny.string(), "-o", measured.string(), "--quiet"});
  ASSERT_EQ(first.status, 0) << first.err;
  const nlohmann::json files = nlohmann::json::parse(readFile(measured / "summary.json"))["files"];
  ASSERT_EQ(files.size(), 5u) << files.dump();

  // Room for the lock file and all the run's outputs but one page: the disk fills as the run
  // closes summary.json, its last, with every other output whole.
  SmallDisk disk(dir_ / "disk", 1 + tmpfsPagesUnder(measured) - 1);
  REQUIRE_MOUNTED(disk);
  const fs::path out = dir_ / "disk" / "out";
  fs::create_directories(out);
  const Outcome full = glint({"run", tiny.string(), "-o", out.string(), "--quiet"});
  expectFullDiskMessage(full, out / "summary.json");
  EXPECT_EQ(folderContents(out), (std::map<std::string, std::string>{}))
      << "no output, no temporary, no lock file";
}

TEST_F(Outputs, AFullDiskLeavesNeitherThePointsTableNorTheTimeSeries) {
  const fs::path data = GLINT_TEST_DATA_DIR;
  const auto run = [&](const fs::path& table, const fs::path& series) {
    return glint({"points", (data / "engagement_mpi.json").string(), "--points",
                  (data / "engagement_points.csv").string(), "--out", table.string(),
                  "--time-series", series.string(), "--quiet"});
  };
  const Outcome measured = run(dir_ / "table.csv", dir_ / "series.csv");
  ASSERT_EQ(measured.status, 0) << measured.err;
  // Room for the table and all of the time series but its last page.
  SmallDisk disk(dir_ / "disk", tmpfsPages(fs::file_size(dir_ / "table.csv")) +
                                    tmpfsPages(fs::file_size(dir_ / "series.csv")) - 1);
  REQUIRE_MOUNTED(disk);
  const Outcome full = run(dir_ / "disk" / "table.csv", dir_ / "disk" / "series.csv");
  expectFullDiskMessage(full, dir_ / "disk" / "series.csv");
  EXPECT_TRUE(fs::is_empty(dir_ / "disk")) << "neither file, nor a temporary";
}

TEST_F(Outputs, AFullDiskLeavesNoStudyFileAndTheStudyResumesItsScenarios) {
  // The batch tests' study, coarse, one scenario: about 3 s.
  nlohmann::json base =
      nlohmann::json::parse(readFile(fs::path(GLINT_TEST_DATA_DIR) / "study_scene.json"));
  base["observers"]["voxel_m"] = 0.8;
  base["planes"][0]["pixel_m"] = 0.4;
  base["far_field"] = {{"enabled", false}};
  std::ofstream(dir_ / "base.json") << base.dump();
  const fs::path study = dir_ / "study.json";
  std::ofstream(study) << R"({"scene": "base.json", "sweep": {"pitch_deg": [4]}})";
  const fs::path measured = dir_ / "measured";
  const Outcome first = glint({"batch", study.string(), "-o", measured.string(), "--quiet"});
  ASSERT_EQ(first.status, 0) << first.err;

  // Room for the scenario, the lock file, scenarios.csv and half of box.vdb.
  SmallDisk disk(dir_ / "disk", tmpfsPagesUnder(measured / "scenarios") + 1 +
                                    tmpfsPages(fs::file_size(measured / "scenarios.csv")) +
                                    tmpfsPages(fs::file_size(measured / "box.vdb")) / 2);
  REQUIRE_MOUNTED(disk);
  const fs::path out = dir_ / "disk" / "out";
  const Outcome full = glint({"batch", study.string(), "-o", out.string(), "--quiet"});
  expectFullDiskMessage(full, out / "box.vdb");
  std::vector<std::string> left;
  for (const auto& e : fs::directory_iterator(out)) left.push_back(e.path().filename().string());
  EXPECT_EQ(left, std::vector<std::string>{"scenarios"})
      << "no scenarios.csv, map or summary.json; the finished scenario stays";
  EXPECT_TRUE(fs::exists(out / "scenarios" / "s000000" / "result.json"));

  // With room, the next run takes the scenario up and writes the study's files.
  ASSERT_TRUE(disk.resize(4096));
  const Outcome resumed = glint({"batch", study.string(), "-o", out.string()});
  ASSERT_EQ(resumed.status, 0) << resumed.err;
  EXPECT_NE(resumed.err.find("(1 done before, 0 to run)"), std::string::npos) << resumed.err;
  for (const char* name : {"scenarios.csv", "box.vdb", "ground.exr", "summary.json"})
    EXPECT_TRUE(fs::is_regular_file(out / name)) << name;
}

}  // namespace
}  // namespace glint
