#pragma once
/// @file
/// @brief Pause points for tests: with GLINT_TEST_PAUSE_AFTER set in its environment, glint stops
/// at the point it names and waits for a signal, so that a test can interrupt it there however
/// fast or loaded the machine is (tests/pipeline/interrupt_test.sh).

#include <ostream>

namespace glint {

/// @brief The environment variable, and its values: pause once the outputs' temporaries are
/// created, once the first of a command's outputs is in place and the others are not yet, or
/// once all of them are.
inline constexpr const char* kTestPauseVariable = "GLINT_TEST_PAUSE_AFTER";
inline constexpr const char* kTestPauseAfterTemporaries = "temporaries";
inline constexpr const char* kTestPauseAfterFirstOutput = "first-output";
inline constexpr const char* kTestPauseAfterOutputs = "outputs";

/// @brief If GLINT_TEST_PAUSE_AFTER is `temporaries`, says so on @p err (a line starting
/// "glint: paused") and blocks until a signal ends the process; otherwise returns at once.
/// Call it right after the run has created all its output temporaries.
void pauseForTestsAfterTemporaries(std::ostream& err);

/// @brief If GLINT_TEST_PAUSE_AFTER is `first-output`, says so on @p err (a line starting
/// "glint: paused") and blocks until a signal ends the process; otherwise returns at once.
/// For OutputSet::commit()'s `after_first`: one output is then in place, the others not.
void pauseForTestsAfterFirstOutput(std::ostream& err);

/// @brief If GLINT_TEST_PAUSE_AFTER is `outputs`, says so on @p err (a line starting
/// "glint: paused") and blocks until a signal ends the process; otherwise returns at once.
/// Call it right after OutputSet::commit() returns: every output is then in place.
void pauseForTestsAfterOutputs(std::ostream& err);

}  // namespace glint
