#include "pipeline/base/test_pause.h"

#include <unistd.h>

#include <cstdlib>
#include <cstring>

namespace glint {
namespace {

// Pauses for a signal if GLINT_TEST_PAUSE_AFTER is @p value, saying that glint paused after
// @p what.
void pauseIfAsked(const char* value, const char* what, std::ostream& err) {
  const char* asked = std::getenv(kTestPauseVariable);
  if (asked == nullptr || std::strcmp(asked, value) != 0) return;
  // The line is the test's cue: by now the files are on disk, so the test needs neither a long
  // run nor a timed poll to find glint mid-write.
  err << "glint: paused after " << what << " (" << kTestPauseVariable << "=" << value
      << "); waiting for a signal" << std::endl;
  // Only a signal ends this: the interrupt handlers exit from within pause().
  for (;;) ::pause();
}

}  // namespace

void pauseForTestsAfterTemporaries(std::ostream& err) {
  pauseIfAsked(kTestPauseAfterTemporaries, "creating the output temporaries", err);
}

void pauseForTestsAfterFirstOutput(std::ostream& err) {
  pauseIfAsked(kTestPauseAfterFirstOutput, "putting the first output in place", err);
}

void pauseForTestsAfterOutputs(std::ostream& err) {
  pauseIfAsked(kTestPauseAfterOutputs, "putting every output in place", err);
}

}  // namespace glint
