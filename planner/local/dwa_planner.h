#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "planner/cost_map.h"
#include "planner/local/critics.h"
#include "planner/local/trajectory_generator.h"
#include "planner/path.h"

/// @file
/// DwaPlanner: TrajectoryGenerator × critics, weighted sum and argmin (Nav2 DWB). Every command
/// it returns lies inside the dynamic window of the previous command, so it never exceeds the
/// profile's velocity or acceleration limits.

namespace cairn::planner {

struct DwaParams {
  TrajectoryGeneratorParams generator;
  // Critic scales (weights of each critic's value in the sum).
  double path_align_scale{1.0};
  double goal_dist_scale{1.5};
  double clearance_scale{1.0};
  double speed_scale{0.4};
  double oscillation_scale{0.2};
  /// Clearance: keep trajectories that are blocked only beyond the braking distance (see
  /// ClearanceCritic), with this reaction margin.
  bool admissible_braking{true};
  double braking_margin_s{0.3};
  /// Clearance: getting closer than this beyond the inscribed radius to a blocking cell costs.
  double clearance_inflation_m{0.3};
  /// PathAlign looks this far ahead of the final pose (Nav2's forward_point_distance).
  double forward_point_distance_m{0.325};
  /// Oscillation memory is cleared after this much motion since the first reversal.
  double oscillation_reset_dist_m{0.05};
  double oscillation_reset_angle_rad{0.2};
  /// Also score trajectories that track the global path by pure pursuit (see
  /// TrajectoryGenerator::TrackPath), one per lookahead: a short one threads a door beside a
  /// wall, a long one smooths a straight; each turns in place beyond the angle. They compete
  /// with the samples; a tracking trajectory clear over its whole horizon is taken when the best
  /// sample would stand still or creep (forward speed below `stall_speed_mps`), or when the path
  /// near the robot runs within the clearance inflation of a blocking cell (a door, a gap).
  bool path_tracking{true};
  double stall_speed_mps{0.1};
  std::vector<double> tracking_lookaheads_m{0.2, 0.3, 0.45, 0.6};
  double tracking_turn_in_place_rad{0.8};
  double tracking_min_radius_m{0.9};     ///< slower on curves tighter than this ...
  double tracking_slow_distance_m{0.6};  ///< ... and this close to blocking cells

  /// @throws std::invalid_argument naming the bad field.
  void Validate() const;
};

struct DwaInput {
  const CostMap* map{nullptr};
  common::Pose2 pose;
  Velocity last_command;
  const Path* path{nullptr};
  size_t segment_begin{0};
  size_t segment_end{0};
  common::Vector2 local_goal{common::Vector2::Zero()};
};

struct DwaResult {
  bool found{false};  ///< false: no valid trajectory; `command` then brakes
  Velocity command;
  double score{0.0};
  Trajectory best;
  int samples{0};
  int valid{0};
  bool oscillation_reset{false};     ///< every valid sample was an oscillation: memory cleared
  bool tracking_chosen{false};       ///< a path-tracking trajectory was chosen ...
  bool tracking_broke_stall{false};  ///< ... over a best sample that stood still or crept
  std::vector<int64_t> rejections;   ///< this cycle, per critic (same order as critic_names())
  std::vector<double> best_values;   ///< the best trajectory's scale × value, per critic
  /// The best valid sample that drives forward (for "why does it not move" diagnostics).
  bool has_best_forward{false};
  Velocity best_forward;
  std::vector<double> best_forward_values;
};

class DwaPlanner {
 public:
  /// @throws std::invalid_argument for invalid limits or params.
  DwaPlanner(const VelocityLimits& limits, const DwaParams& params);
  DwaPlanner(const DwaPlanner&) = delete;
  DwaPlanner& operator=(const DwaPlanner&) = delete;

  /// Scores every sample of the window around `input.last_command` and returns the best.
  /// When every sample is rejected, returns the braking command with found = false. If the
  /// only rejections of otherwise valid samples came from the oscillation critic, its memory is
  /// cleared and the best of those is used (so oscillation alone never stalls the robot).
  DwaResult Compute(const DwaInput& input);
  /// Tells the stateful critics which command was sent.
  void Commit(const Velocity& sent, const common::Pose2& pose);
  /// Clears critic memory and rejection counts (new goal).
  void Reset();

  const std::vector<std::string>& critic_names() const { return names_; }
  /// Trajectories rejected by each critic since the last Reset().
  const std::vector<int64_t>& rejection_counts() const { return rejections_; }
  const TrajectoryGenerator& generator() const { return generator_; }
  const DwaParams& params() const { return params_; }

 private:
  DwaParams params_;
  TrajectoryGenerator generator_;
  std::vector<std::unique_ptr<TrajectoryCritic>> critics_;
  ClearanceCritic* clearance_{nullptr};
  OscillationCritic* oscillation_{nullptr};
  std::vector<std::string> names_;
  std::vector<int64_t> rejections_;
  Trajectory scratch_;
};

}  // namespace cairn::planner
