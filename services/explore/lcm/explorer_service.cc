#include "services/explore/lcm/explorer_service.h"

#include <cmath>
#include <cstring>

#include "cairn/lcmt_goal.hpp"
#include "cairn/lcmt_sim_control_reply.hpp"
#include "cairn/lcmt_sim_control_request.hpp"
#include "cairn/lcmt_velocity_command.hpp"

#include "common/channels.h"
#include "common/check.h"
#include "mapstore/lcm/mapstore_client.h"
#include "services/explore/nbv_report.h"
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
    case ExploreMode::kNbv:
      return cairn::lcmt_explore_status::MODE_NBV;
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
  } else if (config_.mode == ExploreMode::kNbv) {
    nbv_ = std::make_unique<NbvMission>(config_.nbv.ToMissionParams());
    node_.Subscribe<cairn::lcmt_laser_scan>(
        ch::ForRobot(robot_, ch::kTurretScan),
        [this](const cairn::lcmt_laser_scan& m) { OnTurretLine(m); });
    node_.Subscribe<cairn::lcmt_nav_status>(
        ch::ForRobot(robot_, ch::kNavStatus),
        [this](const cairn::lcmt_nav_status& m) { OnNavStatus(m); });
    node_.Subscribe<cairn::lcmt_sim_control_reply>(
        ch::kSimControlReply,
        [this](const cairn::lcmt_sim_control_reply& m) { OnSimControlReply(m); });
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
  } else if (nbv_) {
    node_.Event(
        "exploring %s (%s) by next-best-view (%s) over a %.0f m2 work area, scans from "
        "%s/%s, goals to %s",
        robot_.c_str(), profile_.name.c_str(), config_.nbv.preset.c_str(),
        nbv_->info_map().work_area().AreaM2(), robot_.c_str(), config_.nbv.turret_sensor.c_str(),
        ch::ForRobot(robot_, ch::kGoal).c_str());
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
  // The next-best-view mission counts its own distance (the tree's path when teleported).
  if (last_xy_ && !nbv_) status_.distance_m += (robot_xy_ - *last_xy_).norm();
  last_xy_ = robot_xy_;
}

