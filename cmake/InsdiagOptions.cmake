# Project-wide options as INTERFACE targets: nothing here touches global flags.
option(INSDIAG_BUILD_TESTS "Build the test suite" ON)
option(INSDIAG_BUILD_BENCHMARKS "Build the Google Benchmark programs" ON)
option(INSDIAG_WARNINGS_AS_ERRORS "Treat compiler warnings as errors (on in CI)" OFF)
option(INSDIAG_SANITIZE "Build with AddressSanitizer and UndefinedBehaviorSanitizer" OFF)
option(INSDIAG_FUZZ "Build the libFuzzer targets (tests/fuzz; clang), instrumenting every first-party library" OFF)

find_program(INSDIAG_CCACHE ccache)
if(INSDIAG_CCACHE)
  # The tests' precompiled headers (tests/CMakeLists.txt) are cached only with
  # this sloppiness; the compiler's own check (-Winvalid-pch) still guards them.
  set(CMAKE_CXX_COMPILER_LAUNCHER env CCACHE_SLOPPINESS=pch_defines,time_macros ${INSDIAG_CCACHE})
endif()

# insdiag::warnings — the warning set every first-party target builds with.
add_library(insdiag_warnings INTERFACE)
add_library(insdiag::warnings ALIAS insdiag_warnings)
target_compile_options(insdiag_warnings INTERFACE
  -Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor -Wcast-align
  -Woverloaded-virtual -Wnull-dereference -Wimplicit-fallthrough
  $<$<BOOL:${INSDIAG_WARNINGS_AS_ERRORS}>:-Werror>)

# insdiag::sanitizers — opt-in ASan/UBSan for debugging runs.
add_library(insdiag_sanitizers INTERFACE)
add_library(insdiag::sanitizers ALIAS insdiag_sanitizers)
if(INSDIAG_FUZZ)
  target_compile_options(insdiag_sanitizers INTERFACE -fsanitize=fuzzer-no-link,address,undefined
                         -fno-sanitize-recover=undefined -fno-omit-frame-pointer -g)
  target_link_options(insdiag_sanitizers INTERFACE -fsanitize=address,undefined)
elseif(INSDIAG_SANITIZE)
  target_compile_options(insdiag_sanitizers INTERFACE -fsanitize=address,undefined -fno-omit-frame-pointer)
  target_link_options(insdiag_sanitizers INTERFACE -fsanitize=address,undefined)
endif()

# Fails the configure step when `target` links (directly or transitively through
# first-party targets) any of `forbidden` (regular expressions matched against
# target names): the engine must stay a pure library, the server must not carry
# the fleet generator. The message names the chain of links that reached it.
function(insdiag_forbid_links target)
  set(pending ${target})
  set(seen "")
  while(pending)
    list(POP_FRONT pending current)
    if(current IN_LIST seen)
      continue()
    endif()
    list(APPEND seen ${current})
    foreach(forbidden IN LISTS ARGN)
      if(current MATCHES "${forbidden}")
        set(chain "${current}")
        set(step "${current}")
        while(DEFINED "linked_by_${step}")
          set(step "${linked_by_${step}}")
          string(PREPEND chain "${step} -> ")
        endwhile()
        message(FATAL_ERROR "${target} must not link ${current} (layering rule: see the layers in the root "
                            "CMakeLists.txt); it does through ${chain}")
      endif()
    endforeach()
    if(TARGET ${current})
      get_target_property(aliased ${current} ALIASED_TARGET)
      set(next "")
      if(aliased)
        list(APPEND next ${aliased})
      endif()
      get_target_property(links ${current} LINK_LIBRARIES)
      get_target_property(ilinks ${current} INTERFACE_LINK_LIBRARIES)
      foreach(l IN LISTS links ilinks)
        if(l AND NOT l MATCHES "NOTFOUND$" AND NOT l MATCHES "^\\$<")
          list(APPEND next ${l})
        endif()
      endforeach()
      foreach(l IN LISTS next)
        if(NOT l IN_LIST seen AND NOT DEFINED "linked_by_${l}")
          set("linked_by_${l}" "${current}")
        endif()
      endforeach()
      list(APPEND pending ${next})
    endif()
  endwhile()
endfunction()
