#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "common/types.h"
#include "planner/cost_map.h"
#include "planner/local/trajectory_generator.h"
#include "planner/path.h"

/// @file
/// Trajectory critics (Nav2 DWB shape). Each critic scores one simulated trajectory with a
/// Score{valid, value}: an invalid trajectory is rejected whatever the others say, and the
/// DWA picks the valid trajectory with the lowest sum of scale × value.

namespace cairn::planner {

/// A critic's verdict on one trajectory. `value` is a cost: lower is better, never negative.
struct Score {
  bool valid{true};
  double value{0.0};
};

/// What the critics know about the current control cycle.
struct CriticContext {
  const CostMap* map{nullptr};
  common::Pose2 pose;         ///< robot pose (world)
  Velocity last_command;      ///< the command sent in the previous cycle
  const Path* path{nullptr};  ///< global path (world)
  size_t segment_begin{0};    ///< local window of path segments the critics look at
  size_t segment_end{0};
  common::Vector2 local_goal{common::Vector2::Zero()};  ///< carrot on the path (world)
};

/// Base class of the critics. Critics are stateful only where they say so (oscillation).
class TrajectoryCritic {
 public:
  TrajectoryCritic(std::string name, double scale) : name_(std::move(name)), scale_(scale) {}
  virtual ~TrajectoryCritic() = default;
  TrajectoryCritic(const TrajectoryCritic&) = delete;
  TrajectoryCritic& operator=(const TrajectoryCritic&) = delete;

  const std::string& name() const { return name_; }
  double scale() const { return scale_; }

  /// Called once per cycle before any Score(); `context` outlives the cycle's scoring.
  virtual void Prepare(const CriticContext& context) { context_ = &context; }
  virtual Score Evaluate(const Trajectory& trajectory) const = 0;
  /// The command actually sent this cycle and the pose it was sent from.
  virtual void Commit(const Velocity& /*sent*/, const common::Pose2& /*pose*/) {}
  /// Forget any history (new goal).
  virtual void Reset() {}
  /// True when this critic rejects only from its memory of past commands (oscillation): when
  /// such critics alone leave no valid trajectory, the DWA clears their memory (Reset) and
  /// takes the best of those trajectories, so memory alone never stalls the robot.
  virtual bool RejectsByMemory() const { return false; }

 protected:
  const CriticContext& context() const { return *context_; }

 private:
  std::string name_;
  double scale_;
  const CriticContext* context_{nullptr};
};

/// "clearance": the footprint checked at every simulated pose.
///
/// A trajectory that stays on valid cells scores the larger of (a) the highest cost under its
/// footprint over its first 0.3 m, divided by the lethal cost (over the whole horizon a faster
/// sample reaches further onto graded terrain the global path crosses, and creeping would always
/// win), and (b) its closest approach to a blocking cell: 1 when
/// the nearest blocking cell is within the footprint's inscribed radius of the centre, falling
/// linearly to 0 at `inflation_m` beyond it. The cost layer carries no inflation, so (b) is what
/// keeps the robot off walls and corners (0..1 in all).
///
/// One that reaches a lethal (or blocking unknown) cell, or on a map with one-way cells drives
/// over one in a heading it refuses (CostMap::MotionAllowed, between consecutive poses), is
/// rejected unless the robot could still
/// brake before that pose (the admissible velocities of Fox, Burgard and Thrun's dynamic window
/// approach): braking both axes at their acceleration limits covers the arc of half the stopping
/// time at constant speed, so the trajectory is admissible when its first blocked pose comes later
/// than that plus `margin_s`. An admissible but blocked trajectory scores
/// 2 + (1 - t_blocked / horizon) (2..3), worse than any clear one, so the robot slows down in front
/// of obstacles instead of finding every sample rejected at once. With `admissible_braking` off,
/// any blocked pose rejects the trajectory (Nav2 DWB).
///
/// Proximity counts only beyond what the global path itself needs: the path's own proximity
/// over the stretch a trajectory can reach (`path_reach_m` from the robot) is subtracted. A path
/// the global planner bent close around a table leg would otherwise make every slow sample
/// from rest (the only ones a dynamic window holds) cost more in proximity than it gains in
/// progress, and the robot would stand still beside the leg for ever.
///
/// When the robot already touches blocking cells (an obstacle appeared under it, or a wall grew
/// by a cell), those cells count as free for the cycle, so trajectories that move away stay
/// valid and the robot can escape; any other blocking cell still rejects.
class ClearanceCritic : public TrajectoryCritic {
 public:
  struct Params {
    bool admissible_braking{true};
    double sim_step_s{0.1};   ///< time between simulated poses
    double margin_s{0.3};     ///< reaction margin (pose steps, control periods, latency)
    double inflation_m{0.3};  ///< proximity to blocking cells costs up to this far
    double acc_lim_x_mps2{0.8};
    double acc_lim_theta_radps2{1.5};
    double path_reach_m{1.0};  ///< the path's proximity is read this far from the robot
  };
  ClearanceCritic(double scale, const Params& params)
      : TrajectoryCritic("clearance", scale), params_(params) {}
  void Prepare(const CriticContext& context) override;
  Score Evaluate(const Trajectory& trajectory) const override;
  /// True for a score of a trajectory that is clear over its whole horizon (not one blocked
  /// beyond its braking distance, which scores 2..3).
  static bool ClearOverHorizon(const Score& score) { return score.valid && score.value < 2.0; }
  /// Blocking cells under the robot this cycle (empty when it is clear).
  const std::vector<int64_t>& escaping_cells() const { return escaping_; }
  /// The proximity (0..1) the global path itself has near the robot this cycle.
  double path_proximity() const { return path_proximity_; }

