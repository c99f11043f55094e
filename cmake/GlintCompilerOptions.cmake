# Compiler settings shared by every glint target.
#
# The physics relies on IEEE semantics (NaN checks, compensated sums, exact zero tests), so
# no fast-math style flag may ever be added here.

# ccache with paths taken relative to the checkout and the build folder left out of the hash:
# a fresh clone elsewhere (CI's) then finds what any earlier build of the same sources left, in
# the Release and the sanitizer build alike (the latter's line tables would otherwise hash it).
find_program(GLINT_CCACHE ccache)
if(GLINT_CCACHE AND (NOT CMAKE_CXX_COMPILER_LAUNCHER OR CMAKE_CXX_COMPILER_LAUNCHER STREQUAL
                                                         GLINT_CCACHE))
  set(CMAKE_CXX_COMPILER_LAUNCHER /usr/bin/env CCACHE_BASEDIR=${PROJECT_SOURCE_DIR}
      CCACHE_NOHASHDIR=true ${GLINT_CCACHE} CACHE STRING "Compiler launcher" FORCE)
endif()

# glint_configure_target(<target>): warnings (as errors with GLINT_WERROR) and the repository
# root as the include root, so headers are included as "facets/beckmann.h".
function(glint_configure_target target)
  target_compile_options(${target} PRIVATE
    -Wall -Wextra -Wpedantic -Wshadow -Wconversion -Wno-sign-conversion
    -Wnon-virtual-dtor -Wold-style-cast -Woverloaded-virtual -Wdouble-promotion
    $<$<BOOL:${GLINT_WERROR}>:-Werror>)
endfunction()
