// What a long run prints while it works: the step under way counted by its own items, whose
// total is known when the step begins (issue 65: "211644/228806 directions" grew as the far
// radius's spheres were scheduled, and the reach's levels did the same).
#include "pipeline/base/progress.h"

#include <gtest/gtest.h>

#include <string>

#include "pipeline/base/phase_clock.h"

namespace glint {
namespace {

TEST(Progress, AStepIsCountedByItsOwnItemsWhoseTotalDoesNotGrow) {
  WorkCounter counter;
  counter.beginStage("face", 2, 6);
  counter.items_scheduled += 1000;
  counter.items_done += 100;  // the steps before
  counter.beginStep("level", 3, 0, 40);
  counter.items_scheduled += 40;
  counter.items_done += 10;
  counter.evaluations += 12345;
  const std::string line = progressLine(counter, "reach points", 0, 3.0);
  EXPECT_EQ(line.rfind("glint: face 2 of 6, level 3: 10/40 reach points (25%), 1.23e+04 "
                       "evaluations, 3.00 s elapsed, about ",
                       0),
            0u)
      << line;
  EXPECT_NE(line.find(" left in this level"), std::string::npos) << line;

  // More items scheduled later (the next level's) do not change the step's count.
  counter.items_scheduled += 5000;
  counter.items_done += 30;
  EXPECT_NE(
      progressLine(counter, "reach points", 0, 4.0).find("level 3: 40/40 reach points (100%)"),
      std::string::npos)
      << progressLine(counter, "reach points", 0, 4.0);
}

TEST(Progress, AStepOfABoundedCountSaysAtMostHowManyThereAre) {
  WorkCounter counter;
  counter.beginStep("sphere", 4, 13, 1454);
  counter.items_done += 727;
  const std::string line = progressLine(counter, "directions", 0, 1.0);
  EXPECT_NE(line.find("glint: sphere 4 of at most 13: 727/1454 directions (50%)"),
            std::string::npos)
      << line;
  EXPECT_EQ(progressLine(counter, "files", 0, 1.0, true).find("left"), std::string::npos)
      << "items of no like cost estimate no time left: "
      << progressLine(counter, "files", 0, 1.0, true);
  EXPECT_EQ(line.find("evaluations"), std::string::npos)
      << "work that integrates nothing does not count evaluations: " << line;
  counter.endStages();
  EXPECT_NE(progressLine(counter, "directions", 2000, 1.0).find("glint: 727/2000 directions"),
            std::string::npos)
      << "without steps, the whole count: " << progressLine(counter, "directions", 2000, 1.0);
}

TEST(PhaseClock, APhaseTimedTwiceAddsUpInThePlaceItFirstTook) {
  PhaseClock clock;
  clock.add("b", 1.0);
  { const PhaseClock::Scope a = clock.phase("a"); }
  clock.add("b", 2.5);
  ASSERT_EQ(clock.phases().size(), 2u);
  EXPECT_EQ(clock.phases()[0].first, "b");
  EXPECT_DOUBLE_EQ(clock.phases()[0].second, 3.5) << "1 s and 2.5 s of the same phase";
  EXPECT_EQ(clock.phases()[1].first, "a");
  EXPECT_GE(clock.phases()[1].second, 0.0);
  EXPECT_LE(clock.phases()[1].second, clock.elapsedSeconds())
      << "a scope within the clock's life is no longer than it";
}

}  // namespace
}  // namespace glint
