#pragma once

#include <cstdint>
#include <deque>
#include <optional>

#include "common/types.h"

/// @file
/// PoseBuffer: recent timestamped poses of one robot, looked up at a sensor's time.

namespace cairn::mapping {

class PoseBuffer {
 public:
  /// @param max_age_s samples older than this behind the newest are forgotten.
  explicit PoseBuffer(double max_age_s = 5.0)
      : max_age_us_(static_cast<int64_t>(max_age_s * 1e6)) {}

  /// Adds a sample. Samples out of time order are inserted in place; a sample with the time
  /// of an existing one replaces it. Non-finite poses are refused (returns false).
  bool Add(int64_t utime, const common::Pose3& pose);

  /// The pose at `utime`: interpolated (linear position, slerp orientation) between the
  /// samples around it when both lie within `max_gap_s` of it, else the nearest sample within
  /// `max_gap_s`; nullopt when no sample is that close.
  std::optional<common::Pose3> At(int64_t utime, double max_gap_s) const;

  /// The newest sample.
  std::optional<std::pair<int64_t, common::Pose3>> Latest() const;
  bool empty() const { return samples_.empty(); }
  size_t size() const { return samples_.size(); }
  void Clear() { samples_.clear(); }

 private:
  int64_t max_age_us_;
  std::deque<std::pair<int64_t, common::Pose3>> samples_;  // ascending time
};

}  // namespace cairn::mapping
