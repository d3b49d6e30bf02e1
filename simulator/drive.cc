#include "simulator/drive.h"

#include <algorithm>
#include <cmath>

#include "common/check.h"

namespace cairn::sim {
namespace {

double Approach(double current, double target, double max_step) {
  if (target > current) return std::min(target, current + max_step);
  return std::max(target, current - max_step);
}

}  // namespace

DriveController::DriveController(const common::VelocityLimits& limits, double wheel_radius_m, double track_m,
                                 double watchdog_s)
    : limits_(limits), wheel_radius_m_(wheel_radius_m), track_m_(track_m), watchdog_s_(watchdog_s) {
  CAIRN_THROW_UNLESS(wheel_radius_m > 0.0 && track_m > 0.0 && watchdog_s > 0.0,
                     "drive needs a positive wheel radius, track and watchdog period");
}

CommandVerdict DriveController::SetCommand(double linear_mps, double angular_radps, double now_s) {
  if (!std::isfinite(linear_mps) || !std::isfinite(angular_radps)) return CommandVerdict::kDropped;
  const double v = std::clamp(linear_mps, limits_.min_vel_x_mps, limits_.max_vel_x_mps);
  const double w =
      std::clamp(angular_radps, -limits_.max_vel_theta_radps, limits_.max_vel_theta_radps);
  target_linear_mps_ = v;
  target_angular_radps_ = w;
  last_command_s_ = now_s;
  watchdog_active_ = false;
  return (v != linear_mps || w != angular_radps) ? CommandVerdict::kClamped
                                                 : CommandVerdict::kAccepted;
}

bool DriveController::Update(double now_s, double dt_s) {
  bool stopped_now = false;
  if (!watchdog_active_ && now_s - last_command_s_ > watchdog_s_) {
    watchdog_active_ = true;
    stopped_now = target_linear_mps_ != 0.0 || target_angular_radps_ != 0.0;
    target_linear_mps_ = 0.0;
    target_angular_radps_ = 0.0;
  }
  linear_mps_ = Approach(linear_mps_, target_linear_mps_, limits_.acc_lim_x_mps2 * dt_s);
  angular_radps_ =
      Approach(angular_radps_, target_angular_radps_, limits_.acc_lim_theta_radps2 * dt_s);
  return stopped_now;
}

void DriveController::Halt() {
  target_linear_mps_ = target_angular_radps_ = 0.0;
  linear_mps_ = angular_radps_ = 0.0;
  watchdog_active_ = true;
}

double DriveController::left_wheel_radps() const {
  return (linear_mps_ - 0.5 * angular_radps_ * track_m_) / wheel_radius_m_;
}

double DriveController::right_wheel_radps() const {
  return (linear_mps_ + 0.5 * angular_radps_ * track_m_) / wheel_radius_m_;
}

}  // namespace cairn::sim
