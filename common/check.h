#pragma once

#include <sstream>
#include <stdexcept>
#include <string>

/// @file
/// Error-handling macros (house style section 8.4).
///
/// CAIRN_DEMAND(cond): a broken internal invariant (a bug). Always on; prints the expression,
/// file and line, and aborts.
/// CAIRN_THROW_UNLESS(cond, msg): bad input to a library API. Throws std::invalid_argument
/// with the message and the failed expression.

namespace cairn::common::internal {
[[noreturn]] void Abort(const char* condition, const char* file, int line, const std::string& what);
[[noreturn]] void ThrowInvalidArgument(const char* condition, const std::string& what);
}  // namespace cairn::common::internal

#define CAIRN_DEMAND(cond)                                                        \
  do {                                                                            \
    if (!(cond)) ::cairn::common::internal::Abort(#cond, __FILE__, __LINE__, ""); \
  } while (0)

#define CAIRN_THROW_UNLESS(cond, msg)                                        \
  do {                                                                       \
    if (!(cond)) {                                                           \
      std::ostringstream cairn_msg_stream_;                                  \
      cairn_msg_stream_ << msg;                                              \
      ::cairn::common::internal::ThrowInvalidArgument(#cond, cairn_msg_stream_.str()); \
    }                                                                        \
  } while (0)
