# Helpers that give every cairn target the same flags and enforce the layering rule:
# core libraries never link cairn::lcmtypes (so an LCM include in core code fails to compile).

function(cairn_target_defaults target)
  target_compile_options(${target} PRIVATE ${CAIRN_WARNING_FLAGS})
  target_include_directories(${target} PUBLIC $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}>)
endfunction()

# cairn_core_library(NAME alias SOURCES ... DEPS ...): a pure library without LCM.
function(cairn_core_library name)
  cmake_parse_arguments(ARG "" "ALIAS" "SOURCES;DEPS;PRIVATE_DEPS" ${ARGN})
  foreach(dep IN LISTS ARG_DEPS ARG_PRIVATE_DEPS)
    if(dep STREQUAL "cairn::lcmtypes" OR dep STREQUAL "cairn::runtime" OR dep MATCHES "PkgConfig::LCM")
      message(FATAL_ERROR "core library ${name} may not depend on ${dep}: core code never includes LCM")
    endif()
  endforeach()
  add_library(${name} ${ARG_SOURCES})
  cairn_target_defaults(${name})
  target_link_libraries(${name} PUBLIC ${ARG_DEPS} PRIVATE ${ARG_PRIVATE_DEPS})
  if(ARG_ALIAS)
    add_library(${ARG_ALIAS} ALIAS ${name})
  endif()
endfunction()

# cairn_service_library(NAME alias SOURCES ... DEPS ...): the LCM adapter/service layer.
function(cairn_service_library name)
  cmake_parse_arguments(ARG "" "ALIAS" "SOURCES;DEPS;PRIVATE_DEPS" ${ARGN})
  add_library(${name} ${ARG_SOURCES})
  cairn_target_defaults(${name})
  target_link_libraries(${name} PUBLIC ${ARG_DEPS} cairn::lcmtypes PRIVATE ${ARG_PRIVATE_DEPS})
  if(ARG_ALIAS)
    add_library(${ARG_ALIAS} ALIAS ${name})
  endif()
endfunction()

# cairn_executable(NAME SOURCES ... DEPS ...): a thin *_main.cc process, lands in build/bin.
function(cairn_executable name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS" ${ARGN})
  add_executable(${name} ${ARG_SOURCES})
  cairn_target_defaults(${name})
  target_link_libraries(${name} PRIVATE ${ARG_DEPS})
endfunction()
