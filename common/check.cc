#include "common/check.h"

#include <cstdio>
#include <cstdlib>

namespace cairn::common::internal {

void Abort(const char* condition, const char* file, int line, const std::string& what) {
  std::fprintf(stderr, "cairn: internal error: %s failed at %s:%d %s\n", condition, file, line,
               what.c_str());
  std::fflush(stderr);
  std::abort();
}

void ThrowInvalidArgument(const char* condition, const std::string& what) {
  throw std::invalid_argument(what.empty() ? std::string("invalid argument: ") + condition : what);
}

}  // namespace cairn::common::internal
