# GLINT_SANITIZE: every glint target (libraries, glint, tests, replays) with AddressSanitizer,
# LeakSanitizer and UndefinedBehaviorSanitizer, in a build folder of its own:
#   cmake -S . -B build-asan -G Ninja -DCMAKE_CXX_COMPILER=clang++-14 -DGLINT_SANITIZE=ON \
#         -DGLINT_BUILD_BENCH=OFF -DGLINT_WERROR=OFF
# .ci/sanitize does that, builds and runs ctest with the options and suppressions of
# .ci/sanitizers/ (without them the known third-party reports fail the suite).
# Clang 14 (Debian: clang-14, libclang-rt-14-dev) is what CI runs; GCC 12 is accepted too.
# Prebuilt libraries (oneTBB, OpenVDB, Embree, OpenEXR, Open MPI) are not instrumented, but
# their header templates compiled into glint are. Included by the top-level CMakeLists.txt
# before any target is defined, so the options reach every target.
#
# Every UBSan check aborts at its first report (-fno-sanitize-recover=undefined) except the
# alignment check: an aborting check calls Die() even when its report is suppressed, and the
# oneTBB misaligned downcast (.ci/sanitizers/ubsan.supp) must be suppressible. An alignment
# report that is not suppressed still stops the program under .ci/sanitize's halt_on_error=1.

option(GLINT_SANITIZE "Every glint target with ASan, LSan and UBSan (Clang or GCC)" OFF)

if(GLINT_SANITIZE)
  if(NOT CMAKE_CXX_COMPILER_ID MATCHES "Clang|GNU")
    message(FATAL_ERROR
      "GLINT_SANITIZE=ON needs Clang or GCC, but the C++ compiler is ${CMAKE_CXX_COMPILER_ID} "
      "${CMAKE_CXX_COMPILER}. Configure a separate build folder with "
      "-DCMAKE_CXX_COMPILER=clang++-14 -DGLINT_SANITIZE=ON, or run .ci/sanitize.")
  endif()
  add_compile_options(-fsanitize=address,undefined -fno-sanitize-recover=undefined
                      -fsanitize-recover=alignment -fno-omit-frame-pointer)
  # Reports name file and line in a Release build too (Debug and RelWithDebInfo have -g).
  if(NOT CMAKE_BUILD_TYPE MATCHES "Deb")
    if(CMAKE_CXX_COMPILER_ID MATCHES "Clang")
      add_compile_options(-gline-tables-only)
    else()
      add_compile_options(-g1)
    endif()
  endif()
  add_link_options(-fsanitize=address,undefined)
endif()
