// The glint command line; everything it does lives in glint_pipeline.
#include <iostream>

#include "export/atomic_file.h"
#include "pipeline/commands/cli.h"

int main(int argc, char** argv) {
  // SIGINT, SIGTERM and SIGHUP remove unfinished output files and exit with 128 + signal.
  glint::installInterruptCleanup();
  return glint::runGlint(argc, argv, std::cout, std::cerr);
}
