# OctoMap layer insertion benchmark (group "mapping": build/bin/bench_mapping_octomap).
include(${PROJECT_SOURCE_DIR}/services/mapping/occupancy_library.cmake)
cairn_executable(bench_mapping_octomap
  SOURCES ${CMAKE_CURRENT_LIST_DIR}/bench_octomap.cc
  DEPS cairn::mapping_occupancy cairn::common)
