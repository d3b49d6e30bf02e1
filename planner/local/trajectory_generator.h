#pragma once

#include <vector>

#include "common/robot_profile.h"
#include "common/types.h"
#include "common/velocity_limits.h"
#include "planner/cost_map.h"
#include "planner/path.h"

/// @file
/// The local planner's trajectory generator (Nav2 DWB's StandardTrajectoryGenerator shape): a
/// dynamic window of velocities reachable within one control period under the profile's
/// acceleration limits, sampled on a grid, each sample simulated at constant velocity over a
/// horizon (Fox, Burgard and Thrun). It also offers path-tracking trajectories (TrackPath): the
/// robot steering along the global path by regulated pure pursuit under the same limits. No
/// constant arc threads the S-bend from a corridor through a door beside it, or around a table
/// leg: every arc that reaches the door clips its frame, and the robot would stand still.

namespace cairn::planner {

using common::Velocity;
using common::VelocityLimits;

/// Velocities reachable in one control period: [min, max] per axis.
struct DynamicWindow {
  double min_linear_mps{0.0};
  double max_linear_mps{0.0};
  double min_angular_radps{0.0};
  double max_angular_radps{0.0};
};

struct TrajectoryGeneratorParams {
  int vx_samples{20};             ///< samples of forward speed across the window
  int vtheta_samples{20};         ///< samples of yaw rate across the window
  double sim_time_s{1.7};         ///< horizon each sample is simulated over
  double sim_step_s{0.1};         ///< spacing of the simulated poses
  double control_period_s{0.05};  ///< 20 Hz: the window spans what one period can reach

  /// @throws std::invalid_argument naming the bad field.
  void Validate() const;
};

/// A sampled command and the poses it leads to (world frame, at sim_step_s, ..., sim_time_s;
/// the current pose is not included).
struct Trajectory {
  Velocity velocity;            ///< the command for the next control period
  Velocity target;              ///< the velocity it heads for (= velocity for a window sample)
  double peak_linear_mps{0.0};  ///< largest |forward speed| along the trajectory
  double peak_angular_radps{0.0};
  std::vector<common::Pose2> poses;
};

class TrajectoryGenerator {
 public:
  /// @throws std::invalid_argument for invalid limits or params.
  TrajectoryGenerator(const VelocityLimits& limits, const TrajectoryGeneratorParams& params);

  /// The window around the last command, clipped to the velocity limits. It never asks for more
  /// than one period of acceleration away from `last_command` (if `last_command` lies outside
  /// the limits the window is the nearest reachable speed inside them).
  DynamicWindow Window(const Velocity& last_command) const;
  /// vx_samples × vtheta_samples commands spread evenly over the window (fewer when an axis of
  /// the window is a single value). Zero is included on an axis whenever the window holds it,
  /// so stopping and driving straight are always candidates.
  std::vector<Velocity> Samples(const Velocity& last_command) const;
  /// Poses of a constant-velocity arc from `start` (exact unicycle integration).
  void Simulate(const common::Pose2& start, const Velocity& velocity, Trajectory* out) const;
  /// The robot tracking `path` from `start` by regulated pure pursuit (Macenski et al., Nav2's
  /// RPP): toward a point `lookahead_m` ahead of its projection (searched from
  /// `first_segment`), turning in place first where that point lies more than
  /// `turn_in_place_rad` off its heading, at the top speed scaled down on curves tighter than
  /// `min_radius_m`, near blocking cells of `map` (closer than `slow_distance_m` beyond the
  /// footprint's inscribed radius; no map: no slowing) and over the last metre of the path,
  /// never below `min_speed_fraction` of it; the same acceleration limits as every sample,
  /// from `last_command`. `velocity` is the first period's command, `target` the velocity
  /// asked for at the start. False when the path has fewer than 2 poses.
  struct TrackingParams {
    double lookahead_m{0.4};
    double turn_in_place_rad{0.8};
    double min_radius_m{0.9};
    double slow_distance_m{0.6};
    double min_speed_fraction{0.2};
  };
  bool TrackPath(const common::Pose2& start, const Velocity& last_command, const Path& path,
                 size_t first_segment, const TrackingParams& tracking, const CostMap* map,
                 Trajectory* out) const;
  /// The command that slows down the most within the window (towards zero on both axes).
  Velocity Brake(const Velocity& last_command) const;
  /// The command closest to `target` within the window (each axis clamped).
  Velocity Toward(const Velocity& last_command, const Velocity& target) const;

  const VelocityLimits& limits() const { return limits_; }
  const TrajectoryGeneratorParams& params() const { return params_; }

 private:
  VelocityLimits limits_;
  TrajectoryGeneratorParams params_;
  int steps_{17};
};

}  // namespace cairn::planner
