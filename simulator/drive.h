#pragma once

#include "common/velocity_limits.h"

/// @file
/// DriveController: turns velocity commands (v, w) into wheel speed targets, the way a robot's
/// motor firmware does: commands with NaN or infinite values are refused, commands beyond the
/// profile's velocity limits are clamped, speed changes are ramped within the acceleration
/// limits, and a watchdog stops the wheels when no command arrived for a while (sim time).

namespace cairn::sim {

enum class CommandVerdict {
  kAccepted,  ///< taken as given
  kClamped,   ///< taken, limited to the profile's velocity limits
  kDropped,   ///< refused: not finite
};

class DriveController {
 public:
  /// @param track_m the kinematic track: the distance between left and right wheel contact
  ///        lines that makes (v, w) mixing match the real turning rate (larger than the
  ///        geometric track for skid steer).
  /// @throws std::invalid_argument for a non-positive radius, track or watchdog period.
  DriveController(const common::VelocityLimits& limits, double wheel_radius_m, double track_m,
                  double watchdog_s = 0.5);

  /// A velocity command at sim time now_s.
  CommandVerdict SetCommand(double linear_mps, double angular_radps, double now_s);
  /// Advances the ramp by dt_s at sim time now_s. Returns true once when the watchdog stops a
  /// moving robot.
  bool Update(double now_s, double dt_s);
  /// Stops at once (reset, pause of a robot): targets and ramp go to zero.
  void Halt();

  double left_wheel_radps() const;
  double right_wheel_radps() const;
  /// The ramped (v, w) the wheels are following now.
  double linear_mps() const { return linear_mps_; }
  double angular_radps() const { return angular_radps_; }
  /// The latest accepted (clamped) command.
  double target_linear_mps() const { return target_linear_mps_; }
  double target_angular_radps() const { return target_angular_radps_; }
  /// True while no command arrived within the watchdog period.
  bool watchdog_active() const { return watchdog_active_; }

 private:
  common::VelocityLimits limits_;
  double wheel_radius_m_;
  double track_m_;
  double watchdog_s_;
  double last_command_s_{-1e300};
  double target_linear_mps_{0.0};
  double target_angular_radps_{0.0};
  double linear_mps_{0.0};
  double angular_radps_{0.0};
  bool watchdog_active_{true};
};

}  // namespace cairn::sim
