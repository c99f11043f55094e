# GLINT_FUZZ: a libFuzzer build of the input boundaries (tests/fuzz/README.md).
#
# A fuzz build is a build folder of its own, configured with Clang:
#   cmake -S . -B build-fuzz -G Ninja -DCMAKE_CXX_COMPILER=clang++-14 -DGLINT_FUZZ=ON ...
# Every glint target in it is compiled with AddressSanitizer, UndefinedBehaviorSanitizer and
# libFuzzer's coverage instrumentation, so a bug deep in the loaders is seen, not only one in
# the fuzz targets; tests/fuzz/CMakeLists.txt adds the fuzzers, which link libFuzzer itself.
# Prebuilt libraries (tinygltf, OpenVDB, TBB, Embree) are not instrumented. Included by the
# top-level CMakeLists.txt before any target is defined, so the options reach every target.

option(GLINT_FUZZ "libFuzzer targets; every glint target with ASan and UBSan (Clang only)" OFF)

if(GLINT_FUZZ)
  if(NOT CMAKE_CXX_COMPILER_ID MATCHES "Clang")
    message(FATAL_ERROR
      "GLINT_FUZZ=ON needs Clang (libFuzzer is part of Clang), but the C++ compiler is "
      "${CMAKE_CXX_COMPILER_ID} ${CMAKE_CXX_COMPILER}. Configure a separate build folder with "
      "-DCMAKE_CXX_COMPILER=clang++-14 -DGLINT_FUZZ=ON (tests/fuzz/README.md).")
  endif()
  if(NOT GLINT_BUILD_TESTS)
    message(WARNING "GLINT_FUZZ=ON without GLINT_BUILD_TESTS: no fuzzers are built")
  endif()
  # A UBSan report aborts, so libFuzzer records it as a crash instead of printing and going on.
  add_compile_options(-fsanitize=address,undefined -fno-sanitize-recover=undefined
                      -fno-omit-frame-pointer -fsanitize=fuzzer-no-link)
  # Reports name file and line in a Release build too (Debug and RelWithDebInfo have -g).
  if(NOT CMAKE_BUILD_TYPE MATCHES "Deb")
    add_compile_options(-gline-tables-only)
  endif()
  add_link_options(-fsanitize=address,undefined)
endif()
