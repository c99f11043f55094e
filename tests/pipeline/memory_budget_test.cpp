// The memory budget: sizes read as users write them, refusals that say what a region needs,
// and a watch that raises its flag once the process passes the budget.
#include "pipeline/memory_budget.h"

#include <gtest/gtest.h>

#include <chrono>
#include <thread>

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
  // This process is resident in more than a kilobyte: the flag must rise at the first sample.
  const MemoryWatch watch(1024);
  for (int i = 0; i < 500 && !watch.exceeded(); ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  ASSERT_TRUE(watch.exceeded()) << "no sample in 5 s";
  EXPECT_TRUE(watch.stopFlag().load());
  EXPECT_GT(watch.peakBytes(), 1024u);
  EXPECT_THROW(watch.check("the observer box"), InputError);
  const MemoryWatch roomy(std::uint64_t{1} << 50);
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  EXPECT_FALSE(roomy.exceeded()) << "a petabyte budget was passed";
  EXPECT_NO_THROW(roomy.check("the observer box"));
}

}  // namespace
}  // namespace glint
