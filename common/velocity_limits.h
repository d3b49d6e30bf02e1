#pragma once

#include "common/robot_profile.h"

/// @file
/// A base-frame velocity command and the limits a robot profile puts on it: the one struct the
/// simulator's drive and the navigator's planners both read.

namespace cairn::common {

/// A base-frame velocity command: forward speed and yaw rate.
struct Velocity {
  double linear_mps{0.0};
  double angular_radps{0.0};
  bool operator==(const Velocity& o) const {
    return linear_mps == o.linear_mps && angular_radps == o.angular_radps;
  }
};

/// Velocity and acceleration limits (Nav2 vocabulary), from a robot profile.
struct VelocityLimits {
  double max_vel_x_mps{0.5};
  double min_vel_x_mps{-0.1};  ///< most negative forward speed, <= 0
  double max_vel_theta_radps{1.0};
  double acc_lim_x_mps2{0.8};
  double acc_lim_theta_radps2{1.5};

  static VelocityLimits FromProfile(const RobotProfile& profile);
  /// @throws std::invalid_argument naming the bad field.
  void Validate() const;
  /// True when `next` may follow `previous` after `period_s` (within `slack` of each limit).
  bool Allows(const Velocity& previous, const Velocity& next, double period_s,
              double slack = 1e-9) const;
};

}  // namespace cairn::common
