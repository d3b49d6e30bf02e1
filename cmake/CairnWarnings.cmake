# Warning flags for every cairn target (applied through cairn_target_defaults).
set(CAIRN_WARNING_FLAGS -Wall -Wextra -Wpedantic)
if(CAIRN_WERROR)
  list(APPEND CAIRN_WARNING_FLAGS -Werror)
endif()
