# Every third-party package comes from Debian 12 (see scripts/setup).
find_package(PkgConfig REQUIRED)
pkg_check_modules(LCM REQUIRED IMPORTED_TARGET lcm)
find_program(LCM_GEN lcm-gen REQUIRED)
find_package(Threads REQUIRED)
find_package(Eigen3 3.3 REQUIRED NO_MODULE)
find_package(yaml-cpp REQUIRED)
find_package(mujoco REQUIRED)
# Debian's mujoco config lists /usr/include/libqhull_r/ (from libqhull-dev, which it does not
# depend on and MuJoCo's public headers do not need); drop it when absent so targets generate.
get_target_property(_cairn_mujoco_inc mujoco::mujoco INTERFACE_INCLUDE_DIRECTORIES)
if(_cairn_mujoco_inc)
  list(FILTER _cairn_mujoco_inc EXCLUDE REGEX "libqhull_r")
  set_target_properties(mujoco::mujoco PROPERTIES INTERFACE_INCLUDE_DIRECTORIES
                        "${_cairn_mujoco_inc}")
endif()
find_package(octomap REQUIRED)
find_package(ompl REQUIRED)
find_package(SQLite3 REQUIRED)
find_package(ZLIB REQUIRED)
find_package(PNG REQUIRED)
pkg_check_modules(ZSTD REQUIRED IMPORTED_TARGET libzstd)

# OMPL 1.5.2 and OctoMap 1.9.7 export variables only: wrap them once.
if(NOT TARGET cairn::ompl)
  add_library(cairn_ompl INTERFACE)
  target_include_directories(cairn_ompl SYSTEM INTERFACE ${OMPL_INCLUDE_DIRS})
  # Debian's omplConfig.cmake appends Boost development libraries (libboost_*.so) that are not
  # installed and not needed: libompl.so names its runtime dependencies itself. Link only the
  # entries that exist (absolute paths that are present, or plain names such as "ode").
  set(CAIRN_OMPL_LINK_LIBRARIES)
  foreach(lib IN LISTS OMPL_LIBRARIES)
    if(NOT IS_ABSOLUTE "${lib}" OR EXISTS "${lib}")
      list(APPEND CAIRN_OMPL_LINK_LIBRARIES "${lib}")
    endif()
  endforeach()
  target_link_libraries(cairn_ompl INTERFACE ${CAIRN_OMPL_LINK_LIBRARIES})
  add_library(cairn::ompl ALIAS cairn_ompl)
endif()
if(NOT TARGET cairn::octomap)
  add_library(cairn_octomap INTERFACE)
  target_include_directories(cairn_octomap SYSTEM INTERFACE ${OCTOMAP_INCLUDE_DIRS})
  target_link_libraries(cairn_octomap INTERFACE ${OCTOMAP_LIBRARIES})
  add_library(cairn::octomap ALIAS cairn_octomap)
endif()

find_package(Java COMPONENTS Development QUIET)
