# Run as `cmake -DHEADER=<file> -P BoundLcmDecode.cmake` after lcm-gen: bounds the generated
# C++ decoder against what a message says about itself (ARCHITECTURE.md rule 8).
#
# lcm-gen 1.3.1's decoders size every variable-length array from the count on the wire before
# they check that the bytes are there (a 60-byte message claiming 67 million entries allocates
# them), resize with a negative count (std::length_error, thrown through liblcm's C dispatch),
# and take a string length of 0 or less as a length of SIZE_MAX. This rewrites, in place:
# - `this->X.resize(this->N);` to refuse (return -1) a count below 0 or above the bytes that
#   remain: every element of every cairn type takes at least one byte on the wire, so a count
#   the message cannot hold is a malformed message, and what is allocated is bounded by the
#   message's size;
# - `if(__L > maxlen - pos) return -1;` (a string's length, NUL included) to refuse L < 1 too.
# The result is checked: a header with a resize left unguarded fails the build.
if(NOT HEADER)
  message(FATAL_ERROR "BoundLcmDecode.cmake needs -DHEADER=<generated header>")
endif()
file(READ "${HEADER}" text)
string(REGEX REPLACE
  "([ ]*)this->([A-Za-z0-9_]+)\\.resize\\(this->([A-Za-z0-9_]+)\\);"
  "\\1if (this->\\3 < 0 || this->\\3 > maxlen - pos) return -1;  // cairn: bounded\n\\1this->\\2.resize(this->\\3);"
  text "${text}")
string(REGEX REPLACE
  "if\\((__[A-Za-z0-9_]+) > maxlen - pos\\) return -1;"
  "if(\\1 < 1 || \\1 > maxlen - pos) return -1;  // cairn: bounded"
  text "${text}")
# Every resize must now follow its guard.
string(REGEX REPLACE "// cairn: bounded\n[ ]*this->[A-Za-z0-9_]+\\.resize\\(" "" rest "${text}")
if(rest MATCHES "\\.resize\\(")
  message(FATAL_ERROR "${HEADER}: a resize is left without its bound")
endif()
file(WRITE "${HEADER}" "${text}")
