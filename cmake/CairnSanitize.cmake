# Sanitizers and fuzzing (scripts/sanitize, scripts/fuzz).
#
# CAIRN_SANITIZE: sanitizers for every target, e.g. "address,undefined" or "thread" (clang or
# gcc). Undefined behaviour aborts (no recovery), so a test that meets it fails.
# CAIRN_FUZZ: builds the tests/fuzz targets as libFuzzer binaries (clang only) and instruments
# every target for coverage. Without it each fuzz target is a replay binary that runs its corpus
# (tests/fuzz/corpus/<target>) once, registered as a unit test: every build replays the corpora.
set(CAIRN_SANITIZE "" CACHE STRING "Sanitizers for every target: address,undefined | thread")
option(CAIRN_FUZZ "Build the fuzz targets with libFuzzer (clang)" OFF)

if(CAIRN_SANITIZE)
  add_compile_options(-fsanitize=${CAIRN_SANITIZE} -fno-omit-frame-pointer)
  add_link_options(-fsanitize=${CAIRN_SANITIZE})
  if(CAIRN_SANITIZE MATCHES "undefined")
    add_compile_options(-fno-sanitize-recover=undefined)
  endif()
endif()
if(CAIRN_FUZZ)
  if(NOT CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
    message(FATAL_ERROR "CAIRN_FUZZ needs clang (CC=clang CXX=clang++): libFuzzer is clang's")
  endif()
  add_compile_options(-fsanitize=fuzzer-no-link)
endif()
