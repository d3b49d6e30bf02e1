#include "planner/local/critics.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace cairn::planner {

using common::Pose2;
using common::Vector2;

namespace {

// Below these magnitudes a command counts as "not moving" on that axis.
constexpr double kLinearEps = 0.01;   // m/s
constexpr double kAngularEps = 0.02;  // rad/s

int Sign(double x, double eps) { return x > eps ? 1 : (x < -eps ? -1 : 0); }

}  // namespace

double ClearanceCritic::Proximity(double clearance_m, double inscribed_m) const {
  if (params_.inflation_m <= 0.0 || !std::isfinite(clearance_m)) return 0.0;
  return std::clamp(1.0 - (clearance_m - inscribed_m) / params_.inflation_m, 0.0, 1.0);
}

void ClearanceCritic::Prepare(const CriticContext& context) {
  TrajectoryCritic::Prepare(context);
  escaping_.clear();
  straddled_.clear();
  path_proximity_ = 0.0;
  if (context.map == nullptr) return;
  const CostMap& map = *context.map;
  if (!map.IsValid(context.pose)) escaping_ = map.BlockingCellsUnder(context.pose);
  straddled_ = map.StraddledOneWayBits(context.pose);
  // The path's own proximity within reach: points every half cell along its local window.
  if (context.path == nullptr || context.path->size() < 2 || params_.inflation_m <= 0.0) return;
  const auto& poses = context.path->poses();
  const double inscribed = map.footprint().inscribed_radius_m();
  const double step = 0.5 * map.resolution_m();
  const size_t end = std::min(context.segment_end, poses.size() - 1);
  for (size_t i = context.segment_begin; i < end; ++i) {
    const Vector2 a = poses[i].position(), b = poses[i + 1].position();
    const double length = (b - a).norm();
    const int n = std::max(1, static_cast<int>(std::ceil(length / step)));
    bool beyond = false;
    for (int k = 0; k <= n; ++k) {
      const Vector2 p = a + (b - a) * (static_cast<double>(k) / n);
      if ((p - context.pose.position()).norm() > params_.path_reach_m) {
        beyond = k > 0 || beyond;
        continue;
      }
      path_proximity_ = std::max(path_proximity_, Proximity(map.SmoothClearanceAt(p), inscribed));
    }
    // Past the reach, stop (the window only grows farther from the robot).
    if (beyond && (b - context.pose.position()).norm() > params_.path_reach_m) break;
  }
}

// How far along a trajectory the clearance critic reads the terrain cost.
constexpr double kTerrainCostReachM = 0.3;

Score ClearanceCritic::Evaluate(const Trajectory& trajectory) const {
  const CostMap& map = *context().map;
  const double inscribed = map.footprint().inscribed_radius_m();
  float worst = 0.0f;
  double closest = std::numeric_limits<double>::infinity();
  double travelled_m = 0.0;
  // Poses closer than half a cell apart (a footprint corner's travel counts too): a footprint
  // that grazes a table leg between two 0.1 s poses of a fast sample is blocked all the same.
  const double max_step_m = 0.5 * map.resolution_m();
  const double reach_m = map.footprint().circumscribed_radius_m();
  auto check = [&](const Pose2& p) {
    return escaping_.empty() ? map.CheckFootprint(p) : map.CheckFootprintIgnoring(p, escaping_);
  };
  for (size_t k = 0; k < trajectory.poses.size(); ++k) {
    const Pose2& previous = k == 0 ? context().pose : trajectory.poses[k - 1];
    const Pose2& pose = trajectory.poses[k];
    const double step_m =
        std::max((pose.position() - previous.position()).norm(),
                 reach_m * std::abs(common::WrapAngle(pose.yaw_rad - previous.yaw_rad)));
    FootprintCost c = check(pose);
    // The first step also at its middle: the robot stands there after one control period
    // (20 Hz against the 0.1 s simulation step), and a footprint edge passing a cell's centre
    // can cover it there and at neither end (a slow arc grazing an obstacle).
    const int between =
        std::max(k == 0 ? 1 : 0, static_cast<int>(std::ceil(step_m / max_step_m)) - 1);
    // On a map with one-way cells, the direction of travel between the poses too: a step the
    // robot may only drive down blocks the climb like a lethal cell, unless the robot already
    // straddles that edge (it stands on both of its cells: the map changed under it).
    Pose2 from = previous;
    for (int j = 1; j <= between + 1 && c.valid; ++j) {
      const double f = static_cast<double>(j) / (between + 1);
      const Pose2 p =
          j > between
              ? pose
              : Pose2{previous.x_m + f * (pose.x_m - previous.x_m),
                      previous.y_m + f * (pose.y_m - previous.y_m),
                      previous.yaw_rad + f * common::WrapAngle(pose.yaw_rad - previous.yaw_rad)};
      if (j <= between) {
        const FootprintCost mid = check(p);
        if (!mid.valid) c = mid;
      }
      if (c.valid && !map.MotionAllowed(from, p, FootprintKind::kRobot, straddled_)) {
        c = {false, map.params().lethal_cost, false};
      }
      from = p;
    }
    if (k > 0) {
      travelled_m += (trajectory.poses[k].position() - trajectory.poses[k - 1].position()).norm();
    }
    if (c.valid) {
      // Terrain cost counts over the first kTerrainCostReachM only: over the whole horizon a
      // faster sample reaches further onto graded terrain (a ramp the global path climbs) and
      // always scores worse than creeping, until the robot stalls at its foot.
      if (travelled_m <= kTerrainCostReachM) worst = std::max(worst, c.max_cost);
      closest = std::min(closest, map.SmoothClearanceAt(trajectory.poses[k].position()));
      continue;
    }
    if (!params_.admissible_braking) return {false, 0.0};
    const double t_blocked = (k + 1) * params_.sim_step_s;
    const double stop_s = std::max(trajectory.peak_linear_mps / params_.acc_lim_x_mps2,
                                   trajectory.peak_angular_radps / params_.acc_lim_theta_radps2);
    if (t_blocked <= 0.5 * stop_s + params_.margin_s) return {false, 0.0};
    const double horizon = trajectory.poses.size() * params_.sim_step_s;
    return {true, 2.0 + (1.0 - t_blocked / horizon)};
  }
  const double proximity = std::max(0.0, Proximity(closest, inscribed) - path_proximity_);
  return {true, std::max(static_cast<double>(worst / map.params().lethal_cost), proximity)};
}

