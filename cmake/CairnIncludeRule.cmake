# The include rule (ARCHITECTURE rule 1), as a script anyone can run:
#   cmake -DROOT=<source tree> [-DEXCLUDE=<folder under ROOT>] -P cmake/CairnIncludeRule.cmake
# No file outside services/runtime/, an lcm/ folder, a *_main.cc, tests/ and bench/ includes
# <lcm/...> or a generated "cairn/..." header (lcmt_* types, the type registry). Prints every
# offending line and fails; the build runs it on the whole tree (target cairn_include_rule).
if(NOT ROOT)
  message(FATAL_ERROR "usage: cmake -DROOT=<dir> -P CairnIncludeRule.cmake")
endif()
get_filename_component(root "${ROOT}" ABSOLUTE)
file(GLOB_RECURSE files RELATIVE "${root}" "${root}/*.h" "${root}/*.hpp" "${root}/*.cc"
     "${root}/*.cpp")
set(bad)
foreach(rel IN LISTS files)
  if(rel MATCHES "^(tests|bench|build[^/]*)/" OR rel MATCHES "(^|/)\\.")
    continue()
  endif()
  if(EXCLUDE AND rel MATCHES "^${EXCLUDE}/")
    continue()
  endif()
  if(rel MATCHES "^services/runtime/" OR rel MATCHES "(^|/)lcm/" OR rel MATCHES "_main\\.cc$")
    continue()
  endif()
  file(STRINGS "${root}/${rel}" hits REGEX "^[ \t]*#[ \t]*include[ \t]*[<\"](lcm/|cairn/)")
  foreach(line IN LISTS hits)
    string(STRIP "${line}" line)
    list(APPEND bad "${rel}: ${line}")
  endforeach()
endforeach()
if(bad)
  list(JOIN bad "\n  " text)
  message(FATAL_ERROR "include rule: core code may not include LCM (move the file to the "
          "component's lcm/ folder, or keep LCM out of it):\n  ${text}")
endif()
list(LENGTH files count)
message(STATUS "include rule: ${count} files checked, no LCM include in core code")
