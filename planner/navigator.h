#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "common/robot_profile.h"
#include "common/types.h"
#include "planner/cost_map.h"
#include "planner/drive_log.h"
#include "planner/global/global_planner.h"
#include "planner/local/dwa_planner.h"
#include "planner/nav_status.h"
#include "planner/path.h"
#include "planner/places.h"
#include "planner/recovery.h"

/// @file
/// Navigator: the navigation state machine, pure and clock-free (every call takes the time),
/// so it runs the same under a unit test's fake time and in cairn-navigator.
///
/// The caller feeds it poses, cost-map snapshots, goals and plan results, and calls Step()
/// once per control period. Step() says what to publish (a velocity command, the path, the
/// status) and when to start a global plan, which the caller runs (in cairn-navigator on a
/// worker thread) and hands back with OnPlanResult().
///
/// Behaviour:
/// - A goal is a pose (with or without a heading) or a place name, resolved on the current map
///   to the free cell of the place farthest from walls.
/// - Driving follows the path with the DWA local planner; the robot first turns in place when
///   the path points far from its heading.
/// - It replans when the map changes under the path ahead or the robot strays from the path.
/// - When planning fails, no trajectory is valid for a while, or the robot makes no progress,
///   the recoveries run in order (rotate, back up, wait, clear the short-term layer), each
///   followed by a new plan; when they are exhausted the goal fails with the last reason.
/// - Safety: while a goal is active and the pose or the map is older than its limit (or
///   missing), every cycle commands an immediate stop and the status says why. That stop is
///   the one command not bound by the acceleration limits; every other command stays inside
///   the dynamic window of the previous one.

namespace cairn::planner {

/// The DWA's local goal: the path point `lookahead_m` past `arc_m`, brought back along the path
/// (in steps of half a cell and at least 5 cm, not nearer than `min_lookahead_m`) until the robot's
/// footprint could slide straight to it, heading along the way, without touching a blocking cell.
/// Where the path turns round a corner (into a door), a carrot beyond the corner pulls the robot
/// into the corner's cells, where it can neither go on nor turn; Nav2's pure pursuit checks the
/// lookahead's line the same way. Poses within the footprint's circumscribed radius of the
/// robot are not checked (a robot touching a cell must still get a goal).
common::Vector2 VisibleCarrot(const CostMap& map, const Path& path, const common::Pose2& pose,
                              double arc_m, double lookahead_m, double min_lookahead_m);

struct NavigatorParams {
  double control_period_s{0.05};  ///< 20 Hz
  double xy_goal_tolerance_m{0.25};
  double yaw_goal_tolerance_rad{0.25};
  /// Older odometry/pose stops the robot (checked a control period early, so the stop is out
  /// before the limit).
  double max_pose_age_s{0.5};
  double max_map_age_s{0.5};        ///< the same for the cost layer
  double max_clock_skew_s{1.0};     ///< inputs stamped further in the future count as stale
  double lookahead_m{1.2};          ///< the DWA's local goal this far along the path ...
  double min_lookahead_m{0.3};      ///< ... or nearer, down to this, until the robot sees it
  double local_path_window_m{3.0};  ///< path the alignment critic looks at
  double rotate_to_heading_threshold_rad{0.8};  ///< turn in place first above this error
  double max_path_deviation_m{1.0};             ///< farther from the path: replan
  double path_check_ahead_m{10.0};  ///< a map change blocking this much path ahead: replan
  double min_replan_interval_s{1.0};
  double replan_period_s{5.0};     ///< > 0: also replan this often ...
  double replace_path_ratio{0.9};  ///< ... and switch when the new path costs less than this
                                   ///< fraction of what is left of the current one
  double plan_time_budget_s{1.0};
  /// Farther than `occupied_goal_far_m` from its goal, a plan whose goal footprint is blocked
  /// ends at the nearest valid pose within `occupied_goal_shift_m` instead of failing: cells
  /// seen from afar at a grazing angle (a platform's top beyond a ramp) may read as a step that
  /// the approach then measures away. Nearer, a blocked goal is GOAL_OCCUPIED as before.
  double occupied_goal_far_m{3.0};
  double occupied_goal_shift_m{1.0};
  double no_valid_trajectory_patience_s{1.5};
  /// > 0: explore first (seed 004). A plan that fails because the map shows no way yet (no path,
  /// goal or start blocked, goal beyond the map, timed out) while the robot is still to start is
  /// tried again every min_replan_interval_s for up to this long, the robot held still; the wait
  /// is logged where it starts and ends. With unknown cells as obstacles the robot then moves
  /// only once its sensors have shown a way. 0: such a plan fails (or recovers) at once.
  double wait_for_map_s{0.0};
  /// Approach through known space (seed 004's AUV navigates only through discovered cells;
  /// meaningful with unknown cells blocking): when a plan to the goal fails because the map
  /// does not show a way yet, drive to the reachable known pose nearest the goal
  /// (ApproachPose) if that brings the robot at least approach_min_gain_m nearer, and try the
  /// goal again from there (and at every replan on the way); else wait as above.
  bool approach_through_known{false};
  double approach_min_gain_m{5.0};
  double progress_distance_m{0.2};        ///< must move this far ...
  double progress_timeout_s{10.0};        ///< ... within this time, else recover
  double recovery_reset_distance_m{1.0};  ///< driving this far re-arms the first recovery
  int stop_repeat_cycles{10};             ///< zero commands sent after a goal ends
  RecoveryParams recovery;
  PlaceGoalParams place;

