#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "common/status.h"
#include "common/types.h"

/// @file
/// Planned against driven X(t), Y(t), as seed 004 plots them: at a fixed period of sim time,
/// where the odometry and the ground truth put the robot and where the planner's latest path
/// meant it to be (the point of that path nearest the true position). Pure: the mission feeds
/// it what it hears; WriteCsv writes the table.

namespace cairn::mission {

struct TrackSample {
  double t_s{0.0};  ///< sim time since the first sample
  common::Vector2 truth_m{common::Vector2::Zero()};
  std::optional<common::Vector2> odom_m;     ///< the latest odometry, when any came
  std::optional<common::Vector2> planned_m;  ///< nearest point of the latest path, when any
};

class TrackLog {
 public:
  /// One row every `period_s` of sim time, at most `max_samples` (later ones are counted).
  explicit TrackLog(double period_s = 0.5, size_t max_samples = 100000);

  /// The latest plan (world frame). A path with a non-finite point is refused (kept: the one
  /// before); an empty one clears the plan.
  common::Status OnPath(const std::vector<common::Vector2>& path_m);
  void OnOdometry(const common::Vector2& position_m);
  /// A ground-truth pose at `utime`: adds a row when a period has passed since the last.
  void OnTruth(int64_t utime, const common::Vector2& position_m);

  const std::vector<TrackSample>& samples() const { return samples_; }
  int64_t dropped() const { return dropped_; }

  /// Writes "t_s,odom_x_m,odom_y_m,truth_x_m,truth_y_m,planned_x_m,planned_y_m" and a row per
  /// sample (empty fields where there was no odometry or plan yet) to `path`.
  common::Status WriteCsv(const std::string& path) const;

 private:
  double period_s_;
  size_t max_samples_;
  std::vector<common::Vector2> path_m_;
  std::optional<common::Vector2> odom_m_;
  std::optional<int64_t> first_utime_;
  int64_t last_row_utime_{0};
  std::vector<TrackSample> samples_;
  int64_t dropped_{0};
};

/// The point of the polyline `path_m` nearest `p` (the single point of a one-point path).
/// @pre path_m is not empty.
common::Vector2 NearestOnPath(const std::vector<common::Vector2>& path_m, const common::Vector2& p);

}  // namespace cairn::mission
