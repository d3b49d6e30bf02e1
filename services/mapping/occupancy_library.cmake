# Occupancy half of cairn::mapping (2-D log-odds occupancy, obstacle band, OctoMap layer,
# dynamic layers) as its own core library until it joins the cairn_mapping target.
# Included from tests/unit/mapping/occupancy.cmake and bench/mapping/octomap.cmake.
if(NOT TARGET cairn_mapping_occupancy)
  set(_occ_dir ${PROJECT_SOURCE_DIR}/services/mapping)
  cairn_core_library(cairn_mapping_occupancy ALIAS cairn::mapping_occupancy
    SOURCES
      ${_occ_dir}/raytrace.cc
      ${_occ_dir}/occupancy_grid.cc
      ${_occ_dir}/occupancy_band.cc
      ${_occ_dir}/octomap_batch_insert.cc
      ${_occ_dir}/octomap_layer.cc
      ${_occ_dir}/dynamic_layers.cc
    DEPS cairn::common cairn::octomap Eigen3::Eigen
    PRIVATE_DEPS PNG::PNG)
endif()