void ExplorerService::OnNavStatus(const cairn::lcmt_nav_status& msg) {
  if (!msg.robot.empty() && msg.robot != robot_) return;
  using S = cairn::lcmt_nav_status;
  if (nbv_) {
    if (done_ || !nbv_goal_id_ || msg.goal_id != *nbv_goal_id_) return;
    const bool reached = msg.state == S::STATE_REACHED;
    // The navigator stops for a stale map or pose and resumes by itself when they are fresh:
    // the goal is still on.
    const bool paused = msg.state == S::STATE_STOPPED &&
                        (msg.reason == S::REASON_STALE_MAP || msg.reason == S::REASON_STALE_ODOM ||
                         msg.reason == S::REASON_NO_MAP);
    if (paused || (!reached && msg.state != S::STATE_FAILED && msg.state != S::STATE_CANCELLED &&
                   msg.state != S::STATE_STOPPED)) {
      return;
    }
    nbv_goal_id_.reset();
    const double now_s = NowS();
    node_.Event("view point %lld %s%s", static_cast<long long>(msg.goal_id),
                reached ? "reached" : "failed: ", reached ? "" : msg.message.c_str());
    CarryOut(nbv_->OnGoalResult(reached, msg.message, now_s), now_s);
    return;
  }
  const auto active = frontier_.active_goal();
  if (!active || msg.goal_id != *active) return;
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

void ExplorerService::OnTurretLine(const cairn::lcmt_laser_scan& msg) {
  if (done_ || !nbv_) return;
  if (!msg.robot.empty() && msg.robot != robot_) {
    node_.CountDropped("lines_for_other_robots");
    return;
  }
  const auto line = runtime::FromLcm(msg);
  if (!line.ok() || !std::isfinite(msg.turret_angle_rad)) {
    node_.CountDropped("bad_turret_lines");
    node_.Warn("bad_turret_line",
               "turret line refused: " + (line.ok() ? std::string("the turret angle is not finite")
                                                    : line.status().message()));
    return;
  }
  const double now_s = static_cast<double>(msg.utime) * 1e-6;
  const int before = nbv_->scans();
  const NbvAction action = nbv_->OnTurretLine(line.value(), msg.turret_angle_rad, now_s);
  if (nbv_->scans() != before) UpdateNbvStatus();
  CarryOut(action, now_s);
}

void ExplorerService::CarryOut(const NbvAction& action, double now_s) {
  if (!action.event.empty()) {
    node_.Event("%s", action.event.c_str());
    status_.message = action.event;
  }
  if (action.request_scan) {
    // After a drive the robot stands still a moment first; the first scan goes at once.
    trigger_at_s_ = now_s + (nbv_->goals_sent() > 0 ? config_.nbv.settle_s : 0.0);
    SetBehaviour("SCANNING");
  }
  if (action.goal) SendNbvGoal(*action.goal);
  if (action.done) Finish(nbv_->end_reason());
}

void ExplorerService::OnSimControlReply(const cairn::lcmt_sim_control_reply& msg) {
  if (done_ || msg.request_id <= 0 || msg.request_id >= next_request_id_) return;  // not ours
  const bool ok = msg.status == cairn::lcmt_sim_control_reply::STATUS_OK;
  if (teleport_request_ && msg.request_id == *teleport_request_) {
    teleport_request_.reset();
    const double now_s = NowS();
    if (ok) {
      for (const auto& p : teleport_path_m_) nbv_->OnPosition(p);
    }
    node_.Event("view point %s",
                ok ? "reached (teleported)" : ("not reached: " + msg.message).c_str());
    CarryOut(nbv_->OnGoalResult(ok, ok ? "" : msg.message, now_s), now_s);
    return;
  }
  if (!ok) node_.Warn("scan_request", "the simulator refused the scan request: " + msg.message);
}

void ExplorerService::SendScanRequest() {
  cairn::lcmt_sim_control_request req{};
  req.utime = node_.NowUtime();
  req.request_id = next_request_id_++;
  req.requester = kProcess;
  req.op = cairn::lcmt_sim_control_request::OP_TRIGGER_SENSOR;
  req.name = robot_ + "/" + config_.nbv.turret_sensor;
  node_.Publish(ch::kSimControl, req);
}

void ExplorerService::SaveInfoMap() {
  const auto slash = config_.save_to.find('/');
  mapstore::MapSnapshot snapshot;
  snapshot.site = config_.save_to.substr(0, slash);
  snapshot.name = config_.save_to.substr(slash + 1);
  snapshot.base = nbv_->info_map().ToGridMap();
  snapshot.provenance.source_robot = robot_;
  snapshot.provenance.source_profile = profile_.name;
  snapshot.provenance.source_profile_hash = profile_.ContentHash();
  snapshot.provenance.code_version = "cairn-explorer nbv";
  snapshot.provenance.parameters =
      "preset: " + config_.nbv.preset + "\nwork_area: \"" + config_.nbv.work_area + "\"\n";
  mapstore::MapstoreClient client(node_.lcm(), kProcess);
  const auto reply = client.Save(snapshot);
  if (!reply.ok()) {
    node_.Warn("save", "the information map was not saved to " + config_.save_to + ": " +
                           reply.status().ToString());
  } else if (reply->status != cairn::lcmt_mapstore_reply::STATUS_OK) {
    node_.Warn("save", "the map store refused the information map: " + reply->message);
  } else {
    node_.Event("information map saved as %s version %lld (%zu layers)", config_.save_to.c_str(),
                static_cast<long long>(reply->version), snapshot.base.layer_names().size());
  }
}

void ExplorerService::SendNbvGoal(const Candidate& goal) {
  if (config_.nbv.drive == "teleport") {
    cairn::lcmt_sim_control_request req{};
    req.utime = node_.NowUtime();
    req.request_id = next_request_id_++;
    req.requester = kProcess;
    req.op = cairn::lcmt_sim_control_request::OP_RESET_ROBOT;
    req.name = robot_;
    req.position_m[0] = goal.position_m.x();
    req.position_m[1] = goal.position_m.y();
    // Above the view point's ground, not "on the surface below": from high up that surface
    // may be a tree's crown.
    req.position_m[2] = std::isfinite(goal.ground_z_m)
                            ? goal.ground_z_m + config_.nbv.teleport_base_height_m
                            : 0.0;  // no ground known there: the surface below
    req.yaw_rad = 0.0;
    teleport_request_ = req.request_id;
    teleport_path_m_ = goal.path_m;
    node_.Publish(ch::kSimControl, req);
    SetBehaviour("TELEPORTING");
    UpdateNbvStatus();
    return;
  }
  nbv_goal_id_ = next_goal_id_++;
  cairn::lcmt_goal msg{};
  msg.utime = node_.NowUtime();
  msg.robot = robot_;
  msg.goal_id = *nbv_goal_id_;
  msg.kind = cairn::lcmt_goal::KIND_POSE;
  msg.x_m = goal.position_m.x();
  msg.y_m = goal.position_m.y();
  msg.use_yaw = false;
  msg.xy_tolerance_m = config_.nbv.goal_tolerance_m;
  node_.Publish(ch::ForRobot(robot_, ch::kGoal), msg);
  SetBehaviour("DRIVING");
  UpdateNbvStatus();
}

void ExplorerService::UpdateNbvStatus() {
  status_.scans = nbv_->scans();
  status_.distance_m = nbv_->distance_m();
  status_.goals_sent = nbv_->goals_sent();
  status_.goals_reached = nbv_->goals_reached();
  status_.goals_failed = nbv_->goals_failed();
  if (!nbv_->view_points().empty()) {
    status_.coverage = nbv_->view_points().back().coverage;
    status_.quality = nbv_->view_points().back().mean_quality;
  }
}

void ExplorerService::TickNbv(double now_s) {
  if (!have_pose_) {
    SetBehaviour("WAITING", "waiting for a pose");
    status_.state = cairn::lcmt_explore_status::STATE_WAITING;
    return;
  }
  if (!start_s_) {
    start_s_ = now_s;
    status_.state = cairn::lcmt_explore_status::STATE_EXPLORING;
    node_.SetState(runtime::HealthState::kReady, "exploring");
    CarryOut(nbv_->Start(now_s), now_s);
  }
  status_.elapsed_s = now_s - *start_s_;
  if (config_.duration_s > 0.0 && status_.elapsed_s >= config_.duration_s) {
    nbv_->Stop("the exploration time is over");
    Finish("the exploration time (" + std::to_string(static_cast<int>(config_.duration_s)) +
           " s) is over");
    return;
  }
  if (config_.nbv.drive != "teleport") nbv_->OnPosition(robot_xy_);
  if (trigger_at_s_ && now_s >= *trigger_at_s_) {
    trigger_at_s_.reset();
    SendScanRequest();
  }
  const int failed_before = nbv_->goals_failed();
  const NbvAction action = nbv_->Tick(now_s);
  if (nbv_->goals_failed() != failed_before && nbv_goal_id_) {
    // The mission gave the goal up: the navigator stops driving to it.
    FrontierAction cancel;
    cancel.kind = FrontierAction::Kind::kCancelGoal;
    cancel.goal_id = *nbv_goal_id_;
    SendGoal(cancel);
    nbv_goal_id_.reset();
  }
  CarryOut(action, now_s);
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
  if (nbv_) {
    TickNbv(NowS());
    return;
  }
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
  } else if (nbv_) {
    if (nbv_goal_id_) {
      FrontierAction cancel;
      cancel.kind = FrontierAction::Kind::kCancelGoal;
      cancel.goal_id = *nbv_goal_id_;
      SendGoal(cancel);
      nbv_goal_id_.reset();
    }
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
  status_.state =
      failed() ? cairn::lcmt_explore_status::STATE_FAILED : cairn::lcmt_explore_status::STATE_DONE;
  SetBehaviour("DONE", why);
  PublishStatus();
  if (nbv_) UpdateNbvStatus();
  node_.Event("done: %s (%.1f m driven in %.0f s, %d reverses, %d goals: %d reached, %d failed)",
              why.c_str(), status_.distance_m, status_.elapsed_s, status_.reverses,
              status_.goals_sent, status_.goals_reached, status_.goals_failed);
  node_.SetState(runtime::HealthState::kReady, "done: " + why);
}

void ExplorerService::WrapUp() {
  if (!nbv_ || wrapped_up_) return;
  wrapped_up_ = true;
  // Seed 002's summary, a line per view point, and the renders.
  const std::string table = NbvSummaryTable(*nbv_, config_.nbv.preset);
  size_t begin = 0;
  for (size_t end = table.find('\n'); end != std::string::npos;
       begin = end + 1, end = table.find('\n', begin)) {
    node_.Event("%s", table.substr(begin, end - begin).c_str());
  }
  if (!config_.save_to.empty()) SaveInfoMap();
  if (!config_.out_dir.empty()) {
    const auto written = WriteNbvReport(*nbv_, config_.nbv.preset, config_.out_dir);
    if (written.ok()) {
      node_.Event("summary and renders written to %s (%zu files)", config_.out_dir.c_str(),
                  written->size());
    } else {
      node_.Warn("report",
                 "the summary and renders could not be written: " + written.status().ToString());
    }
  }
}

void ExplorerService::PublishStatus() {
  status_.utime = node_.NowUtime();
  node_.Publish(ch::ForRobot(robot_, ch::kExploreStatus), status_);
}

}  // namespace cairn::explore
