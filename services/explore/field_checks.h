#pragma once

#include <sstream>
#include <stdexcept>

/// @file
/// Checks on the fields of the scan analysis's inputs and params (internal to cairn::explore).

namespace cairn::explore::internal {

/// Throws std::invalid_argument "<field> <rule>, got <got>".
template <typename T>
[[noreturn]] void Fail(const char* field, const char* rule, const T& got) {
  std::ostringstream msg;
  msg << field << " " << rule << ", got " << got;
  throw std::invalid_argument(msg.str());
}

/// Throws std::invalid_argument "<field> <rule>, got <got>" unless ok.
template <typename T>
void Require(bool ok, const char* field, const char* rule, const T& got) {
  if (!ok) Fail(field, rule, got);
}

}  // namespace cairn::explore::internal
