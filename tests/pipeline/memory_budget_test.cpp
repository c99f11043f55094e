// The memory budget: sizes read as users write them, refusals that say what a region needs,
// and a watch that raises its flag once the process passes the budget.
#include "pipeline/memory_budget.h"

#include <gtest/gtest.h>

#include <chrono>
#include <thread>
#include <vector>

#include "observers/field.h"
#include "pipeline/input_error.h"

namespace glint {
namespace {

TEST(MemoryBudget, SizesReadAsWritten) {
  EXPECT_EQ(parseByteSize("512M"), std::uint64_t{512} << 20);
  EXPECT_EQ(parseByteSize("4G"), std::uint64_t{4} << 30);
  EXPECT_EQ(parseByteSize("4GB"), std::uint64_t{4} << 30);
  EXPECT_EQ(parseByteSize("16GiB"), std::uint64_t{16} << 30);
  EXPECT_EQ(parseByteSize("1.5g"), std::uint64_t{3} << 29);
  EXPECT_EQ(parseByteSize("2e9"), std::uint64_t{2000000000});
  EXPECT_EQ(parseByteSize("100K"), std::uint64_t{102400});
  for (const char* bad : {"", "0", "-1G", "nan", "inf", "12Q", "G", "1e30", "4 G"}) {
    EXPECT_FALSE(parseByteSize(bad).has_value()) << "'" << bad << "' was taken as a size";
  }
}

TEST(MemoryBudget, BytesPrintedInPowersOf1024) {
  EXPECT_EQ(formatBytes(512.0), "512 bytes");
  EXPECT_EQ(formatBytes(1536.0), "1.5 KB");
  EXPECT_EQ(formatBytes(17.7 * 1073741824.0), "17.7 GB");
}

TEST(MemoryBudget, TheDefaultIsThreeQuartersOfTheMachine) {
  const std::uint64_t machine = machineMemoryBytes();
  EXPECT_GT(machine, std::uint64_t{256} << 20) << "no machine runs glint in less";
  EXPECT_EQ(defaultMemoryBudgetBytes(), machine / 4 * 3);
  EXPECT_GT(residentBytes(), 0u) << "/proc/self/statm unread";
}

TEST(MemoryBudget, ARegionBeyondTheBudgetIsRefusedWithItsEstimate) {
  // The box: −2000…2000 m at 0.0625 m, 64 000 voxels a side, 4 000³ coarse blocks.
  FieldSpec spec;
  spec.min_m = Vec3(-2000.0);
  spec.max_m = Vec3(2000.0);
  spec.voxel_m = 0.0625;
  spec.block_voxels = 16;
  const std::uint64_t floor_bytes = fieldMemoryFloorBytes(spec, false);
  EXPECT_GE(floor_bytes, std::uint64_t{64'000'000'000} * 1000)
      << "6.4e10 coarse blocks at a kilobyte or more each";
  EXPECT_GT(fieldMemoryFloorBytes(spec, true), floor_bytes) << "the dense twin needs more";
  try {
    requireWithinBudget("observer box", floor_bytes, std::uint64_t{16} << 30, "coarsen voxel_m");
    ADD_FAILURE() << "an 87 TB region was accepted in a 16 GB budget";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              "observer box needs at least 87.3 TB of memory, more than the budget of 16 GB "
              "(--memory); coarsen voxel_m");
  }
  EXPECT_NO_THROW(requireWithinBudget("box", 1000, 1000, "")) << "the budget itself is allowed";
}

TEST(MemoryBudget, TheWatchRaisesItsFlagPastTheBudget) {
  // The watch samples once before its constructor returns, and this process is resident in
  // more than a kilobyte: the flag is up at once, with no wait on the watch's thread.
  const MemoryWatch watch(1024);
  ASSERT_GE(watch.samples(), 1u) << "the constructor takes the first sample";
  EXPECT_GT(watch.peakBytes(), 1024u) << "the sample read /proc/self/statm";
  EXPECT_TRUE(watch.exceeded()) << "resident " << watch.peakBytes() << " bytes, budget 1024";
  EXPECT_TRUE(watch.stopFlag().load()) << "the flag the field builders poll";
  EXPECT_THROW(watch.check("the observer box"), InputError);
  // A petabyte is not passed: and the watch has sampled, so this is its verdict, not silence.
  const MemoryWatch roomy(std::uint64_t{1} << 50);
  ASSERT_GE(roomy.samples(), 1u) << "the constructor takes the first sample";
  EXPECT_GT(roomy.peakBytes(), 0u) << "the sample read /proc/self/statm";
  EXPECT_FALSE(roomy.exceeded()) << "a petabyte budget was passed at " << roomy.peakBytes();
  EXPECT_NO_THROW(roomy.check("the observer box"));
}

TEST(MemoryBudget, TheWatchSeesMemoryTakenAfterItStarted) {
  // A budget 64 MiB above what the process holds now, then 128 MiB taken and touched: a sample
  // of the watch's own thread taken after that must raise the flag. The wait is for samples,
  // not for time (a watch whose thread never samples is left to ctest's timeout).
  constexpr std::size_t kMiB = std::size_t{1} << 20;
  const MemoryWatch watch(residentBytes() + 64 * kMiB);
  ASSERT_GE(watch.samples(), 1u) << "the constructor takes the first sample";
  ASSERT_FALSE(watch.exceeded()) << "premise: within the budget at the start";
  std::vector<char> taken(128 * kMiB);
  for (std::size_t i = 0; i < taken.size(); i += 4096) taken[i] = 1;  // resident, page by page
  // A sample that began before the pages were touched may still be in flight: two more.
  const std::uint64_t after = watch.samples() + 2;
  while (watch.samples() < after) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  EXPECT_TRUE(watch.exceeded()) << "128 MiB past a budget with 64 MiB to spare; peak "
                                << watch.peakBytes() << ", budget " << watch.budgetBytes();
  EXPECT_GE(watch.peakBytes(), watch.budgetBytes()) << "the peak records what passed the budget";
  EXPECT_EQ(taken[4096], 1) << "the pages stayed in use";
}

}  // namespace
}  // namespace glint
