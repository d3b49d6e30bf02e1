#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "planner/cost_map.h"
#include "planner/local/critic_registry.h"
#include "planner/local/critics.h"
#include "planner/local/trajectory_generator.h"
#include "planner/path.h"

/// @file
/// DwaPlanner: TrajectoryGenerator × critics, weighted sum and argmin (Nav2 DWB). Every command
/// it returns lies inside the dynamic window of the previous command, so it never exceeds the
/// profile's velocity or acceleration limits. The critics are DwaParams::critics, made by name
/// through a CriticRegistry and scored in the listed order.

namespace cairn::planner {

struct DwaParams {
  TrajectoryGeneratorParams generator;
  /// The critics in scoring order, each with its weight and its own params (critic_registry.h).
  /// Every critic scores every trajectory; the order is that of the per-critic rejection counts
  /// and values (DwaResult, NavStatus, the navigator's diagnostics).
  std::vector<CriticConfig> critics{DefaultCritics()};
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

  /// The entry of the critic named `name`, or nullptr.
  CriticConfig* FindCritic(const std::string& name);
  const CriticConfig* FindCritic(const std::string& name) const;

  /// @throws std::invalid_argument naming the bad field (an empty critic list, an empty or
  /// repeated critic name, a bad scale; unknown critics are the registry's to refuse).
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
  /// Every otherwise valid sample was rejected by critics that reject from memory only
  /// (oscillation): their memory was cleared and the best of those samples taken.
  bool oscillation_reset{false};
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
  /// Makes params.critics through `registry` (which need not outlive the planner).
  /// @throws std::invalid_argument for invalid limits or params, or a critic the registry
  /// does not know or refuses.
  DwaPlanner(const VelocityLimits& limits, const DwaParams& params,
             const CriticRegistry& registry = BuiltinCritics());
  DwaPlanner(const DwaPlanner&) = delete;
  DwaPlanner& operator=(const DwaPlanner&) = delete;

  /// Scores every sample of the window around `input.last_command` and returns the best.
  /// When every sample is rejected, returns the braking command with found = false. If the
  /// only rejections of otherwise valid samples came from critics that reject from memory
  /// (TrajectoryCritic::RejectsByMemory: oscillation), their memory is cleared and the best of
  /// those is used (so oscillation alone never stalls the robot). The path-tracking fallback
  /// (DwaParams::path_tracking) reads the first "clearance" critic of the list, if any.
  DwaResult Compute(const DwaInput& input);
  /// Tells the stateful critics which command was sent.
  void Commit(const Velocity& sent, const common::Pose2& pose);
  /// Clears critic memory and rejection counts (new goal).
  void Reset();

  /// The critics' names in scoring order (the order of every per-critic vector).
  const std::vector<std::string>& critic_names() const { return names_; }
  /// Trajectories rejected by each critic since the last Reset().
  const std::vector<int64_t>& rejection_counts() const { return rejections_; }
  const TrajectoryGenerator& generator() const { return generator_; }
  const DwaParams& params() const { return params_; }

 private:
  struct Cycle;  // one Compute()'s running bests
  void Consider(bool tracking, Cycle* cycle);
  void ScoreTracking(const DwaInput& input, Cycle* cycle);
  void PreferTracking(Cycle* cycle) const;
  void Decide(const DwaInput& input, Cycle* cycle);

  DwaParams params_;
  TrajectoryGenerator generator_;
  std::vector<std::unique_ptr<TrajectoryCritic>> critics_;
  const ClearanceCritic* clearance_{nullptr};  // the first "clearance" critic, if any
  size_t clearance_index_{0};
  std::vector<std::string> names_;
  std::vector<int64_t> rejections_;
  Trajectory scratch_;
};

}  // namespace cairn::planner
