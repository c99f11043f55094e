// The glint command line; everything it does lives in glint_pipeline.
#include <iostream>

#include "pipeline/cli.h"

int main(int argc, char** argv) { return glint::runGlint(argc, argv, std::cout, std::cerr); }