  /// @throws std::invalid_argument naming the bad field.
  void Validate() const;
};

struct NavGoal {
  int64_t id{0};
  bool is_place{false};
  std::string place;
  common::Pose2 pose;
  bool use_yaw{false};
  double xy_tolerance_m{0.0};     ///< 0: the params' tolerance
  double yaw_tolerance_rad{0.0};  ///< 0: the params' tolerance
};

/// A plan to run: the snapshot and request to hand to GlobalPlanner::Plan.
struct PlanJob {
  int64_t request_id{0};
  PlanRequest request;
  std::shared_ptr<const CostMap> map;
};

struct StepOutput {
  std::optional<Velocity> command;  ///< publish when set
  bool emergency_stop{false};       ///< the command is a safety stop
  std::optional<PlanJob> plan;      ///< start this plan (supersedes any running one)
  bool cancel_plan{false};          ///< cancel the running plan
  bool clear_short_term{false};     ///< ask the mapper to clear its short-term layer
  bool path_changed{false};         ///< path() changed (publish it)
  bool status_changed{false};       ///< state, reason or goal changed (publish the status)
  std::vector<std::string> events;  ///< notable events of this cycle, one log line each
};

class Navigator {
 public:
  /// @throws std::invalid_argument for an invalid profile or params.
  Navigator(const common::RobotProfile& profile, const NavigatorParams& params,
            const DwaParams& dwa, std::vector<Place> places = {});
  Navigator(const Navigator&) = delete;
  Navigator& operator=(const Navigator&) = delete;

  /// A new goal replaces the current one. A place name that is not known fails at once.
  void SetGoal(const NavGoal& goal, double now_s);
  /// Cancels the active goal (no effect when idle).
  void Cancel(double now_s);
  /// A robot pose measured at stamp_s.
  void OnPose(const common::Pose2& pose, double stamp_s);
  /// A new cost-map snapshot, received at now_s.
  void OnMap(std::shared_ptr<const CostMap> map, double now_s);
  /// The map's producer was heard at now_s (a manifest or tile without a new snapshot): the
  /// current snapshot is still current.
  void OnMapHeartbeat(double now_s) {
    if (map_) map_rx_s_ = now_s;
  }
  /// The outcome of a PlanJob; results of superseded jobs are ignored.
  void OnPlanResult(int64_t request_id, const PlanResult& result, double now_s);
  /// One control cycle.
  StepOutput Step(double now_s);

  const NavStatus& status() const { return status_; }
  const Path& path() const { return path_; }
  double path_cost() const { return path_cost_; }
  /// The last command returned by Step (zero before the first).
  const Velocity& last_command() const { return last_command_; }
  const VelocityLimits& limits() const { return limits_; }
  const std::vector<Place>& places() const { return places_; }
  bool active() const;

