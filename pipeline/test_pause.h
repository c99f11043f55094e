#pragma once
/// @file
/// @brief A pause point for tests: with GLINT_TEST_PAUSE_AFTER=temporaries in its environment,
/// glint stops once its output temporaries exist and waits for a signal, so that a test can
/// interrupt it there however fast or loaded the machine is (tests/pipeline/interrupt_test.sh).

#include <ostream>

namespace glint {

/// @brief The environment variable, and the value that pauses after the outputs' temporaries
/// are created.
inline constexpr const char* kTestPauseVariable = "GLINT_TEST_PAUSE_AFTER";
inline constexpr const char* kTestPauseAfterTemporaries = "temporaries";

/// @brief If GLINT_TEST_PAUSE_AFTER is `temporaries`, says so on @p err (a line starting
/// "glint: paused") and blocks until a signal ends the process; otherwise returns at once.
/// Call it right after the run has created all its output temporaries.
void pauseForTestsAfterTemporaries(std::ostream& err);

}  // namespace glint
