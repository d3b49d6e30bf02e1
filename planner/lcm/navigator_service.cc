#include "planner/lcm/navigator_service.h"

#include <chrono>
#include <cmath>
#include <cstdio>

#include "cairn/lcmt_body_velocity_request.hpp"
#include "cairn/lcmt_map_control_request.hpp"
#include "cairn/lcmt_path.hpp"
#include "cairn/lcmt_velocity_command.hpp"

#include "common/body_velocity.h"
#include "common/channels.h"
#include "common/check.h"
#include "common/layers.h"
#include "services/runtime/conversions.h"

namespace cairn::planner {

namespace ch = cairn::channels;

namespace {

constexpr char kProcess[] = "cairn-navigator";

LcmMapClientParams MapClientParams(const std::string& robot, const common::RobotProfile& profile,
                                   const NavigatorConfig& config) {
  LcmMapClientParams p;
  p.robot = robot;
  p.layer = config.map.LayerFor(profile.name);
  p.directed_layer = config.map.DirectedLayerFor(profile.name);
  p.map_name = config.map_name;
  p.requester = kProcess;
  p.resend_interval_s = config.resend_interval_s;
  p.snapshot.encoding = config.map.encoding;
  p.snapshot.occupancy = config.map.occupancy;
  p.snapshot.cost = config.cost_map;
  p.snapshot.incomplete_timeout_s = config.incomplete_map_timeout_s;
  p.snapshot.look_at_unseen_drops = config.map.look_at_unseen_drops;
  p.own_thread = config.map_thread;
  return p;
}

bool Finite(double v) { return std::isfinite(v); }

}  // namespace

NavigatorService::NavigatorService(runtime::Node& node, NavigatorConfig config,
                                   common::RobotProfile profile, std::vector<Place> places)
    : node_(node),
      config_(std::move(config)),
      profile_(std::move(profile)),
      robot_(node.options().robot),
      navigator_(profile_, config_.navigator, config_.local_planner, std::move(places)),
      planner_(config_.global_planner),
      map_client_(node, MapClientParams(node.options().robot, profile_, config_),
                  profile_.footprint_m) {
  CAIRN_THROW_UNLESS(!robot_.empty(), "the navigator needs a robot name");
  map_control_requests_ = runtime::Node::WallUtime();  // request ids unique across restarts
  node_.Subscribe<cairn::lcmt_goal>(ch::ForRobot(robot_, ch::kGoal),
                                    [this](const cairn::lcmt_goal& g) { OnGoal(g); });
  if (config_.pose_source == PoseSource::kOdom) {
    node_.Subscribe<cairn::lcmt_odometry>(ch::ForRobot(robot_, ch::kOdom),
                                          [this](const cairn::lcmt_odometry& m) { OnOdometry(m); });
  } else {
    node_.Subscribe<cairn::lcmt_pose>(ch::ForRobot(robot_, ch::kPose),
                                      [this](const cairn::lcmt_pose& m) { OnPose(m); });
  }
  worker_ = std::thread([this] { WorkerLoop(); });
  node_.AddTimer(1.0 / config_.control_rate_hz, [this] { OnControlTimer(); });
  node_.AddTimer(1.0 / config_.status_rate_hz, [this] { PublishStatus(); });
  node_.SetState(runtime::HealthState::kReady, "waiting for a goal");
  node_.Event(
      "navigating %s as %s on layer %s (%s) with %s (%s), DWA %dx%d over %.1f s at %.0f Hz of "
      "%s time, pose from %s",
      robot_.c_str(), profile_.name.c_str(), config_.map.LayerFor(profile_.name).c_str(),
      MapEncodingName(config_.map.encoding), config_.global_planner.planner.c_str(),
      StateSpaceKindName(config_.global_planner.state_space),
      config_.local_planner.generator.vx_samples, config_.local_planner.generator.vtheta_samples,
      config_.local_planner.generator.sim_time_s, config_.control_rate_hz,
      ControlClockName(config_.control_clock),
      ch::ForRobot(robot_, config_.pose_source == PoseSource::kOdom ? ch::kOdom : ch::kPose)
          .c_str());
}

NavigatorService::~NavigatorService() {
  {
    std::lock_guard<std::mutex> lock(worker_mutex_);
    worker_exit_ = true;
    queued_.reset();
    cancel_current_ = true;
  }
  worker_cv_.notify_all();
  if (worker_.joinable()) worker_.join();
}

void NavigatorService::WorkerLoop() {
  while (true) {
    PlanJob job;
    {
      std::unique_lock<std::mutex> lock(worker_mutex_);
      worker_cv_.wait(lock, [this] { return worker_exit_ || queued_.has_value(); });
      if (worker_exit_) return;
      job = std::move(*queued_);
      queued_.reset();
      cancel_current_ = false;
      worker_busy_ = true;
    }
    PlanResult result;
    try {
      result = planner_.Plan(*job.map, job.request, &cancel_current_);
    } catch (const std::exception& e) {
      result.status = PlanStatus::kTimedOut;
      result.message = std::string("planner error: ") + e.what();
    }
    {
      std::lock_guard<std::mutex> lock(worker_mutex_);
      results_.emplace_back(job.request_id, std::move(result));
      worker_busy_ = false;
    }
    idle_cv_.notify_all();
  }
}

bool NavigatorService::WaitForPlanner(double timeout_s) {
  std::unique_lock<std::mutex> lock(worker_mutex_);
  return idle_cv_.wait_for(lock, std::chrono::duration<double>(timeout_s),
                           [this] { return !worker_busy_ && !queued_.has_value(); });
}

void NavigatorService::StartPlan(PlanJob job) {
  {
    std::lock_guard<std::mutex> lock(worker_mutex_);
    queued_ = std::move(job);
    cancel_current_ = true;  // a running plan is superseded
  }
  worker_cv_.notify_all();
}

void NavigatorService::CancelPlan() {
  std::lock_guard<std::mutex> lock(worker_mutex_);
  queued_.reset();
  cancel_current_ = true;
}

void NavigatorService::HandlePlanResults(double now_s) {
  std::vector<std::pair<int64_t, PlanResult>> results;
  {
    std::lock_guard<std::mutex> lock(worker_mutex_);
    results.swap(results_);
  }
  for (auto& [id, r] : results) {
    node_.Count("plans");
    if (!r.ok()) node_.Count(std::string("plan_") + PlanStatusName(r.status));
    if (r.status != PlanStatus::kCancelled) {
      // The extent of the path tells a detour from a way round an obstacle at a glance.
      std::string shape;
      if (r.ok() && !r.poses.empty()) {
        Eigen::Vector2d lo = r.poses.front().position(), hi = lo;
        for (const auto& p : r.poses) {
          lo = lo.cwiseMin(p.position());
          hi = hi.cwiseMax(p.position());
        }
        char text[160];
        std::snprintf(text, sizeof(text), ", %.2f m, cost %.1f, x %.1f..%.1f, y %.1f..%.1f",
                      r.length_m, r.cost, lo.x(), hi.x(), lo.y(), hi.y());
        shape = text;
      }
      node_.Event("plan %lld: %s in %.0f ms%s%s", static_cast<long long>(id),
                  PlanStatusName(r.status), r.total_time_s * 1e3, shape.c_str(),
                  r.message.empty() ? "" : (" (" + r.message + ")").c_str());
    }
    navigator_.OnPlanResult(id, r, now_s);
  }
}

void NavigatorService::OnControlTimer() {
  // Paced by the poses: the wall clock ticks only while they do not come.
  if (config_.control_clock == ControlClock::kPose &&
      std::chrono::steady_clock::now() - last_tick_wall_ <
          std::chrono::duration<double>(1.5 / config_.control_rate_hz)) {
    return;
  }
  Tick();
}

void NavigatorService::Tick() {
  last_tick_wall_ = std::chrono::steady_clock::now();
  const double now_s = NowS();
  HandlePlanResults(now_s);
  FeedMap();
  const StepOutput out = navigator_.Step(now_s);
  if (out.cancel_plan) CancelPlan();
  if (out.plan) StartPlan(*out.plan);
  if (out.clear_short_term) AskToClearShortTerm();
  if (out.command) PublishCommand(*out.command, out.emergency_stop);
  if (out.path_changed) PublishPath();
  for (const std::string& event : out.events) node_.Event("%s", event.c_str());
  ReportState(out.status_changed);
}

// Feeds a new snapshot, or notes that the mapper re-announced the current one.
void NavigatorService::FeedMap() {
  map_client_.Poll();
  const auto latest = map_client_.Latest();
  const int64_t heard = map_client_.last_heard_utime();
  if (latest && latest != fed_map_) {
    if (!fed_map_ || fed_map_->geometry() != latest->geometry()) {
      const auto& g = latest->geometry();
      node_.Event("cost layer %d x %d cells at %.2f m, origin (%.2f, %.2f)", g.size_x, g.size_y,
                  g.resolution_m, g.origin.x_m, g.origin.y_m);
    }
    navigator_.OnMap(latest, static_cast<double>(heard) * 1e-6);
    fed_map_ = latest;
    fed_heard_utime_ = heard;
  } else if (latest && heard != fed_heard_utime_) {
    navigator_.OnMapHeartbeat(static_cast<double>(heard) * 1e-6);
    fed_heard_utime_ = heard;
  }
}

void NavigatorService::AskToClearShortTerm() {
  cairn::lcmt_map_control_request r{};
  r.utime = node_.NowUtime();
  r.request_id = ++map_control_requests_;
  r.requester = kProcess;
  r.op = cairn::lcmt_map_control_request::OP_CLEAR_SHORT_TERM;
  r.profile = profile_.name;
  r.has_profile = false;
  node_.Publish(ch::ForRobot(robot_, ch::kMapControl), r);
  node_.Event("asked the mapper to clear its short-term layer (request %lld)",
              static_cast<long long>(r.request_id));
}

void NavigatorService::PublishCommand(const Velocity& command, bool emergency_stop) {
  if (config_.command_output == CommandOutput::kBodyVelocity) {
    // Seed 004's velocity bridge: one body-velocity request per command.
    const common::BodyVelocityRequest r =
        common::BridgeVelocity({command.linear_mps, command.angular_radps}, profile_.name);
    cairn::lcmt_body_velocity_request req{};
    req.utime = node_.NowUtime();
    req.robot = robot_;
    req.frame = r.frame;
    req.requester = r.requester;
    req.goal_id = r.goal_id;
    req.priority = static_cast<int8_t>(r.priority);
    for (int i = 0; i < 6; ++i) {
      req.twist[i] = r.twist[i];
      req.disable_axis[i] = r.disable_axis[i];
    }
    node_.Publish(ch::ForRobot(robot_, ch::kBodyVelocity), req);
    node_.Count("commands");
    if (emergency_stop) node_.Count("safety_stops");
    return;
  }
  cairn::lcmt_velocity_command cmd{};
  cmd.utime = node_.NowUtime();
  cmd.robot = robot_;
  cmd.source = kProcess;
  cmd.linear_mps = command.linear_mps;
  cmd.angular_radps = command.angular_radps;
  node_.Publish(ch::ForRobot(robot_, ch::kCmdVel), cmd);
  node_.Count("commands");
  if (emergency_stop) node_.Count("safety_stops");
}

void NavigatorService::PublishPath() {
  cairn::lcmt_path path{};
  path.utime = node_.NowUtime();
  path.robot = robot_;
  path.goal_id = navigator_.status().goal_id;
  path.planner = config_.global_planner.planner;
  path.cost = navigator_.path_cost();
  for (const common::Pose2& p : navigator_.path().poses()) {
    path.x_m.push_back(p.x_m);
    path.y_m.push_back(p.y_m);
    path.yaw_rad.push_back(p.yaw_rad);
  }
  path.num_poses = static_cast<int32_t>(path.x_m.size());
  node_.Publish(ch::ForRobot(robot_, ch::kPath), path);
}

// The status on a change (logged once per state), and HEALTH DEGRADED while stopped.
void NavigatorService::ReportState(bool status_changed) {
  const NavStatus& s = navigator_.status();
  if (status_changed) {
    PublishStatus();
    if (s.state != last_logged_state_ || s.reason != last_logged_reason_ ||
        s.goal_id != last_logged_goal_) {
      node_.Event("goal %lld: %s (%s) %s", static_cast<long long>(s.goal_id), NavStateName(s.state),
                  NavReasonName(s.reason), s.message.c_str());
      last_logged_state_ = s.state;
      last_logged_reason_ = s.reason;
      last_logged_goal_ = s.goal_id;
    }
  }
  const bool stopped = s.state == NavState::kStopped;
  if (stopped && !stopped_degraded_) {
    node_.SetState(runtime::HealthState::kDegraded, s.message);
    stopped_degraded_ = true;
  } else if (!stopped && stopped_degraded_) {
    node_.SetState(runtime::HealthState::kReady, "inputs fresh");
    stopped_degraded_ = false;
  }
}

cairn::lcmt_nav_status NavigatorService::MakeStatus() const {
  const NavStatus& s = navigator_.status();
  cairn::lcmt_nav_status m{};
  m.utime = node_.NowUtime();
  m.robot = robot_;
  m.goal_id = s.goal_id;
  m.state = static_cast<int8_t>(s.state);
  m.reason = static_cast<int8_t>(s.reason);
  m.message = s.message;
  m.progress = s.progress;
  m.distance_remaining_m = s.distance_remaining_m;
  m.distance_travelled_m = s.distance_travelled_m;
  m.replans = s.replans;
  m.recoveries = s.recoveries;
  m.critic_names = s.critic_names;
  m.critic_rejections = s.critic_rejections;
  m.num_critics = static_cast<int32_t>(m.critic_names.size());
  return m;
}

void NavigatorService::PublishStatus() {
  node_.Publish(ch::ForRobot(robot_, ch::kNavStatus), MakeStatus());
}

void NavigatorService::RefuseGoal(const cairn::lcmt_goal& goal, const std::string& why) {
  node_.CountDropped("bad_goals");
  node_.Warn("bad_goal", "goal " + std::to_string(goal.goal_id) + " refused: " + why);
  cairn::lcmt_nav_status m = MakeStatus();
  m.goal_id = goal.goal_id;
  m.state = cairn::lcmt_nav_status::STATE_FAILED;
  m.reason = cairn::lcmt_nav_status::REASON_NONE;
  m.message = "goal refused: " + why;
  node_.Publish(ch::ForRobot(robot_, ch::kNavStatus), m);
}

void NavigatorService::OnGoal(const cairn::lcmt_goal& msg) {
  if (!msg.robot.empty() && msg.robot != robot_) {
    RefuseGoal(msg, "it is for robot '" + msg.robot + "'");
    return;
  }
  const double now_s = NowS();
  if (msg.kind == cairn::lcmt_goal::KIND_CANCEL) {
    node_.Event("goal %lld: cancel requested", static_cast<long long>(msg.goal_id));
    navigator_.Cancel(now_s);
    return;
  }
  if (!Finite(msg.xy_tolerance_m) || msg.xy_tolerance_m < 0.0 || !Finite(msg.yaw_tolerance_rad) ||
      msg.yaw_tolerance_rad < 0.0) {
    RefuseGoal(msg, "tolerances must be finite and not negative");
    return;
  }
  // A goal id already taken is a re-send (senders repeat a goal until the status names it, as
  // a message on the bus can be lost): idempotent, it never restarts the goal.
  if (msg.goal_id != 0 && msg.goal_id == last_goal_id_) {
    node_.Count("goal_repeats", 1);
    return;
  }
  NavGoal goal;
  goal.id = msg.goal_id;
  goal.xy_tolerance_m = msg.xy_tolerance_m;
  goal.yaw_tolerance_rad = msg.yaw_tolerance_rad;
  if (msg.kind == cairn::lcmt_goal::KIND_POSE) {
    if (!Finite(msg.x_m) || !Finite(msg.y_m) || (msg.use_yaw && !Finite(msg.yaw_rad))) {
      RefuseGoal(msg, "the pose is not finite");
      return;
    }
    goal.pose = {msg.x_m, msg.y_m, msg.use_yaw ? common::WrapAngle(msg.yaw_rad) : 0.0};
    goal.use_yaw = msg.use_yaw;
    node_.Event(
        "goal %lld: pose (%.2f, %.2f%s)", static_cast<long long>(msg.goal_id), msg.x_m, msg.y_m,
        msg.use_yaw ? (", " + std::to_string(msg.yaw_rad).substr(0, 5) + " rad").c_str() : "");
  } else if (msg.kind == cairn::lcmt_goal::KIND_PLACE) {
    if (msg.place.empty()) {
      RefuseGoal(msg, "the place name is empty");
      return;
    }
    goal.is_place = true;
    goal.place = msg.place;
    node_.Event("goal %lld: place '%s'", static_cast<long long>(msg.goal_id), msg.place.c_str());
  } else {
    RefuseGoal(msg, "unknown kind " + std::to_string(msg.kind));
    return;
  }
  last_goal_id_ = msg.goal_id;
  navigator_.SetGoal(goal, now_s);
}

void NavigatorService::AcceptPose(const common::Pose3& pose, int64_t utime) {
  const int64_t now = node_.NowUtime();
  // A missing stamp counts as "now"; a stamp far in the future is left for the navigator to
  // judge (it reports clock skew as stale input).
  const int64_t stamp = utime > 0 ? utime : now;
  navigator_.OnPose(pose.ToPose2(), static_cast<double>(stamp) * 1e-6);
  if (config_.control_clock != ControlClock::kPose) return;
  // A tick on the first pose a control period (of the poses' time) after the last; a stamp
  // that went back (a restarted simulation) starts the count again.
  const int64_t period_us = static_cast<int64_t>(1e6 / config_.control_rate_hz);
  if (last_tick_stamp_ == 0 || stamp < last_tick_stamp_ || stamp - last_tick_stamp_ >= period_us) {
    last_tick_stamp_ = stamp;
    Tick();
  }
}

void NavigatorService::OnPose(const cairn::lcmt_pose& msg) {
  if (!msg.robot.empty() && msg.robot != robot_) {
    node_.CountDropped("poses_for_other_robots");
    return;
  }
  const auto pose = runtime::FromLcm(msg);
  if (!pose.ok()) {
    node_.CountDropped("bad_poses");
    node_.Warn("bad_pose", "pose refused: " + pose.status().message());
    return;
  }
  AcceptPose(*pose, msg.utime);
}

void NavigatorService::OnOdometry(const cairn::lcmt_odometry& msg) {
  if (!msg.robot.empty() && msg.robot != robot_) {
    node_.CountDropped("odometry_for_other_robots");
    return;
  }
  const auto pose = runtime::FromLcm(msg);
  if (!pose.ok()) {
    node_.CountDropped("bad_odometry");
    node_.Warn("bad_odometry", "odometry refused: " + pose.status().message());
    return;
  }
  AcceptPose(*pose, msg.utime);
}

}  // namespace cairn::planner
