#pragma once

#include <chrono>
#include <cstdarg>
#include <cstdint>
#include <mutex>
#include <optional>
#include <string>

/// @file
/// One-line logging for processes: "2026-11-21T10:00:00.123Z cairn-sim[rover1] INFO  message".
/// Processes log notable events, never one line per message; RateLimiter helps with repeated
/// events (a flood of bad messages becomes one line per interval with a count).

namespace cairn::common {

enum class LogLevel { kDebug = 0, kInfo, kWarn, kError };

/// Sets the process tag printed on every line (call once in main).
void SetLogTag(const std::string& tag);
/// Lines below this level are dropped (default kInfo; processes take CAIRN_LOG_LEVEL=debug,
/// info, warn or error from the environment: runtime::Node, or the main of a process without
/// one).
void SetLogLevel(LogLevel level);
/// "debug", "info", "warn", "error"; nullopt for anything else.
std::optional<LogLevel> LogLevelFromName(const std::string& name);
LogLevel GetLogLevel();

/// printf-style; writes one line to stderr under a lock.
void Log(LogLevel level, const char* format, ...) __attribute__((format(printf, 2, 3)));
void VLog(LogLevel level, const char* format, va_list args);

/// Lets an event through at most once per interval and counts what it suppressed.
class RateLimiter {
 public:
  explicit RateLimiter(double interval_s = 5.0) : interval_s_(interval_s) {}
  RateLimiter(const RateLimiter&) = delete;
  RateLimiter& operator=(const RateLimiter&) = delete;

  /// True when the caller should log now; `suppressed` receives how many events were
  /// swallowed since the last line.
  bool Allow(int64_t* suppressed);

 private:
  double interval_s_;
  std::mutex mutex_;
  std::chrono::steady_clock::time_point last_{};
  bool ever_{false};
  int64_t suppressed_{0};
};

}  // namespace cairn::common

#define CAIRN_LOG_DEBUG(...) ::cairn::common::Log(::cairn::common::LogLevel::kDebug, __VA_ARGS__)
#define CAIRN_LOG_INFO(...) ::cairn::common::Log(::cairn::common::LogLevel::kInfo, __VA_ARGS__)
#define CAIRN_LOG_WARN(...) ::cairn::common::Log(::cairn::common::LogLevel::kWarn, __VA_ARGS__)
#define CAIRN_LOG_ERROR(...) ::cairn::common::Log(::cairn::common::LogLevel::kError, __VA_ARGS__)
