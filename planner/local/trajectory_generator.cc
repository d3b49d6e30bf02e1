#include "planner/local/trajectory_generator.h"

#include <algorithm>
#include <cmath>

#include "common/check.h"

namespace cairn::planner {

using common::Pose2;

VelocityLimits VelocityLimits::FromProfile(const common::RobotProfile& profile) {
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

void TrajectoryGeneratorParams::Validate() const {
  CAIRN_THROW_UNLESS(vx_samples >= 1, "vx_samples must be at least 1");
  CAIRN_THROW_UNLESS(vtheta_samples >= 1, "vtheta_samples must be at least 1");
  CAIRN_THROW_UNLESS(sim_time_s > 0.0, "sim_time_s must be positive");
  CAIRN_THROW_UNLESS(sim_step_s > 0.0 && sim_step_s <= sim_time_s,
                     "sim_step_s must lie in (0, sim_time_s]");
  CAIRN_THROW_UNLESS(control_period_s > 0.0, "control_period_s must be positive");
}

TrajectoryGenerator::TrajectoryGenerator(const VelocityLimits& limits,
                                         const TrajectoryGeneratorParams& params)
    : limits_(limits), params_(params) {
  limits_.Validate();
  params_.Validate();
  steps_ = static_cast<int>(std::ceil(params_.sim_time_s / params_.sim_step_s - 1e-9));
}

namespace {

// [current - step, current + step] clipped to [lo, hi]; when current lies outside [lo, hi] the
// window collapses onto the reachable edge.
void Axis(double current, double step, double lo, double hi, double* out_lo, double* out_hi) {
  *out_lo = std::clamp(current - step, lo, hi);
  *out_hi = std::clamp(current + step, lo, hi);
}

std::vector<double> Spread(double lo, double hi, int n) {
  std::vector<double> out;
  if (n <= 1 || hi - lo < 1e-12) {
    out.push_back(n <= 1 ? 0.5 * (lo + hi) : lo);
    if (lo <= 0.0 && hi >= 0.0) out.back() = 0.0;
    return out;
  }
  out.reserve(n);
  for (int i = 0; i < n; ++i) out.push_back(lo + (hi - lo) * i / (n - 1));
  // Snap the sample nearest to zero onto zero when the window holds zero.
  if (lo <= 0.0 && hi >= 0.0) {
    auto nearest = std::min_element(out.begin(), out.end(),
                                    [](double a, double b) { return std::abs(a) < std::abs(b); });
    *nearest = 0.0;
  }
  return out;
}

}  // namespace

DynamicWindow TrajectoryGenerator::Window(const Velocity& last_command) const {
  DynamicWindow w;
  const double dt = params_.control_period_s;
  Axis(last_command.linear_mps, limits_.acc_lim_x_mps2 * dt, limits_.min_vel_x_mps,
       limits_.max_vel_x_mps, &w.min_linear_mps, &w.max_linear_mps);
  Axis(last_command.angular_radps, limits_.acc_lim_theta_radps2 * dt, -limits_.max_vel_theta_radps,
       limits_.max_vel_theta_radps, &w.min_angular_radps, &w.max_angular_radps);
  return w;
}

std::vector<Velocity> TrajectoryGenerator::Samples(const Velocity& last_command) const {
  const DynamicWindow w = Window(last_command);
  const auto vs = Spread(w.min_linear_mps, w.max_linear_mps, params_.vx_samples);
  const auto ws = Spread(w.min_angular_radps, w.max_angular_radps, params_.vtheta_samples);
  std::vector<Velocity> out;
  out.reserve(vs.size() * ws.size());
  for (double v : vs) {
    for (double omega : ws) out.push_back({v, omega});
  }
  return out;
}

Velocity TrajectoryGenerator::Brake(const Velocity& last_command) const {
  const DynamicWindow w = Window(last_command);
  return {std::clamp(0.0, w.min_linear_mps, w.max_linear_mps),
          std::clamp(0.0, w.min_angular_radps, w.max_angular_radps)};
}

Velocity TrajectoryGenerator::Toward(const Velocity& last_command, const Velocity& target) const {
  const DynamicWindow w = Window(last_command);
  const double v = std::isfinite(target.linear_mps) ? target.linear_mps : 0.0;
  const double omega = std::isfinite(target.angular_radps) ? target.angular_radps : 0.0;
  return {std::clamp(v, w.min_linear_mps, w.max_linear_mps),
          std::clamp(omega, w.min_angular_radps, w.max_angular_radps)};
}

void TrajectoryGenerator::Simulate(const Pose2& start, const Velocity& velocity,
                                   Trajectory* out) const {
  out->velocity = velocity;
  out->poses.resize(static_cast<size_t>(steps_));
  const double v = velocity.linear_mps;
  const double w = velocity.angular_radps;
  const double s0 = std::sin(start.yaw_rad);
  const double c0 = std::cos(start.yaw_rad);
  for (int k = 0; k < steps_; ++k) {
    const double t = std::min((k + 1) * params_.sim_step_s, params_.sim_time_s);
    const double yaw = start.yaw_rad + w * t;
    Pose2& p = out->poses[static_cast<size_t>(k)];
    if (std::abs(w) < 1e-9) {
      p.x_m = start.x_m + v * t * c0;
      p.y_m = start.y_m + v * t * s0;
    } else {
      const double r = v / w;
      const double s1 = std::sin(yaw), c1 = std::cos(yaw);
      p.x_m = start.x_m + r * (s1 - s0);
      p.y_m = start.y_m - r * (c1 - c0);
    }
    p.yaw_rad = common::WrapAngle(yaw);
  }
}

}  // namespace cairn::planner
