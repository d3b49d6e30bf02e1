# Unit tests of the occupancy half of the mapping core.
include(${PROJECT_SOURCE_DIR}/services/mapping/occupancy_library.cmake)
cairn_add_test(mapping_occupancy_test
  SOURCES
    ${CMAKE_CURRENT_LIST_DIR}/occupancy_raytrace_test.cc
    ${CMAKE_CURRENT_LIST_DIR}/occupancy_grid_test.cc
    ${CMAKE_CURRENT_LIST_DIR}/occupancy_band_test.cc
    ${CMAKE_CURRENT_LIST_DIR}/octomap_layer_test.cc
    ${CMAKE_CURRENT_LIST_DIR}/dynamic_layers_test.cc
  LIBS cairn::mapping_occupancy PNG::PNG
  LABELS unit)
