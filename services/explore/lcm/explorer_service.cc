#include "services/explore/lcm/explorer_service.h"

#include <cmath>
#include <cstring>

#include "cairn/lcmt_goal.hpp"
#include "cairn/lcmt_velocity_command.hpp"

#include "common/channels.h"
#include "common/check.h"
#include "services/runtime/conversions.h"

namespace cairn::explore {

namespace ch = channels;

namespace {

constexpr char kProcess[] = "cairn-explorer";
constexpr char kCostLayer[] = "cost";

int8_t ModeCode(ExploreMode mode) {
  switch (mode) {
    case ExploreMode::kReactive:
      return cairn::lcmt_explore_status::MODE_REACTIVE;
    case ExploreMode::kStateless:
      return cairn::lcmt_explore_status::MODE_STATELESS;
    case ExploreMode::kFrontier:
      return cairn::lcmt_explore_status::MODE_FRONTIER;
  }
  return 0;
}

planner::LcmMapClientParams MapClientParams(const std::string& robot,
                                            const ExplorerConfig& config) {
  planner::LcmMapClientParams p;
  p.robot = robot;
  p.layer = config.frontier.layer;
  p.requester = kProcess;
  p.snapshot.encoding = planner::MapEncoding::kOccupancy;
  p.snapshot.occupancy.occupied_threshold_og =
      static_cast<float>(config.frontier.occupied_threshold_og);
  p.snapshot.occupancy.free_threshold_og = static_cast<float>(config.frontier.free_threshold_og);
  return p;
}

bool Reactive(ExploreMode mode) {
  return mode == ExploreMode::kReactive || mode == ExploreMode::kStateless;
}

}  // namespace

ExplorerService::ExplorerService(runtime::Node& node, ExplorerConfig config,
                                 common::RobotProfile profile)
    : node_(node),
      config_(std::move(config)),
      profile_(std::move(profile)),
      robot_(node.options().robot),
      reactive_(config_.reactive),
      stateless_(config_.reactive),
      frontier_(config_.frontier) {
  CAIRN_THROW_UNLESS(!robot_.empty(), "the explorer needs a robot name");
  config_.Validate();
  profile_.Validate();
  status_.robot = robot_;
  status_.mode = ModeCode(config_.mode);
  status_.state = cairn::lcmt_explore_status::STATE_STARTING;
  status_.coverage = NAN;
  status_.quality = NAN;
  for (float& s : status_.sector_min_m) s = NAN;
  if (Reactive(config_.mode)) {
    node_.Subscribe<cairn::lcmt_laser_scan>(ch::ForRobot(robot_, ch::kScan),
                                            [this](const cairn::lcmt_laser_scan& m) { OnScan(m); });
  } else {
    map_client_ = std::make_unique<planner::LcmMapClient>(node_, MapClientParams(robot_, config_),
                                                          profile_.footprint_m);
    node_.Subscribe<cairn::lcmt_nav_status>(
        ch::ForRobot(robot_, ch::kNavStatus),
        [this](const cairn::lcmt_nav_status& m) { OnNavStatus(m); });
  }
  node_.Subscribe<cairn::lcmt_pose>(ch::ForRobot(robot_, ch::kPose),
                                    [this](const cairn::lcmt_pose& m) { OnPose(m); });
  node_.AddTimer(0.1, [this] { Tick(); });
  node_.AddTimer(1.0 / config_.status_rate_hz, [this] { PublishStatus(); });
  node_.SetState(runtime::HealthState::kReady, "waiting for input");
  if (Reactive(config_.mode)) {
    node_.Event("exploring %s (%s) %s on %s, %s", robot_.c_str(), profile_.name.c_str(),
                ExploreModeName(config_.mode), ch::ForRobot(robot_, ch::kScan).c_str(),
                config_.duration_s > 0.0
                    ? ("for " + std::to_string(static_cast<int>(config_.duration_s)) + " s").c_str()
                    : "until stopped");
  } else {
    node_.Event("exploring %s (%s) by frontiers on layer %s, goals to %s", robot_.c_str(),
                profile_.name.c_str(), config_.frontier.layer.c_str(),
                ch::ForRobot(robot_, ch::kGoal).c_str());
  }
}

ExplorerService::~ExplorerService() = default;

double ExplorerService::NowS() const { return static_cast<double>(node_.NowUtime()) * 1e-6; }

void ExplorerService::SetBehaviour(const std::string& behaviour, const std::string& message) {
  status_.behaviour = behaviour;
  if (!message.empty()) status_.message = message;
}

void ExplorerService::PublishCommand(double v_mps, double omega_radps) {
  cairn::lcmt_velocity_command cmd{};
  cmd.utime = node_.NowUtime();
  cmd.robot = robot_;
  cmd.source = kProcess;
  cmd.linear_mps = v_mps;
  cmd.angular_radps = omega_radps;
  node_.Publish(ch::ForRobot(robot_, ch::kCmdVel), cmd);
}

void ExplorerService::OnScan(const cairn::lcmt_laser_scan& msg) {
  if (done_) return;
  if (!msg.robot.empty() && msg.robot != robot_) {
    node_.CountDropped("scans_for_other_robots");
    return;
  }
  const auto scan = runtime::FromLcm(msg);
  if (!scan.ok()) {
    node_.CountDropped("bad_scans");
    node_.Warn("bad_scan", "scan refused: " + scan.status().message());
    return;
  }
  const std::vector<float>& ranges = scan.value().ranges_m;
  if (ranges.size() < 5) {
    node_.CountDropped("short_scans");
    node_.Warn("short_scan", "scan refused: fewer than 5 beams");
    return;
  }
  const double now_s = static_cast<double>(msg.utime) * 1e-6;
  if (!start_s_) {
    start_s_ = now_s;
    status_.state = cairn::lcmt_explore_status::STATE_EXPLORING;
    node_.SetState(runtime::HealthState::kReady, "exploring");
    node_.Event("first scan (%zu beams): exploring", ranges.size());
  }
  last_scan_node_s_ = NowS();
  if (stopped_for_silence_) {
    stopped_for_silence_ = false;
    node_.Event("scans are back: exploring again");
  }
  status_.elapsed_s = now_s - *start_s_;
  if (config_.duration_s > 0.0 && status_.elapsed_s >= config_.duration_s) {
    Finish("the exploration time (" + std::to_string(static_cast<int>(config_.duration_s)) +
           " s) is over");
    return;
  }
  VelocityCommand cmd;
  ReactiveMode mode;
  SectorMinima sectors;
  if (config_.mode == ExploreMode::kReactive) {
    const auto& last = reactive_.state().last_time_s;
    if (last && now_s < *last) {
      // The simulation went back (a reset): the block timer and the turn side start afresh.
      reactive_.Reset();
      node_.Event("scan time went back from %.2f s to %.2f s: the explorer's memory is reset",
                  *last, now_s);
    }
    cmd = reactive_.Step(ranges, now_s);
    const ReactiveState& s = reactive_.state();
    mode = s.mode;
    sectors = s.sectors;
    status_.turn_direction = static_cast<int8_t>(s.turn_direction);
    status_.blocked_s = s.blocked_s;
  } else {
    const StatelessDecision d = stateless_.Decide(ranges);
    cmd = d.command;
    mode = d.mode;
    sectors = d.sectors;
  }
  if (mode == ReactiveMode::kReverse) ++status_.reverses;
  const double minima[5] = {sectors.right_m, sectors.front_right_m, sectors.front_m,
                            sectors.front_left_m, sectors.left_m};
  for (int i = 0; i < 5; ++i) status_.sector_min_m[i] = static_cast<float>(minima[i]);
  status_.behaviour = ReactiveModeName(mode);
  PublishCommand(cmd.v_mps, cmd.omega_radps);
}

void ExplorerService::OnPose(const cairn::lcmt_pose& msg) {
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
  const common::Pose2 p = pose.value().ToPose2();
  robot_xy_ = {p.x_m, p.y_m};
  have_pose_ = true;
  if (last_xy_) status_.distance_m += (robot_xy_ - *last_xy_).norm();
  last_xy_ = robot_xy_;
}

void ExplorerService::OnNavStatus(const cairn::lcmt_nav_status& msg) {
  if (!msg.robot.empty() && msg.robot != robot_) return;
  const auto active = frontier_.active_goal();
  if (!active || msg.goal_id != *active) return;
  using S = cairn::lcmt_nav_status;
  if (msg.state == S::STATE_REACHED) {
    frontier_.OnGoalResult(msg.goal_id, true, NowS());
    node_.Event("goal %lld reached", static_cast<long long>(msg.goal_id));
    SetBehaviour("CHOOSING", "goal reached");
  } else if (msg.state == S::STATE_FAILED || msg.state == S::STATE_CANCELLED ||
             msg.state == S::STATE_STOPPED) {
    // A stale map or pose, or no map yet, says nothing about the goal itself.
    const bool passing = msg.reason == S::REASON_STALE_MAP || msg.reason == S::REASON_STALE_ODOM ||
                         msg.reason == S::REASON_NO_MAP;
    frontier_.OnGoalResult(msg.goal_id, false, NowS(), !passing);
    node_.Event("goal %lld failed (%s): %s", static_cast<long long>(msg.goal_id),
                msg.message.c_str(),
                passing ? "not the goal's fault, it may be chosen again" : "blacklisted");
    SetBehaviour("CHOOSING", "goal failed: " + msg.message);
  }
}

void ExplorerService::SendGoal(const FrontierAction& action) {
  cairn::lcmt_goal goal{};
  goal.utime = node_.NowUtime();
  goal.robot = robot_;
  goal.goal_id = action.goal_id;
  goal.kind = action.kind == FrontierAction::Kind::kCancelGoal ? cairn::lcmt_goal::KIND_CANCEL
                                                               : cairn::lcmt_goal::KIND_POSE;
  goal.x_m = action.goal_m.x();
  goal.y_m = action.goal_m.y();
  goal.use_yaw = false;
  goal.xy_tolerance_m = config_.frontier.goal_tolerance_m;
  node_.Publish(ch::ForRobot(robot_, ch::kGoal), goal);
}

void ExplorerService::Tick() {
  if (done_) return;
  if (Reactive(config_.mode)) {
    if (last_scan_node_s_ && !stopped_for_silence_ &&
        NowS() - *last_scan_node_s_ > config_.scan_timeout_s) {
      stopped_for_silence_ = true;
      PublishCommand(0.0, 0.0);
      node_.Warn("no_scan", "no scan for " + std::to_string(config_.scan_timeout_s) +
                                " s: the robot is told to stop");
    }
    return;
  }
  map_client_->Poll();
  const auto snapshot = map_client_->Latest();
  if (!snapshot || !have_pose_) {
    SetBehaviour("WAITING", !snapshot ? "waiting for the occupancy layer" : "waiting for a pose");
    status_.state = cairn::lcmt_explore_status::STATE_WAITING;
    return;
  }
  const double now_s = NowS();
  if (!start_s_) {
    start_s_ = now_s;
    status_.state = cairn::lcmt_explore_status::STATE_EXPLORING;
    node_.SetState(runtime::HealthState::kReady, "exploring");
    node_.Event("map and pose in: exploring");
  }
  status_.elapsed_s = now_s - *start_s_;
  if (config_.duration_s > 0.0 && status_.elapsed_s >= config_.duration_s) {
    Finish("the exploration time (" + std::to_string(static_cast<int>(config_.duration_s)) +
           " s) is over");
    return;
  }
  if (snapshot != grid_source_) {  // a new snapshot: its cost layer as the frontiers' grid
    grid_source_ = snapshot;
    grid_ = common::GridMap(snapshot->geometry());
    grid_.AddLayer(kCostLayer, common::Layer(snapshot->cost()));
  }
  FrontierAction action;
  try {
    action = frontier_.Tick(&grid_, kCostLayer, robot_xy_, now_s);
  } catch (const std::invalid_argument& e) {
    // The robot off the known grid (the map has not reached it yet): wait.
    node_.Warn("frontier", std::string("no frontier choice: ") + e.what());
    return;
  }
  status_.frontiers = frontier_.frontiers();
  status_.goals_sent = frontier_.goals_sent();
  status_.goals_reached = frontier_.goals_reached();
  status_.goals_failed = frontier_.goals_failed();
  switch (action.kind) {
    case FrontierAction::Kind::kNone:
      break;
    case FrontierAction::Kind::kSendGoal:
      SendGoal(action);
      node_.Event("goal %lld: %s", static_cast<long long>(action.goal_id), action.why.c_str());
      SetBehaviour("DRIVING", action.why);
      break;
    case FrontierAction::Kind::kCancelGoal:
      SendGoal(action);
      node_.Event("%s", action.why.c_str());
      SetBehaviour("CHOOSING", action.why);
      break;
    case FrontierAction::Kind::kFinished:
      Finish(action.why);
      break;
  }
}

void ExplorerService::Halt(const std::string& why) {
  if (Reactive(config_.mode)) {
    PublishCommand(0.0, 0.0);
  } else if (const auto active = frontier_.active_goal()) {
    FrontierAction cancel;
    cancel.kind = FrontierAction::Kind::kCancelGoal;
    cancel.goal_id = *active;
    SendGoal(cancel);
  }
  status_.message = why;
}

void ExplorerService::Finish(const std::string& why) {
  Halt(why);
  done_ = true;
  status_.state = cairn::lcmt_explore_status::STATE_DONE;
  SetBehaviour("DONE", why);
  PublishStatus();
  node_.Event("done: %s (%.1f m driven in %.0f s, %d reverses, %d goals: %d reached, %d failed)",
              why.c_str(), status_.distance_m, status_.elapsed_s, status_.reverses,
              status_.goals_sent, status_.goals_reached, status_.goals_failed);
  node_.SetState(runtime::HealthState::kReady, "done: " + why);
}

void ExplorerService::PublishStatus() {
  status_.utime = node_.NowUtime();
  node_.Publish(ch::ForRobot(robot_, ch::kExploreStatus), status_);
}

}  // namespace cairn::explore
