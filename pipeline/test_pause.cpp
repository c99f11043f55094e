#include "pipeline/test_pause.h"

#include <unistd.h>

#include <cstdlib>
#include <cstring>

namespace glint {

void pauseForTestsAfterTemporaries(std::ostream& err) {
  const char* value = std::getenv(kTestPauseVariable);
  if (value == nullptr || std::strcmp(value, kTestPauseAfterTemporaries) != 0) return;
  // The line is the test's cue: by now every temporary is on disk, so the test needs neither
  // a long run nor a timed poll to find glint mid-write.
  err << "glint: paused after creating the output temporaries (" << kTestPauseVariable << "="
      << kTestPauseAfterTemporaries << "); waiting for a signal" << std::endl;
  // Only a signal ends this: the interrupt handlers exit from within pause().
  for (;;) ::pause();
}

}  // namespace glint
