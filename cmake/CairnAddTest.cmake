# cairn_add_test(NAME SOURCES ... LIBS ... LABELS unit|integration [TIMEOUT s] [PROCESSORS n])
# Builds one GoogleTest executable and registers each of its tests with CTest. PROCESSORS is the
# number of cores a test keeps busy: a closed-loop graph (a real-time simulator with its lidar, a
# mapper and a navigator) takes 2, so `ctest -j2` on a 2-core machine runs it alone, as the graph
# would run on a robot's own computer.
find_package(GTest REQUIRED)
include(GoogleTest)

function(cairn_add_test name)
  cmake_parse_arguments(ARG "" "TIMEOUT;PROCESSORS" "SOURCES;LIBS;LABELS" ${ARGN})
  if(NOT ARG_TIMEOUT)
    set(ARG_TIMEOUT 120)
  endif()
  if(NOT ARG_PROCESSORS)
    set(ARG_PROCESSORS 1)
  endif()
  set(sources ${ARG_SOURCES})
  if(CAIRN_SANITIZE MATCHES "thread")
    # glib's futex locks made visible to ThreadSanitizer (tests/support/tsan_glib_sync.cc).
    list(APPEND sources ${PROJECT_SOURCE_DIR}/tests/support/tsan_glib_sync.cc)
  endif()
  add_executable(${name} ${sources})
  cairn_target_defaults(${name})
  set_target_properties(${name} PROPERTIES RUNTIME_OUTPUT_DIRECTORY ${CMAKE_BINARY_DIR}/tests)
  target_link_libraries(${name} PRIVATE ${ARG_LIBS} GTest::gmock GTest::gtest_main)
  target_compile_definitions(${name} PRIVATE
    CAIRN_SOURCE_DIR="${PROJECT_SOURCE_DIR}" CAIRN_BINARY_DIR="${CMAKE_BINARY_DIR}")
  gtest_discover_tests(${name}
    TEST_PREFIX "${name}."
    PROPERTIES LABELS "${ARG_LABELS}" TIMEOUT ${ARG_TIMEOUT} PROCESSORS ${ARG_PROCESSORS}
    DISCOVERY_TIMEOUT 60)
endfunction()