 private:
  enum class Phase { kFollow, kAlign };
  void SetState(NavState state, NavReason reason, const std::string& message);
  void Fail(NavReason reason, const std::string& message);
  /// Explore first: true when a failed plan is to be tried again on a later map.
  bool WaitForMap(PlanStatus status, const std::string& why, double now_s);
  /// Approach through known space: true when a failed plan to the goal was answered with a
  /// plan to a known pose nearer it (or the current such path is kept).
  bool ApproachThroughKnown(PlanStatus status);
  /// Where the robot is driving: the waypoint when approaching, else the goal.
  const common::Pose2& Target() const { return waypoint_ ? *waypoint_ : *goal_pose_; }
  void RequestPlan(double now_s, const std::string& why);
  bool ResolveGoal();
  /// A place goal chosen on an earlier map moves when the map now shows obstacles near it.
  void MovePlaceGoalIfCrowded();
  void StartRecoveryOrFail(NavReason reason, const std::string& why, double now_s,
                           bool after_blocked = false);
  /// True when a pose of the path ahead is invalid on the planning map; `where` (if given)
  /// gets " at (x, y)" of that pose and the extent of the blocking cells under it.
  bool PathBlockedAhead(std::string* where = nullptr) const;
  void UpdatePathProgress();
  /// The no-progress timer starts again at now_s.
  void RestartProgressTimer(double now_s);
  void ResetGoalState();

  // Step(), stage by stage.
  StepOutput Idle(StepOutput out);
  StepOutput Emit(const Velocity& command, bool emergency, StepOutput out);
  StepOutput Flush(StepOutput out);
  /// Why the pose or the map cannot be used now (kNone: they can).
  NavReason StaleInput(double now_s, std::string* why) const;
  bool StopOnStaleInputs(double now_s);
  void DecideReplan(double now_s);
  bool StartWantedPlan(double now_s, StepOutput* out);
  Velocity Command(double now_s, StepOutput* out);
  // Driving along the path.
  Velocity Drive(double now_s);
  std::optional<Velocity> ArriveOrAlign(double now_s);
  std::optional<Velocity> RecoverWithoutProgress(double now_s);
  std::optional<Velocity> TurnTowardCarrot(double now_s, const common::Vector2& carrot);
  Velocity FollowPath(double now_s, const common::Vector2& carrot);

  common::RobotProfile profile_;
  NavigatorParams params_;
  VelocityLimits limits_;
  DwaPlanner dwa_;
  RecoveryBehaviour recovery_;
  std::vector<Place> places_;

  // Inputs.
  std::optional<common::Pose2> pose_;
  double pose_stamp_s_{0.0};
  std::optional<common::Pose2> last_travel_pose_;
  std::shared_ptr<const CostMap> map_;
  double map_rx_s_{0.0};
  bool map_changed_{false};

  // Goal.
  std::optional<NavGoal> goal_;
  std::optional<common::Pose2> goal_pose_;  // resolved
  bool goal_has_yaw_{false};
  double xy_tolerance_m_{0.25};
  double yaw_tolerance_rad_{0.25};

  // Plan.
  int64_t next_request_id_{1};
  int64_t pending_request_{0};
  bool plan_wanted_{false};
  double last_plan_request_s_{-1e9};
  Path path_;
  double path_cost_{0.0};
  size_t path_segment_{0};
  double path_arc_m_{0.0};
  double path_deviation_m_{0.0};

  // Driving and recovery.
  Phase phase_{Phase::kFollow};
  Velocity last_command_;
  double no_valid_since_s_{-1.0};
  double map_wait_start_s_{-1.0};  ///< explore first: waiting for the map since, or -1
  /// Approach through known space: the known pose driven to instead of the goal, if any.
  std::optional<common::Pose2> waypoint_;
  bool plan_waypoint_next_{false};   ///< the next plan goes to waypoint_, not the goal
  bool pending_to_waypoint_{false};  ///< the running plan goes to waypoint_
  common::Vector2 progress_anchor_{common::Vector2::Zero()};
  double progress_anchor_s_{0.0};
  bool turn_extended_{false};  ///< the turn-in-place extension of this timer is spent
  DriveLog drive_log_;         ///< since the progress timer last restarted
  std::vector<std::string> pending_events_;
  size_t recovery_index_{0};
  common::Vector2 recovery_anchor_{common::Vector2::Zero()};
  NavReason failure_reason_{NavReason::kNone};
  NavState resume_state_{NavState::kPlanning};
  NavReason resume_reason_{NavReason::kNone};
  int stop_cycles_left_{0};
  std::string replan_why_;
  bool periodic_replan_{false};
  bool cancel_plan_pending_{false};
  bool path_changed_pending_{false};
  double last_step_s_{0.0};

  NavStatus status_;
  bool status_changed_{false};
};

}  // namespace cairn::planner
