#include "planner/navigator.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "common/check.h"
#include "planner/approach.h"

namespace cairn::planner {

using common::Pose2;
using common::Vector2;

namespace {

bool IsZero(const Velocity& v) {
  return std::abs(v.linear_mps) < 1e-9 && std::abs(v.angular_radps) < 1e-9;
}

template <typename... Args>
std::string Format(const char* format, Args... values) {
  char buf[160];
  std::snprintf(buf, sizeof(buf), format, values...);
  return buf;
}

}  // namespace

void NavigatorParams::Validate() const {
  CAIRN_THROW_UNLESS(control_period_s > 0.0, "control_period_s must be positive");
  CAIRN_THROW_UNLESS(xy_goal_tolerance_m > 0.0, "xy_goal_tolerance_m must be positive");
  CAIRN_THROW_UNLESS(occupied_goal_far_m >= 0.0, "occupied_goal_far_m must not be negative");
  CAIRN_THROW_UNLESS(occupied_goal_shift_m >= 0.0, "occupied_goal_shift_m must not be negative");
  CAIRN_THROW_UNLESS(yaw_goal_tolerance_rad > 0.0, "yaw_goal_tolerance_rad must be positive");
  CAIRN_THROW_UNLESS(std::isfinite(wait_for_map_s) && wait_for_map_s >= 0.0,
                     "wait_for_map_s must not be negative");
  CAIRN_THROW_UNLESS(std::isfinite(approach_min_gain_m) && approach_min_gain_m >= 0.0,
                     "approach_min_gain_m must not be negative");
  CAIRN_THROW_UNLESS(
      max_pose_age_s > control_period_s,
      "max_pose_age_s must exceed the control period (" << control_period_s << " s)");
  CAIRN_THROW_UNLESS(max_map_age_s > control_period_s,
                     "max_map_age_s must exceed the control period (" << control_period_s << " s)");
  CAIRN_THROW_UNLESS(max_clock_skew_s > 0.0, "max_clock_skew_s must be positive");
  CAIRN_THROW_UNLESS(lookahead_m > 0.0, "lookahead_m must be positive");
  CAIRN_THROW_UNLESS(min_lookahead_m >= 0.0 && min_lookahead_m <= lookahead_m,
                     "min_lookahead_m must be in [0, lookahead_m], got " << min_lookahead_m);
  CAIRN_THROW_UNLESS(local_path_window_m > 0.0, "local_path_window_m must be positive");
  CAIRN_THROW_UNLESS(rotate_to_heading_threshold_rad > 0.0,
                     "rotate_to_heading_threshold_rad must be positive");
  CAIRN_THROW_UNLESS(max_path_deviation_m > 0.0, "max_path_deviation_m must be positive");
  CAIRN_THROW_UNLESS(path_check_ahead_m >= 0.0, "path_check_ahead_m must not be negative");
  CAIRN_THROW_UNLESS(min_replan_interval_s >= 0.0, "min_replan_interval_s must not be negative");
  CAIRN_THROW_UNLESS(replan_period_s >= 0.0, "replan_period_s must not be negative");
  CAIRN_THROW_UNLESS(replace_path_ratio > 0.0 && replace_path_ratio <= 1.0,
                     "replace_path_ratio must lie in (0, 1]");
  CAIRN_THROW_UNLESS(plan_time_budget_s > 0.0, "plan_time_budget_s must be positive");
  CAIRN_THROW_UNLESS(no_valid_trajectory_patience_s >= 0.0,
                     "no_valid_trajectory_patience_s must not be negative");
  CAIRN_THROW_UNLESS(progress_distance_m > 0.0, "progress_distance_m must be positive");
  CAIRN_THROW_UNLESS(progress_timeout_s > 0.0, "progress_timeout_s must be positive");
  CAIRN_THROW_UNLESS(recovery_reset_distance_m > 0.0, "recovery_reset_distance_m must be positive");
  CAIRN_THROW_UNLESS(stop_repeat_cycles >= 0, "stop_repeat_cycles must not be negative");
  recovery.Validate();
}

namespace {

DwaParams WithPeriod(DwaParams dwa, double period_s) {
  dwa.generator.control_period_s = period_s;
  return dwa;
}

}  // namespace

Navigator::Navigator(const common::RobotProfile& profile, const NavigatorParams& params,
                     const DwaParams& dwa, std::vector<Place> places)
    : profile_(profile),
      params_(params),
      limits_(VelocityLimits::FromProfile(profile)),
      dwa_(limits_, WithPeriod(dwa, params.control_period_s)),
      recovery_(dwa_.generator(), params.recovery),
      places_(std::move(places)) {
  profile_.Validate();
  params_.Validate();
  status_.critic_names = dwa_.critic_names();
  status_.critic_rejections.assign(status_.critic_names.size(), 0);
}

bool Navigator::active() const {
  switch (status_.state) {
    case NavState::kPlanning:
    case NavState::kDriving:
    case NavState::kRecovering:
    case NavState::kStopped:
      return true;
    default:
      return false;
  }
}

void Navigator::SetState(NavState state, NavReason reason, const std::string& message) {
  if (state != status_.state || reason != status_.reason) status_changed_ = true;
  status_.state = state;
  status_.reason = reason;
  status_.message = message;
}

void Navigator::Fail(NavReason reason, const std::string& message) {
  SetState(NavState::kFailed, reason, message);
  goal_.reset();
  pending_request_ = 0;
  plan_wanted_ = false;
  stop_cycles_left_ = params_.stop_repeat_cycles;
}

void Navigator::ResetGoalState() {
  goal_pose_.reset();
  periodic_replan_ = false;
  pending_request_ = 0;
  plan_wanted_ = false;
  path_ = Path();
  path_segment_ = 0;
  path_arc_m_ = 0.0;
  path_deviation_m_ = 0.0;
  phase_ = Phase::kFollow;
  no_valid_since_s_ = -1.0;
  map_wait_start_s_ = -1.0;
  waypoint_.reset();
  plan_waypoint_next_ = false;
  pending_to_waypoint_ = false;
  recovery_index_ = 0;
  failure_reason_ = NavReason::kNone;
  status_.progress = 0.0;
  status_.distance_remaining_m = 0.0;
  status_.distance_travelled_m = 0.0;
  status_.replans = 0;
  status_.recoveries = 0;
  dwa_.Reset();
  status_.critic_rejections.assign(status_.critic_names.size(), 0);
}

void Navigator::SetGoal(const NavGoal& goal, double now_s) {
  const bool had_plan = pending_request_ != 0;
  ResetGoalState();
  status_.goal_id = goal.id;
  status_changed_ = true;
  if (had_plan) cancel_plan_pending_ = true;
  xy_tolerance_m_ = goal.xy_tolerance_m > 0.0 ? goal.xy_tolerance_m : params_.xy_goal_tolerance_m;
  yaw_tolerance_rad_ =
      goal.yaw_tolerance_rad > 0.0 ? goal.yaw_tolerance_rad : params_.yaw_goal_tolerance_rad;
  if (goal.is_place) {
    if (FindPlace(places_, goal.place) == nullptr) {
      Fail(NavReason::kUnknownPlace, "unknown place '" + goal.place + "'");
      return;
    }
  } else if (!std::isfinite(goal.pose.x_m) || !std::isfinite(goal.pose.y_m) ||
             (goal.use_yaw && !std::isfinite(goal.pose.yaw_rad))) {
    Fail(NavReason::kOutOfBounds, "the goal pose is not finite");
    return;
  }
  goal_ = goal;
  if (pose_) last_travel_pose_ = pose_;
  progress_anchor_ = pose_ ? pose_->position() : Vector2::Zero();
  RestartProgressTimer(now_s);
  SetState(NavState::kPlanning, NavReason::kNone,
           goal.is_place ? "planning to place '" + goal.place + "'" : "planning");
  plan_wanted_ = true;
}

void Navigator::Cancel(double /*now_s*/) {
  if (!active()) return;
  if (pending_request_ != 0) cancel_plan_pending_ = true;
  SetState(NavState::kCancelled, NavReason::kCancelled, "cancelled");
  goal_.reset();
  pending_request_ = 0;
  plan_wanted_ = false;
  stop_cycles_left_ = params_.stop_repeat_cycles;
}

void Navigator::OnPose(const Pose2& pose, double stamp_s) {
  if (active() && last_travel_pose_) {
    status_.distance_travelled_m += (pose.position() - last_travel_pose_->position()).norm();
  }
  last_travel_pose_ = pose;
  pose_ = pose;
  pose_stamp_s_ = stamp_s;
}

void Navigator::OnMap(std::shared_ptr<const CostMap> map, double now_s) {
  map_ = std::move(map);
  map_rx_s_ = now_s;
  map_changed_ = true;
}

void Navigator::OnPlanResult(int64_t request_id, const PlanResult& result, double now_s) {
  if (request_id != pending_request_ || request_id == 0) return;
  pending_request_ = 0;
  if (!active()) return;
  const bool stopped = status_.state == NavState::kStopped;
  const bool periodic = periodic_replan_;
  periodic_replan_ = false;
  const bool to_waypoint = pending_to_waypoint_;
  pending_to_waypoint_ = false;
  // A path to the goal while approaching through known space replaces the waypoint's.
  const bool target_changes = waypoint_.has_value() && !to_waypoint;
  if (result.ok() && target_changes) {
    waypoint_.reset();
    pending_events_.push_back("approach: the map now shows a way to the goal itself");
  }
  if (result.ok() && periodic && !target_changes && status_.state == NavState::kDriving &&
      !path_.empty() && !PathBlockedAhead()) {
    // Keep the current path unless the new one costs clearly less than what is left of it.
    const double left = path_.length_m() > 0.0
                            ? path_cost_ * (path_.length_m() - path_arc_m_) / path_.length_m()
                            : 0.0;
    if (result.cost >= params_.replace_path_ratio * left) return;
    ++status_.replans;
    status_.message = "periodic replan found a better path";
    pending_events_.push_back(
        Format("periodic replan: a path of cost %.1f replaces what is left of the current one, ",
               result.cost) +
        Format("cost %.1f", left));
  }
  if (result.ok()) {
    path_ = Path(result.poses);
    path_cost_ = result.cost;
    path_segment_ = 0;
    path_arc_m_ = 0.0;
    path_changed_pending_ = true;
    phase_ = Phase::kFollow;
    no_valid_since_s_ = -1.0;
    failure_reason_ = NavReason::kNone;
    // A replan while driving keeps the no-progress timer running: a robot that is stuck while
    // the map keeps changing under its path would otherwise replan for ever and never recover.
    if (status_.state != NavState::kDriving) {
      if (pose_) progress_anchor_ = pose_->position();
      RestartProgressTimer(now_s);
    }
    UpdatePathProgress();
    if (stopped) {
      resume_state_ = NavState::kDriving;
      resume_reason_ = NavReason::kNone;
    } else if (status_.state != NavState::kDriving) {
      if (map_wait_start_s_ >= 0.0) {
        pending_events_.push_back(
            Format("explore first: the map showed a way after %.1f s of waiting; moving",
                   now_s - map_wait_start_s_));
        map_wait_start_s_ = -1.0;
      }
      std::ostringstream m;
      m << "driving a " << path_.length_m() << " m path";
      SetState(NavState::kDriving, NavReason::kNone, m.str());
    }
    return;
  }
  if (result.status == PlanStatus::kCancelled) return;
  const NavReason reason = ReasonOf(result.status);
  const std::string why = std::string("plan failed: ") + PlanStatusName(result.status) +
                          (result.message.empty() ? "" : " (" + result.message + ")");
  if (!to_waypoint && ApproachThroughKnown(result.status)) return;
  if (WaitForMap(result.status, why, now_s)) return;
  if (result.status == PlanStatus::kOutOfBounds) {
    Fail(reason, why);
    return;
  }
  // A failed replan while the current path is still clear: keep driving it.
  if (status_.state == NavState::kDriving && !path_.empty() && !PathBlockedAhead() &&
      path_deviation_m_ <= params_.max_path_deviation_m) {
    status_.message = why + "; keeping the current path";
    return;
  }
  if (stopped) {
    // Decide once the data is fresh again.
    resume_state_ = NavState::kPlanning;
    failure_reason_ = reason;
    plan_wanted_ = true;
    return;
  }
  StartRecoveryOrFail(reason, why, now_s);
}

bool Navigator::ApproachThroughKnown(PlanStatus status) {
  if (!params_.approach_through_known || !map_ || !pose_ || !goal_pose_) return false;
  if (status != PlanStatus::kNoPath && status != PlanStatus::kGoalOccupied &&
      status != PlanStatus::kOutOfBounds && status != PlanStatus::kTimedOut &&
      status != PlanStatus::kApproximate) {
    return false;
  }
  const Vector2 goal = goal_pose_->position();
  const std::optional<Pose2> pose = ApproachPose(*map_, *pose_, goal);
  const double now_to_goal = (pose_->position() - goal).norm();
  // To set out, the known water must lead approach_min_gain_m nearer; once under way, any metre.
  const double needed_m = waypoint_ ? 1.0 : params_.approach_min_gain_m;
  if (!pose || now_to_goal - (pose->position() - goal).norm() < needed_m) {
    // Nothing nearer the goal is known yet: keep a waypoint path still driven, else wait.
    return waypoint_.has_value() && status_.state == NavState::kDriving && !path_.empty() &&
           !PathBlockedAhead();
  }
  if (waypoint_ && (waypoint_->position() - pose->position()).norm() < 1.0 &&
      status_.state == NavState::kDriving && !path_.empty() && !PathBlockedAhead()) {
    return true;  // the same waypoint: keep its path
  }
  const bool first = !waypoint_.has_value();
  waypoint_ = pose;
  plan_waypoint_next_ = true;
  plan_wanted_ = true;
  const std::string note = Format(
      "approach: the map shows no way to the goal yet; heading for the known pose (%.1f, "
      "%.1f), %.1f m from it",
      pose->x_m, pose->y_m, (pose->position() - goal).norm());
  status_.message = note;
  if (first) pending_events_.push_back(note);
  return true;
}

bool Navigator::WaitForMap(PlanStatus status, const std::string& why, double now_s) {
  const bool planning =
      status_.state == NavState::kPlanning ||
      (status_.state == NavState::kStopped && resume_state_ == NavState::kPlanning);
  if (!(params_.wait_for_map_s > 0.0) || !planning || recovery_index_ > 0) return false;
  switch (status) {
    case PlanStatus::kNoPath:
    case PlanStatus::kStartOccupied:
    case PlanStatus::kGoalOccupied:
    case PlanStatus::kOutOfBounds:
    case PlanStatus::kTimedOut:
    case PlanStatus::kApproximate:
      break;
    default:
      return false;
  }
  if (map_wait_start_s_ < 0.0) {
    map_wait_start_s_ = now_s;
    pending_events_.push_back("explore first: waiting for the map to show a way to the goal (" +
                              why + ")");
  }
  if (now_s - map_wait_start_s_ > params_.wait_for_map_s) {
    pending_events_.push_back(
        Format("explore first: no way after %.1f s of waiting", now_s - map_wait_start_s_));
    map_wait_start_s_ = -1.0;
    return false;
  }
  status_.message = why + "; waiting for the map to show a way";
  plan_wanted_ = true;  // StartWantedPlan waits min_replan_interval_s between tries
  return true;
}

void Navigator::StartRecoveryOrFail(NavReason reason, const std::string& why, double now_s,
                                    bool after_blocked) {
  failure_reason_ = reason;
  plan_wanted_ = false;
  const auto& sequence = params_.recovery.sequence;
  // drive_forward is the way out of a pocket: only when the behaviour before it was blocked
  // where the robot stood (after a turn or a reverse that moved, or a plan that failed, the
  // plan from the new pose decides).
  while (!after_blocked && recovery_index_ < sequence.size() &&
         sequence[recovery_index_] == RecoveryKind::kDriveForward) {
    ++recovery_index_;
  }
  if (recovery_index_ < sequence.size() && pose_) {
    const RecoveryKind kind = sequence[recovery_index_++];
    recovery_.Start(kind, *pose_, now_s);
    recovery_anchor_ = pose_->position();
    ++status_.recoveries;
    SetState(NavState::kRecovering, reason, why + "; recovery: " + RecoveryKindName(kind));
    return;
  }
  Fail(reason == NavReason::kNone ? NavReason::kRecoveryExhausted : reason,
       why + "; recoveries exhausted");
}

bool Navigator::ResolveGoal() {
  if (goal_pose_ && goal_ && goal_->is_place) {
    MovePlaceGoalIfCrowded();
    return true;
  }
  if (goal_pose_) return true;
  if (!goal_) return false;
  if (!goal_->is_place) {
    goal_pose_ = goal_->pose;
    goal_has_yaw_ = goal_->use_yaw;
    return true;
  }
  const Place* place = FindPlace(places_, goal_->place);
  if (place == nullptr) {
    Fail(NavReason::kUnknownPlace, "unknown place '" + goal_->place + "'");
    return false;
  }
  const PlaceGoal resolved = ResolvePlace(*place, *map_, params_.place);
  if (!resolved.found) {
    StartRecoveryOrFail(NavReason::kGoalOccupied, resolved.message, last_step_s_);
    return false;
  }
  goal_pose_ = resolved.pose;
  goal_has_yaw_ = false;
  std::ostringstream m;
  m << "place '" << place->name << "' resolves to (" << resolved.pose.x_m << ", "
    << resolved.pose.y_m << "), " << resolved.clearance_m << " m from walls";
  status_.message = m.str();
  return true;
}

void Navigator::MovePlaceGoalIfCrowded() {
  if (!map_ || params_.place.move_margin_m <= 0.0) return;
  const Place* place = FindPlace(places_, goal_->place);
  if (place == nullptr) return;
  const double clearance_now_m = map_->ClearanceAt(goal_pose_->position());
  if (!std::isfinite(clearance_now_m)) return;
  const PlaceGoal better = ResolvePlace(*place, *map_, params_.place);
  if (!better.found || better.clearance_m < clearance_now_m + params_.place.move_margin_m) return;
  std::ostringstream m;
  m.setf(std::ios::fixed);
  m.precision(2);
  m << "place '" << place->name << "' moves to (" << better.pose.x_m << ", " << better.pose.y_m
    << "), " << better.clearance_m << " m from obstacles: the map now shows its goal ("
    << goal_pose_->x_m << ", " << goal_pose_->y_m << ") " << clearance_now_m << " m from one";
  goal_pose_ = better.pose;
  status_.message = m.str();
  status_changed_ = true;
  pending_events_.push_back("goal " + std::to_string(goal_->id) + ": " + m.str());
}

void Navigator::UpdatePathProgress() {
  if (path_.empty() || !pose_) return;
  // Search a window around the last projection so a path that doubles back cannot capture it.
  const size_t first = path_segment_ > 5 ? path_segment_ - 5 : 0;
  const size_t last = path_.IndexAt(path_arc_m_ + 5.0);
  const PathProjection proj = path_.Project(pose_->position(), first, last);
  path_segment_ = proj.segment;
  path_arc_m_ = proj.arc_length_m;
  path_deviation_m_ = proj.distance_m;
  status_.distance_remaining_m = path_.length_m() - path_arc_m_ + proj.distance_m;
  status_.progress =
      path_.length_m() > 0.0 ? std::clamp(path_arc_m_ / path_.length_m(), 0.0, 1.0) : 1.0;
}

bool Navigator::PathBlockedAhead(std::string* where) const {
  if (path_.empty() || !map_) return false;
  // Judged on the map plans are made on: a path that leads to look at an unseen drop is not
  // blocked by it (the local planner stops short of it).
  const CostMap& map = map_->planning_map();
  const size_t end = path_.IndexAt(path_arc_m_ + params_.path_check_ahead_m);
  for (size_t i = path_segment_ + 1; i <= end && i < path_.size(); ++i) {
    const Pose2& pose = path_.poses()[i];
    if (map.IsValid(pose)) continue;
    if (where != nullptr) {
      // Where, for the log: the blocking cells under the footprint there (their extent).
      const std::vector<int64_t> cells = map.BlockingCellsUnder(pose);
      const common::GridGeometry& g = map.geometry();
      Vector2 lo(std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity());
      Vector2 hi = -lo;
      for (const int64_t c : cells) {
        const Vector2 p =
            g.CenterOf({static_cast<int>(c % g.size_x), static_cast<int>(c / g.size_x)});
        lo = lo.cwiseMin(p);
        hi = hi.cwiseMax(p);
      }
      *where = Format(" at (%.2f, %.2f)", pose.x_m, pose.y_m);
      if (!cells.empty()) {
        *where += Format(": %zu blocking cells in x %.1f..%.1f, y %.1f..%.1f", cells.size(), lo.x(),
                         hi.x(), lo.y(), hi.y());
      }
    }
    return true;
  }
  return false;
}

Velocity Navigator::Drive(double now_s) {
  if (const auto command = ArriveOrAlign(now_s)) return *command;
  if (const auto command = RecoverWithoutProgress(now_s)) return *command;
  // The local goal: a carrot `lookahead_m` along the path (nearer where a corner hides it), or
  // the goal itself near the end.
  Vector2 carrot = Target().position();
  if (path_arc_m_ + params_.lookahead_m < path_.length_m()) {
    carrot = VisibleCarrot(*map_, path_, *pose_, path_arc_m_, params_.lookahead_m,
                           params_.min_lookahead_m);
  }
  if (const auto command = TurnTowardCarrot(now_s, carrot)) return *command;
  return FollowPath(now_s, carrot);
}

// Within the goal tolerance: reached, or turning in place to the goal's heading.
std::optional<Velocity> Navigator::ArriveOrAlign(double now_s) {
  const auto& gen = dwa_.generator();
  const Pose2& pose = *pose_;
  const Pose2& goal = *goal_pose_;
  const double to_goal = (pose.position() - goal.position()).norm();
  if (waypoint_ && phase_ == Phase::kFollow && to_goal > xy_tolerance_m_ &&
      (pose.position() - waypoint_->position()).norm() <= xy_tolerance_m_) {
    // At the edge of what the map showed: try the goal again from here.
    waypoint_.reset();
    path_ = Path();
    path_changed_pending_ = true;
    SetState(NavState::kPlanning, NavReason::kNone,
             "approach: at the known pose nearest the goal; planning again");
    plan_wanted_ = true;
    return gen.Brake(last_command_);
  }
  if (phase_ == Phase::kFollow && to_goal <= xy_tolerance_m_) {
    if (!goal_has_yaw_) {
      SetState(NavState::kReached, NavReason::kSuccess, "goal reached");
      status_.progress = 1.0;
      goal_.reset();
      stop_cycles_left_ = params_.stop_repeat_cycles;
      return gen.Brake(last_command_);
    }
    phase_ = Phase::kAlign;
    status_.message = "turning to the goal heading";
  }
  if (phase_ != Phase::kAlign) return std::nullopt;
  const double error = common::WrapAngle(goal.yaw_rad - pose.yaw_rad);
  if (std::abs(error) <= yaw_tolerance_rad_) {
    SetState(NavState::kReached, NavReason::kSuccess, "goal reached");
    status_.progress = 1.0;
    goal_.reset();
    stop_cycles_left_ = params_.stop_repeat_cycles;
    return gen.Brake(last_command_);
  }
  const Velocity turn{0.0, std::copysign(limits_.max_vel_theta_radps, error)};
  if (!MotionClear(map_.get(), pose, turn, params_.recovery.collision_lookahead_s)) {
    Fail(NavReason::kRecoveryExhausted,
         "at the goal position, but turning to the goal heading is blocked");
    return gen.Brake(last_command_);
  }
  RestartProgressTimer(now_s);
  return RotateInPlaceCommand(gen, last_command_, error, limits_.max_vel_theta_radps);
}

// Re-arms the recoveries after real progress; starts one after too long without progress.
std::optional<Velocity> Navigator::RecoverWithoutProgress(double now_s) {
  const Pose2& pose = *pose_;
  if (recovery_index_ > 0 &&
      (pose.position() - recovery_anchor_).norm() > params_.recovery_reset_distance_m) {
    recovery_index_ = 0;
  }
  if ((pose.position() - progress_anchor_).norm() >= params_.progress_distance_m) {
    progress_anchor_ = pose.position();
    RestartProgressTimer(now_s);
    return std::nullopt;
  }
  if (now_s - progress_anchor_s_ <= params_.progress_timeout_s) return std::nullopt;
  const std::string why =
      Format("no progress for %.1f s", params_.progress_timeout_s) +
      drive_log_.Describe((pose.position() - progress_anchor_).norm(), dwa_.critic_names(), pose_,
                          path_.length_m() - path_arc_m_);
  RestartProgressTimer(now_s);
  StartRecoveryOrFail(NavReason::kNone, why, now_s);
  return dwa_.generator().Brake(last_command_);
}

// Far off the carrot's bearing: turn in place toward it first, where the turn is clear.
std::optional<Velocity> Navigator::TurnTowardCarrot(double now_s, const Vector2& carrot) {
  const Pose2& pose = *pose_;
  const Vector2 d = carrot - pose.position();
  const double heading_error = common::WrapAngle(std::atan2(d.y(), d.x()) - pose.yaw_rad);
  if (std::abs(heading_error) <= params_.rotate_to_heading_threshold_rad) return std::nullopt;
  const Velocity turn{0.0, std::copysign(limits_.max_vel_theta_radps, heading_error)};
  if (!MotionClear(map_.get(), pose, turn, params_.recovery.collision_lookahead_s)) {
    return std::nullopt;
  }
  no_valid_since_s_ = -1.0;
  // A turn toward the path gets half the no-progress timeout once per timer: turning back
  // and forth between this branch and the DWA must not hold recoveries off for ever.
  if (!turn_extended_) {
    progress_anchor_s_ = std::max(progress_anchor_s_, now_s - params_.progress_timeout_s / 2);
    turn_extended_ = true;
  }
  drive_log_.CountTurn();
  return RotateInPlaceCommand(dwa_.generator(), last_command_, heading_error,
                              limits_.max_vel_theta_radps);
}

// The DWA toward the carrot along the path's local window; recoveries when no trajectory has
// been valid for too long.
Velocity Navigator::FollowPath(double now_s, const Vector2& carrot) {
  DwaInput in;
  in.map = map_.get();
  in.pose = *pose_;
  in.last_command = last_command_;
  in.path = &path_;
  in.segment_begin = path_segment_;
  in.segment_end = path_.IndexAt(path_arc_m_ + params_.local_path_window_m);
  in.local_goal = carrot;
  const DwaResult r = dwa_.Compute(in);
  drive_log_.Record(r, carrot);
  if (!r.found) {
    if (no_valid_since_s_ < 0.0) no_valid_since_s_ = now_s;
    if (now_s - no_valid_since_s_ > params_.no_valid_trajectory_patience_s) {
      no_valid_since_s_ = -1.0;
      StartRecoveryOrFail(NavReason::kNone, "no valid trajectory", now_s);
    }
  } else {
    no_valid_since_s_ = -1.0;
  }
  return r.command;
}

void Navigator::RestartProgressTimer(double now_s) {
  progress_anchor_s_ = now_s;
  turn_extended_ = false;
  drive_log_.Clear();
}

Vector2 VisibleCarrot(const CostMap& map, const Path& path, const Pose2& pose, double arc_m,
                      double lookahead_m, double min_lookahead_m) {
  const double step = std::max(0.05, 0.5 * map.resolution_m());
  const double skip = map.footprint().circumscribed_radius_m();
  auto sees = [&](const Vector2& target) {
    const Vector2 d = target - pose.position();
    const double length = d.norm();
    if (length <= skip) return true;
    const double yaw = std::atan2(d.y(), d.x());
    for (double s = skip; s < length + 0.5 * step; s += step) {
      const Vector2 p = pose.position() + d * (std::min(s, length) / length);
      if (!map.IsValid({p.x(), p.y(), yaw})) return false;
    }
    return true;
  };
  const double nearest = std::min(min_lookahead_m, lookahead_m);
  for (double ahead = lookahead_m; ahead > nearest; ahead -= step) {
    const Vector2 carrot = path.PoseAt(arc_m + ahead).position();
    if (sees(carrot)) return carrot;
  }
  return path.PoseAt(arc_m + nearest).position();
}

StepOutput Navigator::Step(double now_s) {
  StepOutput out;
  last_step_s_ = now_s;
  const auto& gen = dwa_.generator();
  if (cancel_plan_pending_) {
    out.cancel_plan = true;
    cancel_plan_pending_ = false;
  }
  if (!active()) return Idle(std::move(out));
  if (StopOnStaleInputs(now_s)) return Emit(Velocity{}, true, std::move(out));
  if (status_.state == NavState::kStopped) {
    SetState(resume_state_, resume_reason_, "inputs are fresh again: resuming");
  }
  UpdatePathProgress();
  DecideReplan(now_s);
  if (!StartWantedPlan(now_s, &out)) return Emit(gen.Brake(last_command_), false, std::move(out));
  const Velocity command = Command(now_s, &out);
  return Emit(command, false, std::move(out));
}

// Sends the cycle's command (and tells the DWA's critics), with what changed since the last.
StepOutput Navigator::Emit(const Velocity& command, bool emergency, StepOutput out) {
  out.command = command;
  out.emergency_stop = emergency;
  last_command_ = command;
  if (pose_) dwa_.Commit(command, *pose_);
  status_.critic_rejections = dwa_.rejection_counts();
  return Flush(std::move(out));
}

StepOutput Navigator::Flush(StepOutput out) {
  if (path_changed_pending_) {
    out.path_changed = true;
    path_changed_pending_ = false;
  }
  out.status_changed = status_changed_;
  status_changed_ = false;
  out.events = std::move(pending_events_);
  pending_events_.clear();
  return out;
}

// After a goal ends: brake within the limits, then repeat zero a few times, then go quiet.
StepOutput Navigator::Idle(StepOutput out) {
  if (!IsZero(last_command_))
    return Emit(dwa_.generator().Brake(last_command_), false, std::move(out));
  if (stop_cycles_left_ > 0) {
    --stop_cycles_left_;
    return Emit(Velocity{}, false, std::move(out));
  }
  if (path_changed_pending_) {
    out.path_changed = true;
    path_changed_pending_ = false;
  }
  out.status_changed = status_changed_;
  status_changed_ = false;
  return out;
}

// Safety: stale or missing inputs stop the robot at once. An input counts as stale one control
// period early: by the next cycle it would be older than its limit, so the stop goes out by then.
NavReason Navigator::StaleInput(double now_s, std::string* why) const {
  const double period = params_.control_period_s;
  if (!pose_) {
    *why = "no pose received yet";
    return NavReason::kStaleOdom;
  }
  if (now_s - pose_stamp_s_ > params_.max_pose_age_s - period) {
    *why = Format("the pose is %.2f s old", now_s - pose_stamp_s_);
    return NavReason::kStaleOdom;
  }
  if (pose_stamp_s_ - now_s > params_.max_clock_skew_s) {
    *why = Format("the pose is stamped %.2f s in the future", pose_stamp_s_ - now_s);
    return NavReason::kStaleOdom;
  }
  if (!map_) {
    *why = "no cost layer received yet";
    return NavReason::kNoMap;
  }
  if (now_s - map_rx_s_ > params_.max_map_age_s - period) {
    *why = Format("the cost layer is %.2f s old", now_s - map_rx_s_);
    return NavReason::kStaleMap;
  }
  if (map_rx_s_ - now_s > params_.max_clock_skew_s) {
    *why = Format("the cost layer is stamped %.2f s in the future", map_rx_s_ - now_s);
    return NavReason::kStaleMap;
  }
  if (map_->missing_tiles() > 0) {
    // Holes read as lethal: planning on them would fail the goal for want of tiles (a mapper
    // that just restarted), so wait for them like for a late layer.
    *why = "the cost layer lacks " + std::to_string(map_->missing_tiles()) + " tiles";
    return NavReason::kNoMap;
  }
  return NavReason::kNone;
}

bool Navigator::StopOnStaleInputs(double now_s) {
  std::string why;
  const NavReason stale = StaleInput(now_s, &why);
  if (stale == NavReason::kNone) return false;
  if (status_.state != NavState::kStopped) {
    resume_state_ = status_.state;
    resume_reason_ = status_.reason;
  }
  SetState(NavState::kStopped, stale, why + ": stopped");
  // Timers that measure progress do not run while stopped.
  RestartProgressTimer(now_s);
  no_valid_since_s_ = -1.0;
  return true;
}

// Replan when the map changed under the path ahead, the robot strayed, or periodically.
void Navigator::DecideReplan(double now_s) {
  if (status_.state == NavState::kDriving && !path_.empty() && replan_why_.empty()) {
    std::string where;
    if (map_changed_ && PathBlockedAhead(&where)) {
      replan_why_ = "the map changed under the path" + where;
    } else if (path_deviation_m_ > params_.max_path_deviation_m) {
      replan_why_ = Format("%.2f m off the path", path_deviation_m_);
    } else if (params_.replan_period_s > 0.0 &&
               now_s - last_plan_request_s_ > params_.replan_period_s) {
      replan_why_ = "periodic replan";
    }
  }
  map_changed_ = false;
  if (!replan_why_.empty() && status_.state == NavState::kDriving && pending_request_ == 0 &&
      now_s - last_plan_request_s_ >= params_.min_replan_interval_s) {
    // A periodic replan only replaces the path when it is clearly better (OnPlanResult).
    periodic_replan_ = replan_why_ == "periodic replan";
    if (!periodic_replan_) {
      ++status_.replans;
      status_.message = "replanning: " + replan_why_;
      pending_events_.push_back(status_.message);
    }
    replan_why_.clear();
    plan_wanted_ = true;
  } else if (status_.state != NavState::kDriving) {
    replan_why_.clear();
  }
}

// Starts a plan when one is wanted; false when the goal cannot be resolved this cycle.
bool Navigator::StartWantedPlan(double now_s, StepOutput* out) {
  if (!plan_wanted_ ||
      (status_.state != NavState::kPlanning && status_.state != NavState::kDriving)) {
    return true;
  }
  // Waiting for the map: one try per min_replan_interval_s.
  if (map_wait_start_s_ >= 0.0 && now_s - last_plan_request_s_ < params_.min_replan_interval_s) {
    return true;
  }
  if (!ResolveGoal()) return false;
  plan_wanted_ = false;
  const double to_goal = (pose_->position() - goal_pose_->position()).norm();
  if (to_goal <= xy_tolerance_m_) {
    // Already there: only the heading may be left to do.
    path_ = Path({*pose_, *goal_pose_});
    path_changed_pending_ = true;
    SetState(NavState::kDriving, NavReason::kNone, "at the goal position");
    return true;
  }
  PlanJob job;
  job.request_id = next_request_id_++;
  job.request.start = *pose_;
  pending_to_waypoint_ = plan_waypoint_next_ && waypoint_.has_value();
  plan_waypoint_next_ = false;
  job.request.goal = pending_to_waypoint_ ? *waypoint_ : *goal_pose_;
  job.request.goal_has_yaw = goal_has_yaw_;
  job.request.time_budget_s = params_.plan_time_budget_s;
  if (to_goal > params_.occupied_goal_far_m) {
    job.request.goal_shift_radius_m = params_.occupied_goal_shift_m;
  }
  // Plans may lead to look at unseen drops; the local planner drives on map_ itself.
  job.map = map_->planning_map_shared() ? map_->planning_map_shared() : map_;
  pending_request_ = job.request_id;
  last_plan_request_s_ = now_s;
  if (out->cancel_plan) out->cancel_plan = false;  // the new job supersedes the old one
  out->plan = std::move(job);
  return true;
}

// The command of the current state.
Velocity Navigator::Command(double now_s, StepOutput* out) {
  const auto& gen = dwa_.generator();
  switch (status_.state) {
    case NavState::kDriving:
      return path_.empty() ? gen.Brake(last_command_) : Drive(now_s);
    case NavState::kRecovering: {
      const RecoveryStep step = recovery_.Step(*pose_, last_command_, map_.get(), now_s);
      if (step.request_clear_short_term) out->clear_short_term = true;
      if (step.done && step.blocked) {
        // Blocked where it stood: the next behaviour at once (planning again from the same
        // pose would drive into the same pocket and wait out another no-progress timeout).
        StartRecoveryOrFail(failure_reason_,
                            std::string("after ") + RecoveryKindName(recovery_.kind()) + " (" +
                                step.note + ")",
                            now_s, /*after_blocked=*/true);
      } else if (step.done) {
        SetState(NavState::kPlanning, failure_reason_,
                 std::string("after ") + RecoveryKindName(recovery_.kind()) + " (" + step.note +
                     "): planning again");
        plan_wanted_ = true;
      }
      return step.command;
    }
    default:  // planning, or the goal just ended
      return gen.Brake(last_command_);
  }
}

}  // namespace cairn::planner
