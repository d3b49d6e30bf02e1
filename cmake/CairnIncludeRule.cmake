# The include rule (ARCHITECTURE rule 1), as a script anyone can run:
#   cmake -DROOT=<source tree> [-DEXCLUDE=<folder under ROOT>] -P cmake/CairnIncludeRule.cmake
# No file outside services/runtime/, an lcm/ folder, a *_main.cc, tests/ and bench/ includes
# <lcm/...> or a generated "cairn/..." header (lcmt_* types, the type registry), and none of them
# reads the environment (getenv: folders and settings are passed in by main, ARCHITECTURE rule 3).
# Prints every offending line and fails; the build runs it on the whole tree (target
# cairn_include_rule).
if(NOT ROOT)
  message(FATAL_ERROR "usage: cmake -DROOT=<dir> -P CairnIncludeRule.cmake")
endif()
cmake_policy(SET CMP0009 NEW)  # do not follow symbolic links
get_filename_component(root "${ROOT}" ABSOLUTE)
# Top-level folders other than build trees, tests, benches and hidden ones; then their files.
file(GLOB tops RELATIVE "${root}" "${root}/*")
set(files)
foreach(top IN LISTS tops)
  if(top MATCHES "^(tests|bench|build[^/]*|\\..*)$" OR (EXCLUDE AND top STREQUAL EXCLUDE))
    continue()
  endif()
  if(IS_DIRECTORY "${root}/${top}")
    file(GLOB_RECURSE found RELATIVE "${root}" "${root}/${top}/*.h" "${root}/${top}/*.hpp"
         "${root}/${top}/*.cc" "${root}/${top}/*.cpp")
    list(APPEND files ${found})
  elseif(top MATCHES "\\.(h|hpp|cc|cpp)$")
    list(APPEND files ${top})
  endif()
endforeach()
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
  file(STRINGS "${root}/${rel}" hits REGEX "(^|[^A-Za-z0-9_])(std::)?(secure_)?getenv[ \t]*\\(")
  foreach(line IN LISTS hits)
    string(STRIP "${line}" line)
    list(APPEND bad "${rel}: ${line}")
  endforeach()
endforeach()
if(bad)
  list(JOIN bad "\n  " text)
  message(FATAL_ERROR "include rule: core code may not include LCM nor read the environment "
          "(move the file to the component's lcm/ folder, keep LCM out of it, or pass the value "
          "in from main):\n  ${text}")
endif()
list(LENGTH files count)
message(STATUS "include rule: ${count} files checked, no LCM include and no getenv in core code")
