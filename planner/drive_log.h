#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "common/types.h"
#include "common/velocity_limits.h"
#include "planner/local/dwa_planner.h"

/// @file
/// DriveLog: what the navigator's driving did since its no-progress timer last restarted
/// (cycles turning toward the path, the DWA's choices, speeds and the critics that rejected
/// most), told in the no-progress message so that a robot standing still can be diagnosed.

namespace cairn::planner {

class DriveLog {
 public:
  /// Forgets everything (the no-progress timer restarted).
  void Clear() { *this = DriveLog(); }
  /// One cycle spent turning in place toward the path.
  void CountTurn() { ++turning_; }
  /// One DWA cycle, driving toward `carrot` (world).
  void Record(const DwaResult& result, const common::Vector2& carrot);

  /// " (moved 0.05 m; 3 cycles turning toward the path, 40 DWA cycles at a mean 0.01 m/s,
  /// 0.20 rad/s, 2 without a valid sample; rejected per cycle: clearance 120.00/400, ...; last
  /// choice (v, w) scored speed 0.40, ...; best forward (v, w) scored ...; at (x, y, yaw),
  /// carrot (x, y), 3.20 m of path left)". `critic_names` in the DWA's order; the part from
  /// "at" on only with a `pose`.
  std::string Describe(double moved_m, const std::vector<std::string>& critic_names,
                       const std::optional<common::Pose2>& pose, double path_left_m) const;

  int turning() const { return turning_; }
  int dwa_cycles() const { return dwa_; }
  int invalid_cycles() const { return dwa_invalid_; }
  const std::vector<int64_t>& rejections() const { return rejections_; }

 private:
  int turning_{0};      // cycles turning in place toward the path
  int dwa_{0};          // cycles the DWA chose the command
  int dwa_invalid_{0};  // ... of which no sample was valid
  int samples_{0};      // samples in the last DWA cycle
  double sum_v_mps_{0.0};
  double sum_abs_w_radps_{0.0};
  std::vector<int64_t> rejections_;  // per critic, over the window
  common::Velocity last_best_;       // the last DWA cycle's choice ...
  std::vector<double> last_values_;  // ... and its scale × value per critic
  bool has_forward_{false};          // the last cycle's best forward sample ...
  common::Velocity last_forward_;
  std::vector<double> last_forward_values_;
  common::Vector2 carrot_{common::Vector2::Zero()};
};

}  // namespace cairn::planner
