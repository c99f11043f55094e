#pragma once
// Runs the glint command line in the test's own process and keeps what it printed.
#include <sstream>
#include <string>
#include <vector>

#include "pipeline/commands/cli.h"

namespace glint::test {

struct Outcome {
  int status;
  std::string out, err;
};

/// @brief `glint ARGS...` through runGlint(), standard output and error captured.
inline Outcome glint(std::vector<std::string> args) {
  args.insert(args.begin(), "glint");
  std::vector<const char*> argv;
  for (const auto& a : args) argv.push_back(a.c_str());
  std::ostringstream out, err;
  const int status = runGlint(static_cast<int>(argv.size()), argv.data(), out, err);
  return {status, out.str(), err.str()};
}

}  // namespace glint::test
