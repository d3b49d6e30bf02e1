# Helpers that give every cairn target the same flags and enforce the layering rule (ARCHITECTURE
# rule 1): core libraries never link cairn::lcmtypes or the runtime, so an include of a generated
# lcmt_* header in core code fails to compile; LCM libraries live only in services/runtime/ and in
# a component's lcm/ folder. cmake/CairnIncludeRule.cmake scans the includes as well (it also
# catches <lcm/...>, which the system include path would let through).

function(cairn_target_defaults target)
  target_compile_options(${target} PRIVATE ${CAIRN_WARNING_FLAGS})
  target_include_directories(${target} PUBLIC $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}>)
endfunction()

# cairn_core_library(NAME ALIAS alias SOURCES ... DEPS ... PRIVATE_DEPS ...): a pure library
# without LCM.
function(cairn_core_library name)
  cmake_parse_arguments(ARG "" "ALIAS" "SOURCES;DEPS;PRIVATE_DEPS" ${ARGN})
  foreach(dep IN LISTS ARG_DEPS ARG_PRIVATE_DEPS)
    if(dep MATCHES "^cairn::(lcmtypes|runtime)$" OR dep MATCHES "_lcm$" OR dep MATCHES "PkgConfig::LCM")
      message(FATAL_ERROR "core library ${name} may not depend on ${dep}: core code never includes LCM")
    endif()
  endforeach()
  file(RELATIVE_PATH rel ${PROJECT_SOURCE_DIR} ${CMAKE_CURRENT_SOURCE_DIR})
  if(rel MATCHES "(^|/)lcm$" OR rel STREQUAL "services/runtime")
    message(FATAL_ERROR "core library ${name} is declared in ${rel}, which holds LCM code")
  endif()
  add_library(${name} ${ARG_SOURCES})
  cairn_target_defaults(${name})
  target_link_libraries(${name} PUBLIC ${ARG_DEPS} PRIVATE ${ARG_PRIVATE_DEPS})
  if(ARG_ALIAS)
    add_library(${ARG_ALIAS} ALIAS ${name})
  endif()
endfunction()

# cairn_lcm_library(NAME ALIAS alias SOURCES ... DEPS ... PRIVATE_DEPS ...): an LCM adapter (a
# service, a client, conversions), declared in a component's lcm/ folder or in services/runtime.
function(cairn_lcm_library name)
  cmake_parse_arguments(ARG "" "ALIAS" "SOURCES;DEPS;PRIVATE_DEPS" ${ARGN})
  file(RELATIVE_PATH rel ${PROJECT_SOURCE_DIR} ${CMAKE_CURRENT_SOURCE_DIR})
  if(NOT (rel MATCHES "(^|/)lcm$" OR rel STREQUAL "services/runtime"))
    message(FATAL_ERROR "LCM library ${name} belongs in an lcm/ folder, not in ${rel}")
  endif()
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

# The include rule on the whole source tree, at every build (a second's scan).
file(RELATIVE_PATH _cairn_binary_rel ${PROJECT_SOURCE_DIR} ${PROJECT_BINARY_DIR})
add_custom_target(cairn_include_rule ALL
  COMMAND ${CMAKE_COMMAND} -DROOT=${PROJECT_SOURCE_DIR} -DEXCLUDE=${_cairn_binary_rel}
          -P ${CMAKE_CURRENT_LIST_DIR}/CairnIncludeRule.cmake
  COMMENT "include rule: no LCM in core code" VERBATIM)
