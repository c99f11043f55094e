# Compiler settings shared by every glint target.
#
# The physics relies on IEEE semantics (NaN checks, compensated sums, exact zero tests), so
# no fast-math style flag may ever be added here.

find_program(GLINT_CCACHE ccache)
if(GLINT_CCACHE AND NOT CMAKE_CXX_COMPILER_LAUNCHER)
  set(CMAKE_CXX_COMPILER_LAUNCHER ${GLINT_CCACHE} CACHE STRING "Compiler launcher" FORCE)
endif()

# glint_configure_target(<target>): warnings (as errors with GLINT_WERROR) and the repository
# root as the include root, so headers are included as "facets/beckmann.h".
function(glint_configure_target target)
  target_compile_options(${target} PRIVATE
    -Wall -Wextra -Wpedantic -Wshadow -Wconversion -Wno-sign-conversion
    -Wnon-virtual-dtor -Wold-style-cast -Woverloaded-virtual -Wdouble-promotion
    $<$<BOOL:${GLINT_WERROR}>:-Werror>)
endfunction()
