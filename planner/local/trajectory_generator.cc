#include "planner/local/trajectory_generator.h"

#include <algorithm>
#include <cmath>

#include "common/check.h"

namespace cairn::planner {

using common::Pose2;

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

namespace {

// One exact unicycle step of `dt` at constant (v, w).
void Advance(double v, double w, double dt, Pose2* p) {
  const double s0 = std::sin(p->yaw_rad), c0 = std::cos(p->yaw_rad);
  if (std::abs(w) < 1e-9) {
    p->x_m += v * dt * c0;
    p->y_m += v * dt * s0;
  } else {
    const double yaw = p->yaw_rad + w * dt;
    const double r = v / w;
    p->x_m += r * (std::sin(yaw) - s0);
    p->y_m -= r * (std::cos(yaw) - c0);
    p->yaw_rad = yaw;
  }
}

double StepToward(double current, double target, double max_step) {
  return current + std::clamp(target - current, -max_step, max_step);
}

}  // namespace

bool TrajectoryGenerator::TrackPath(const Pose2& start, const Velocity& last_command,
                                    const Path& path, size_t first_segment,
                                    const TrackingParams& tracking, const CostMap* map,
                                    Trajectory* out) const {
  if (path.size() < 2) return false;
  const double period = params_.control_period_s;
  const int per_step = std::max(1, static_cast<int>(std::ceil(params_.sim_step_s / period - 1e-9)));
  size_t segment = std::min(first_segment, path.size() - 2);
  // What pure pursuit asks for at a pose.
  auto desired = [&](const Pose2& p) {
    const PathProjection proj = path.Project(p.position(), segment, segment + 40);
    segment = proj.segment;
    const double left_m = path.length_m() - proj.arc_length_m;
    const common::Vector2 aim = path.PoseAt(proj.arc_length_m + tracking.lookahead_m).position();
    const common::Vector2 d = aim - p.position();
    const double c = std::cos(p.yaw_rad), s = std::sin(p.yaw_rad);
    const double dx = c * d.x() + s * d.y();
    const double dy = -s * d.x() + c * d.y();
    const double alpha = std::atan2(dy, dx);
    Velocity want;
    if (d.norm() < 1e-6) return want;
    if (std::abs(alpha) > tracking.turn_in_place_rad) {
      want.angular_radps = std::copysign(limits_.max_vel_theta_radps, alpha);
      return want;
    }
    const double curvature = 2.0 * dy / d.squaredNorm();
    // Regulation: the tightest of curvature, proximity and the path's end.
    double scale = std::min(1.0, left_m / 1.0);
    if (std::abs(curvature) > 1e-9) {
      scale = std::min(scale, (1.0 / std::abs(curvature)) / tracking.min_radius_m);
    }
    if (map != nullptr && tracking.slow_distance_m > 0.0) {
      const double beyond_m =
          map->SmoothClearanceAt(p.position()) - map->footprint().inscribed_radius_m();
      if (std::isfinite(beyond_m)) scale = std::min(scale, beyond_m / tracking.slow_distance_m);
    }
    double v = limits_.max_vel_x_mps * std::clamp(scale, tracking.min_speed_fraction, 1.0);
    if (std::abs(curvature) > 1e-9) {
      v = std::min(v, limits_.max_vel_theta_radps / std::abs(curvature));
    }
    want.linear_mps = v;
    want.angular_radps = v * curvature;
    return want;
  };
  const Velocity first = desired(start);
  const Velocity command = Toward(last_command, first);
  out->velocity = command;
  out->target = first;
  out->poses.resize(static_cast<size_t>(steps_));
  Pose2 p = start;
  double v = command.linear_mps, w = command.angular_radps;
  double t = 0.0, peak_v = std::abs(v), peak_w = std::abs(w);
  for (int k = 0; k < steps_; ++k) {
    const double t_end = std::min((k + 1) * params_.sim_step_s, params_.sim_time_s);
    const double h = (t_end - t) / per_step;
    for (int j = 0; j < per_step; ++j) {
      if (t >= period - 1e-9) {
        const Velocity want = desired(p);
        const double v_next = StepToward(v, want.linear_mps, limits_.acc_lim_x_mps2 * h);
        const double w_next = StepToward(w, want.angular_radps, limits_.acc_lim_theta_radps2 * h);
        Advance(0.5 * (v + v_next), 0.5 * (w + w_next), h, &p);
        v = v_next;
        w = w_next;
        peak_v = std::max(peak_v, std::abs(v));
        peak_w = std::max(peak_w, std::abs(w));
      } else {
        Advance(v, w, h, &p);
      }
      t += h;
    }
    p.yaw_rad = common::WrapAngle(p.yaw_rad);
    out->poses[static_cast<size_t>(k)] = p;
  }
  out->peak_linear_mps = peak_v;
  out->peak_angular_radps = peak_w;
  return true;
}

void TrajectoryGenerator::Simulate(const Pose2& start, const Velocity& velocity,
                                   Trajectory* out) const {
  out->velocity = velocity;
  out->target = velocity;
  out->peak_linear_mps = std::abs(velocity.linear_mps);
  out->peak_angular_radps = std::abs(velocity.angular_radps);
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