 private:
  double Proximity(double clearance_m, double inscribed_m) const;

  Params params_;
  std::vector<int64_t> escaping_;
  std::vector<CostMap::StraddledBits> straddled_;  // refusals under the robot this cycle
  double path_proximity_{0.0};
};

/// "path_align": distance (m) from a point `forward_point_distance_m` ahead of the final pose
/// to the local window of the path. Looking ahead of the pose rewards facing along the path.
class PathAlignCritic : public TrajectoryCritic {
 public:
  PathAlignCritic(double scale, double forward_point_distance_m)
      : TrajectoryCritic("path_align", scale),
        forward_point_distance_m_(forward_point_distance_m) {}
  Score Evaluate(const Trajectory& trajectory) const override;

 private:
  double forward_point_distance_m_;
};

/// "goal_dist": distance (m) from the final pose to the local goal.
class GoalDistCritic : public TrajectoryCritic {
 public:
  explicit GoalDistCritic(double scale) : TrajectoryCritic("goal_dist", scale) {}
  Score Evaluate(const Trajectory& trajectory) const override;
};

/// "speed": prefers driving forward fast. (max - v) / max for v >= 0, and 1 + |v| / max when
/// reversing.
class SpeedCritic : public TrajectoryCritic {
 public:
  SpeedCritic(double scale, double max_vel_x_mps)
      : TrajectoryCritic("speed", scale), max_vel_x_mps_(max_vel_x_mps) {}
  Score Evaluate(const Trajectory& trajectory) const override;

 private:
  double max_vel_x_mps_;
};

/// "oscillation": after the robot reversed its linear or angular direction, a trajectory that
/// reverses it back is rejected until the robot has moved `reset_distance_m` or turned
/// `reset_angle_rad` since the first reversal (DWB's OscillationCritic). A trajectory whose
/// direction differs from the last command's costs 1 (hysteresis), else 0.
class OscillationCritic : public TrajectoryCritic {
 public:
  OscillationCritic(double scale, double reset_distance_m, double reset_angle_rad)
      : TrajectoryCritic("oscillation", scale),
        reset_distance_m_(reset_distance_m),
        reset_angle_rad_(reset_angle_rad) {}
  Score Evaluate(const Trajectory& trajectory) const override;
  void Commit(const Velocity& sent, const common::Pose2& pose) override;
  void Reset() override;
  bool RejectsByMemory() const override { return true; }

  bool linear_flipped() const { return linear_flipped_; }
  bool angular_flipped() const { return angular_flipped_; }

 private:
  double reset_distance_m_;
  double reset_angle_rad_;
  int last_linear_sign_{0};
  int last_angular_sign_{0};
  bool linear_flipped_{false};
  bool angular_flipped_{false};
  common::Pose2 flip_pose_;
};

}  // namespace cairn::planner
