#pragma once

#include <optional>
#include <string>
#include <utility>

#include "common/check.h"

namespace cairn::common {

/// Expected outcomes of an operation (house style 8.4: outcomes are values, bugs abort).
enum class StatusCode {
  kOk = 0,
  kInvalidArgument,
  kNotFound,
  kAlreadyExists,
  kCorrupt,
  kUnavailable,
  kTimedOut,
  kCancelled,
  kResourceExhausted,
  kInternal,
  kPermissionDenied,  ///< an operation this process's configuration does not allow
};

/// Human-readable name of a status code ("NOT_FOUND").
const char* StatusCodeName(StatusCode code);

/// A status code and a message saying what was wrong.
class Status {
 public:
  Status() = default;
  Status(StatusCode code, std::string message) : code_(code), message_(std::move(message)) {}
  static Status Ok() { return Status(); }

  bool ok() const { return code_ == StatusCode::kOk; }
  StatusCode code() const { return code_; }
  const std::string& message() const { return message_; }
  /// "NOT_FOUND: no map 'x'".
  std::string ToString() const;

 private:
  StatusCode code_{StatusCode::kOk};
  std::string message_;
};

inline Status InvalidArgumentError(std::string m) {
  return {StatusCode::kInvalidArgument, std::move(m)};
}
inline Status NotFoundError(std::string m) { return {StatusCode::kNotFound, std::move(m)}; }
inline Status CorruptError(std::string m) { return {StatusCode::kCorrupt, std::move(m)}; }
inline Status InternalError(std::string m) { return {StatusCode::kInternal, std::move(m)}; }
inline Status UnavailableError(std::string m) { return {StatusCode::kUnavailable, std::move(m)}; }
inline Status AlreadyExistsError(std::string m) {
  return {StatusCode::kAlreadyExists, std::move(m)};
}
inline Status PermissionDeniedError(std::string m) {
  return {StatusCode::kPermissionDenied, std::move(m)};
}
inline Status ResourceExhaustedError(std::string m) {
  return {StatusCode::kResourceExhausted, std::move(m)};
}

/// A value or the status explaining why there is none (abseil StatusOr, reduced).
template <typename T>
class Result {
 public:
  Result(T value) : value_(std::move(value)) {}         // NOLINT: implicit by design
  Result(Status status) : status_(std::move(status)) {  // NOLINT: implicit by design
    CAIRN_DEMAND(!status_.ok());
  }

  bool ok() const { return status_.ok(); }
  const Status& status() const { return status_; }
  const T& value() const& {
    CAIRN_DEMAND(ok());
    return *value_;
  }
  T& value() & {
    CAIRN_DEMAND(ok());
    return *value_;
  }
  T&& value() && {
    CAIRN_DEMAND(ok());
    return std::move(*value_);
  }
  const T& operator*() const& { return value(); }
  const T* operator->() const { return &value(); }
  T* operator->() { return &value(); }

 private:
  Status status_;
  std::optional<T> value_;
};

}  // namespace cairn::common
