#include "common/velocity_limits.h"

#include <cmath>

#include "common/check.h"

namespace cairn::common {

VelocityLimits VelocityLimits::FromProfile(const RobotProfile& profile) {
  VelocityLimits l;
  l.max_vel_x_mps = profile.max_vel_x_mps;
  l.min_vel_x_mps = profile.min_vel_x_mps;
  l.max_vel_theta_radps = profile.max_vel_theta_radps;
  l.acc_lim_x_mps2 = profile.acc_lim_x_mps2;
  l.acc_lim_theta_radps2 = profile.acc_lim_theta_radps2;
  return l;
}

void VelocityLimits::Validate() const {
  CAIRN_THROW_UNLESS(std::isfinite(max_vel_x_mps) && max_vel_x_mps > 0.0,
                     "max_vel_x_mps must be positive, got " << max_vel_x_mps);
  CAIRN_THROW_UNLESS(std::isfinite(min_vel_x_mps) && min_vel_x_mps <= 0.0,
                     "min_vel_x_mps must be <= 0, got " << min_vel_x_mps);
  CAIRN_THROW_UNLESS(std::isfinite(max_vel_theta_radps) && max_vel_theta_radps > 0.0,
                     "max_vel_theta_radps must be positive, got " << max_vel_theta_radps);
  CAIRN_THROW_UNLESS(std::isfinite(acc_lim_x_mps2) && acc_lim_x_mps2 > 0.0,
                     "acc_lim_x_mps2 must be positive, got " << acc_lim_x_mps2);
  CAIRN_THROW_UNLESS(std::isfinite(acc_lim_theta_radps2) && acc_lim_theta_radps2 > 0.0,
                     "acc_lim_theta_radps2 must be positive, got " << acc_lim_theta_radps2);
}

bool VelocityLimits::Allows(const Velocity& previous, const Velocity& next, double period_s,
                            double slack) const {
  return next.linear_mps <= max_vel_x_mps + slack && next.linear_mps >= min_vel_x_mps - slack &&
         std::abs(next.angular_radps) <= max_vel_theta_radps + slack &&
         std::abs(next.linear_mps - previous.linear_mps) <= acc_lim_x_mps2 * period_s + slack &&
         std::abs(next.angular_radps - previous.angular_radps) <=
             acc_lim_theta_radps2 * period_s + slack;
}

}  // namespace cairn::common
