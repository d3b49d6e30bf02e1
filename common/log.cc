#include "common/log.h"

#include <sys/time.h>

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>

namespace cairn::common {
namespace {

std::mutex& LogMutex() {
  static std::mutex mutex;
  return mutex;
}

std::string& Tag() {
  static std::string tag = "cairn";
  return tag;
}

std::atomic<int>& Level() {
  static std::atomic<int> level{static_cast<int>(LogLevel::kInfo)};
  return level;
}

const char* LevelName(LogLevel level) {
  switch (level) {
    case LogLevel::kDebug: return "DEBUG";
    case LogLevel::kInfo: return "INFO ";
    case LogLevel::kWarn: return "WARN ";
    case LogLevel::kError: return "ERROR";
  }
  return "?";
}

}  // namespace

void SetLogTag(const std::string& tag) {
  std::lock_guard<std::mutex> lock(LogMutex());
  Tag() = tag;
}

void SetLogLevel(LogLevel level) { Level() = static_cast<int>(level); }

std::optional<LogLevel> LogLevelFromName(const std::string& name) {
  if (name == "debug") return LogLevel::kDebug;
  if (name == "info") return LogLevel::kInfo;
  if (name == "warn") return LogLevel::kWarn;
  if (name == "error") return LogLevel::kError;
  return std::nullopt;
}
LogLevel GetLogLevel() { return static_cast<LogLevel>(Level().load()); }

void VLog(LogLevel level, const char* format, va_list args) {
  if (static_cast<int>(level) < Level().load()) return;
  char message[2048];
  std::vsnprintf(message, sizeof(message), format, args);
  timeval tv{};
  gettimeofday(&tv, nullptr);
  std::tm tm{};
  gmtime_r(&tv.tv_sec, &tm);
  char stamp[32];
  std::strftime(stamp, sizeof(stamp), "%Y-%m-%dT%H:%M:%S", &tm);
  std::lock_guard<std::mutex> lock(LogMutex());
  std::fprintf(stderr, "%s.%03dZ %s %s %s\n", stamp, static_cast<int>(tv.tv_usec / 1000),
               Tag().c_str(), LevelName(level), message);
  std::fflush(stderr);
}

void Log(LogLevel level, const char* format, ...) {
  va_list args;
  va_start(args, format);
  VLog(level, format, args);
  va_end(args);
}

bool RateLimiter::Allow(int64_t* suppressed) {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto now = std::chrono::steady_clock::now();
  if (!ever_ || std::chrono::duration<double>(now - last_).count() >= interval_s_) {
    if (suppressed != nullptr) *suppressed = suppressed_;
    suppressed_ = 0;
    last_ = now;
    ever_ = true;
    return true;
  }
  ++suppressed_;
  return false;
}

}  // namespace cairn::common