Score PathAlignCritic::Evaluate(const Trajectory& trajectory) const {
  const CriticContext& ctx = context();
  if (ctx.path == nullptr || ctx.path->empty() || trajectory.poses.empty()) return {true, 0.0};
  const Pose2& last = trajectory.poses.back();
  const Vector2 forward = last.Transform({forward_point_distance_m_, 0.0});
  return {true, ctx.path->Project(forward, ctx.segment_begin, ctx.segment_end).distance_m};
}

Score GoalDistCritic::Evaluate(const Trajectory& trajectory) const {
  if (trajectory.poses.empty()) return {true, 0.0};
  return {true, (trajectory.poses.back().position() - context().local_goal).norm()};
}

Score SpeedCritic::Evaluate(const Trajectory& trajectory) const {
  const double v = trajectory.target.linear_mps;
  if (v >= 0.0) return {true, std::max(0.0, (max_vel_x_mps_ - v) / max_vel_x_mps_)};
  return {true, 1.0 + (-v) / max_vel_x_mps_};
}

Score OscillationCritic::Evaluate(const Trajectory& trajectory) const {
  // The direction the trajectory heads for (a tracking trajectory's target), not its first
  // command: one from forward to reverse reverses even while its first command moves forward.
  const int lin = Sign(trajectory.target.linear_mps, kLinearEps);
  const int ang = Sign(trajectory.target.angular_radps, kAngularEps);
  const bool lin_reverses = lin != 0 && last_linear_sign_ != 0 && lin != last_linear_sign_;
  const bool ang_reverses = ang != 0 && last_angular_sign_ != 0 && ang != last_angular_sign_;
  if ((linear_flipped_ && lin_reverses) || (angular_flipped_ && ang_reverses)) return {false, 0.0};
  return {true, (lin_reverses || ang_reverses) ? 1.0 : 0.0};
}

void OscillationCritic::Commit(const Velocity& sent, const Pose2& pose) {
  const int lin = Sign(sent.linear_mps, kLinearEps);
  const int ang = Sign(sent.angular_radps, kAngularEps);
  if (lin != 0 && last_linear_sign_ != 0 && lin != last_linear_sign_ && !linear_flipped_) {
    linear_flipped_ = true;
    if (!angular_flipped_) flip_pose_ = pose;
  }
  if (ang != 0 && last_angular_sign_ != 0 && ang != last_angular_sign_ && !angular_flipped_) {
    angular_flipped_ = true;
    if (!linear_flipped_) flip_pose_ = pose;
  }
  if (lin != 0) last_linear_sign_ = lin;
  if (ang != 0) last_angular_sign_ = ang;
  // Enough motion since the first reversal clears the memory.
  if (linear_flipped_ || angular_flipped_) {
    const double moved = (pose.position() - flip_pose_.position()).norm();
    const double turned = std::abs(common::WrapAngle(pose.yaw_rad - flip_pose_.yaw_rad));
    if (moved > reset_distance_m_ || turned > reset_angle_rad_) {
      linear_flipped_ = false;
      angular_flipped_ = false;
    }
  }
}

void OscillationCritic::Reset() {
  last_linear_sign_ = 0;
  last_angular_sign_ = 0;
  linear_flipped_ = false;
  angular_flipped_ = false;
}

}  // namespace cairn::planner
