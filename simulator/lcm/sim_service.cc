#include "simulator/lcm/sim_service.h"

#include <cmath>
#include <cstdlib>
#include <stdexcept>
#include <thread>

#include "cairn/lcmt_sim_clock.hpp"

#include "common/body_velocity.h"
#include "common/channels.h"

namespace cairn::sim {
namespace {

using Request = cairn::lcmt_sim_control_request;
using Reply = cairn::lcmt_sim_control_reply;

double Seconds(std::chrono::steady_clock::duration d) {
  return std::chrono::duration<double>(d).count();
}

int8_t StatusToReply(common::StatusCode code) {
  switch (code) {
    case common::StatusCode::kOk:
      return Reply::STATUS_OK;
    case common::StatusCode::kInvalidArgument:
      return Reply::STATUS_INVALID;
    case common::StatusCode::kNotFound:
      return Reply::STATUS_NOT_FOUND;
    case common::StatusCode::kAlreadyExists:
      return Reply::STATUS_ALREADY_EXISTS;
    default:
      return Reply::STATUS_ERROR;
  }
}

const char* OpName(int8_t op) {
  switch (op) {
    case Request::OP_SPAWN:
      return "spawn";
    case Request::OP_MOVE:
      return "move";
    case Request::OP_REMOVE:
      return "remove";
    case Request::OP_OPEN_DOOR:
      return "open door";
    case Request::OP_CLOSE_DOOR:
      return "close door";
    case Request::OP_RESET_ROBOT:
      return "reset robot";
    case Request::OP_PAUSE:
      return "pause";
    case Request::OP_RESUME:
      return "resume";
    case Request::OP_SET_SPEED:
      return "set speed";
    case Request::OP_LIST:
      return "list";
    case Request::OP_TRIGGER_SENSOR:
      return "trigger sensor";
    default:
      return "unknown";
  }
}

// The object a SPAWN request describes.
common::Status ObjectFromRequest(const Request& msg, ObjectSpec* spec) {
  spec->name = msg.name;
  if (msg.shape == Request::SHAPE_BOX) {
    spec->shape = ObjectShape::kBox;
  } else if (msg.shape == Request::SHAPE_CYLINDER) {
    spec->shape = ObjectShape::kCylinder;
  } else if (msg.shape == Request::SHAPE_SPHERE) {
    spec->shape = ObjectShape::kSphere;
  } else {
    return common::InvalidArgumentError("unknown shape " + std::to_string(msg.shape));
  }
  spec->size_m = common::Vector3(msg.size_m[0], msg.size_m[1], msg.size_m[2]);
  spec->position_m = common::Vector3(msg.position_m[0], msg.position_m[1], msg.position_m[2]);
  spec->yaw_rad = msg.yaw_rad;
  return common::Status::Ok();
}

}  // namespace

double ParseSpeed(const std::string& text) {
  if (text == "max") return 0.0;
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0' || !std::isfinite(v) || v < 0.0) {
    throw std::invalid_argument("speed '" + text + "' must be 'max' or a number >= 0");
  }
  return v;
}

SimService::SimService(runtime::Node& node, MujocoSim& sim, SimServiceParams params,
                       const SensorPublishers& publishers)
    : node_(node),
      sim_(sim),
      params_(params),
      publishers_(publishers),
      speed_(params.speed),
      paused_(params.start_paused) {
  for (const RobotSpec& r : sim_.scenario().robots) {
    for (const std::string& sensor : r.sensors.Names()) {
      if (publishers_.Find(sensor) == nullptr) {
        throw std::invalid_argument("robot '" + r.id + "': sensor '" + sensor +
                                    "' has no LCM publisher (simulator/lcm/sensor_publishers.cc)");
      }
    }
  }
  for (const std::string& robot : sim_.robot_ids()) {
    node_.Subscribe<cairn::lcmt_velocity_command>(
        channels::ForRobot(robot, channels::kCmdVel),
        [this, robot](const cairn::lcmt_velocity_command& msg) { OnCommand(robot, msg); });
    node_.Subscribe<cairn::lcmt_body_velocity_request>(
        channels::ForRobot(robot, channels::kBodyVelocity),
        [this, robot](const cairn::lcmt_body_velocity_request& msg) {
          OnBodyVelocity(robot, msg);
        });
  }
  node_.Subscribe<Request>(channels::kSimControl, [this](const Request& msg) { OnControl(msg); });
  Reanchor();
  warnings_reported_ = MujocoWarningCount();
  rtf_wall_ = Clock::now();
  rtf_sim_s_ = sim_.time_s();
  last_paused_clock_ = Clock::now();
  clock_ticks_ = static_cast<int64_t>(std::floor(sim_.time_s() * sim_.scenario().clock_rate_hz));
}

void SimService::Reanchor() {
  anchor_wall_ = Clock::now();
  anchor_sim_s_ = sim_.time_s();
}

// --- inputs ------------------------------------------------------------------------------------

void SimService::OnCommand(const std::string& robot, const cairn::lcmt_velocity_command& msg) {
  if (!msg.robot.empty() && msg.robot != robot) {
    node_.CountDropped("wrong_robot_commands");
    node_.Warn("wrong_robot:" + robot, "command on " + robot + "." + channels::kCmdVel +
                                           " names robot '" + msg.robot + "'; dropped");
    return;
  }
  ApplyCommand(robot, msg.linear_mps, msg.angular_radps);
}

void SimService::OnBodyVelocity(const std::string& robot,
                                const cairn::lcmt_body_velocity_request& msg) {
  if (!msg.robot.empty() && msg.robot != robot) {
    node_.CountDropped("wrong_robot_commands");
    node_.Warn("wrong_robot:" + robot, "body-velocity request on " + robot + "." +
                                           channels::kBodyVelocity + " names robot '" + msg.robot +
                                           "'; dropped");
    return;
  }
  common::BodyVelocityRequest request;
  for (int i = 0; i < 6; ++i) {
    request.twist[i] = msg.twist[i];
    request.disable_axis[i] = msg.disable_axis[i];
  }
  const common::SurgeYaw taken = common::SurgeYawOf(request);
  if (taken.ignored_axes) {
    node_.Count("ignored_axis_requests");
    node_.Warn("ignored_axes:" + robot, "a body-velocity request for " + robot + " (from '" +
                                            msg.requester +
                                            "') enables axes it cannot follow; only surge and "
                                            "yaw are taken");
  }
  ApplyCommand(robot, taken.command.linear_mps, taken.command.angular_radps);
}

void SimService::ApplyCommand(const std::string& robot, double linear_mps, double angular_radps) {
  switch (sim_.Command(robot, linear_mps, angular_radps)) {
    case CommandVerdict::kAccepted:
      break;
    case CommandVerdict::kDropped:
      node_.CountDropped("nan_commands");
      node_.Warn("nan_command:" + robot,
                 "dropped a velocity command for " + robot + " with NaN or infinite values");
      break;
    case CommandVerdict::kClamped:
      node_.Count("clamped_commands");
      node_.Warn("clamped_command:" + robot,
                 "clamped a velocity command for " + robot + " to its profile's limits (v " +
                     std::to_string(linear_mps) + ", w " + std::to_string(angular_radps) + ")");
      break;
  }
}

void SimService::OnControl(const Request& msg) {
  const auto key = std::make_pair(msg.requester, msg.request_id);
  auto it = replies_.find(key);
  if (it != replies_.end()) {
    // A replayed request gets its first answer again and changes nothing.
    node_.Publish(channels::kSimControlReply, it->second);
    return;
  }
  Reply reply = Execute(msg);
  node_.Publish(channels::kSimControlReply, reply);
  replies_[key] = reply;
  reply_order_.push_back(key);
  while (static_cast<int>(reply_order_.size()) > params_.reply_cache_size) {
    replies_.erase(reply_order_.front());
    reply_order_.pop_front();
  }
}

Reply SimService::Execute(const Request& msg) {
  Reply reply;
  reply.utime = sim_.utime();
  reply.request_id = msg.request_id;
  reply.status = Reply::STATUS_OK;
  reply.num_names = 0;
  if (msg.op == Request::OP_LIST) {
    const std::vector<std::string> names = sim_.ListNames();
    reply.names = names;
    reply.num_names = static_cast<int32_t>(names.size());
    reply.message = std::to_string(names.size()) + " names";
    return reply;
  }
  const auto [status, done] = Apply(msg);
  Finish(msg, status, done, &reply);
  return reply;
}

std::pair<common::Status, std::string> SimService::Apply(const Request& msg) {
  const common::Vector3 position(msg.position_m[0], msg.position_m[1], msg.position_m[2]);
  const std::string& name = msg.name;
  switch (msg.op) {
    case Request::OP_SPAWN: {
      ObjectSpec spec;
      const common::Status parsed = ObjectFromRequest(msg, &spec);
      if (!parsed.ok()) return {parsed, ""};
      return {sim_.SpawnObject(spec), "spawned object '" + name + "'"};
    }
    case Request::OP_MOVE:
      return {sim_.MoveObject(name, position, msg.yaw_rad), "moved object '" + name + "'"};
    case Request::OP_REMOVE:
      return {sim_.RemoveObject(name), "removed object '" + name + "'"};
    case Request::OP_OPEN_DOOR:
    case Request::OP_CLOSE_DOOR: {
      const bool open = msg.op == Request::OP_OPEN_DOOR;
      return {sim_.SetDoor(name, open),
              std::string(open ? "opened" : "closed") + " door '" + name + "'"};
    }
    case Request::OP_RESET_ROBOT: {
      // z of 0 (or NaN) puts the robot on the surface below (x, y).
      std::optional<double> z;
      if (std::isfinite(position.z()) && position.z() != 0.0) z = position.z();
      const bool finite_xy = std::isfinite(position.x()) && std::isfinite(position.y());
      return {finite_xy ? sim_.ResetRobot(name, position.x(), position.y(), msg.yaw_rad, z)
                        : common::InvalidArgumentError("reset position must be finite"),
              "reset robot '" + name + "'"};
    }
    case Request::OP_PAUSE:
      paused_ = true;
      return {common::Status::Ok(), "paused"};
    case Request::OP_RESUME:
      paused_ = false;
      Reanchor();
      return {common::Status::Ok(), "resumed"};
    case Request::OP_SET_SPEED:
      if (!std::isfinite(msg.speed) || msg.speed < 0.0) {
        return {common::InvalidArgumentError("speed must be >= 0 (0 = as fast as possible)"), ""};
      }
      speed_ = msg.speed;
      Reanchor();
      return {common::Status::Ok(), msg.speed == 0.0 ? std::string("speed set to max")
                                                     : "speed set to " + std::to_string(msg.speed)};
    case Request::OP_TRIGGER_SENSOR: {
      // "<robot>/<sensor>", split at the first '/'.
      const size_t slash = name.find('/');
      if (slash == std::string::npos || slash == 0 || slash + 1 == name.size()) {
        return {common::InvalidArgumentError("trigger sensor: name must be <robot>/<sensor>"), ""};
      }
      return {sim_.TriggerSensor(name.substr(0, slash), name.substr(slash + 1)),
              "triggered " + name};
    }
    default:
      return {common::InvalidArgumentError("unknown op " + std::to_string(msg.op)), ""};
  }
}

void SimService::Finish(const Request& msg, const common::Status& status, const std::string& done,
                        Reply* reply) {
  reply->status = StatusToReply(status.code());
  reply->message = status.ok() ? done : status.message();
  if (status.ok()) {
    node_.Event("%s", done.c_str());
    return;
  }
  if (status.code() == common::StatusCode::kInvalidArgument) {
    node_.CountDropped("bad_control_requests");
  }
  node_.Warn(std::string("control:") + OpName(msg.op), std::string("SIM.CONTROL ") +
                                                           OpName(msg.op) + " '" + msg.name +
                                                           "' refused: " + status.message());
}

void SimService::HandlePending() {
  // Bounded, so a flood of messages cannot starve the simulation.
  for (int i = 0; i < 1000 && node_.lcm().handleTimeout(0) > 0; ++i) {
  }
}

// --- outputs -----------------------------------------------------------------------------------

void SimService::PublishOutputs() {
  for (const std::string& event : outputs_.events) node_.Event("%s", event.c_str());
  for (const auto& group : outputs_.groups()) {
    if (group->empty()) continue;
    const SensorPublisher* publisher = publishers_.Find(group->sensor());
    CAIRN_DEMAND(publisher != nullptr);  // checked for every robot's sensors at construction
    publisher->publish(node_, *group);
  }
  outputs_.Clear();
}

void SimService::PublishClock() {
  cairn::lcmt_sim_clock clock{};
  clock.utime = sim_.utime();
  clock.wall_utime = runtime::Node::WallUtime();
  clock.real_time_factor = rtf_;
  clock.target_speed = speed_;
  clock.paused = paused_;
  clock.physics_steps = sim_.physics_steps();
  node_.Publish(channels::kSimClock, clock);
}

void SimService::UpdateRealTimeFactor() {
  const Clock::time_point now = Clock::now();
  const double wall = Seconds(now - rtf_wall_);
  if (wall >= 1.0) {
    rtf_ = (sim_.time_s() - rtf_sim_s_) / wall;
    rtf_wall_ = now;
    rtf_sim_s_ = sim_.time_s();
  }
}

void SimService::StepOnce() {
  sim_.Step(&outputs_);
  // SIM.CLOCK at the scenario's rate of simulated time.
  const int64_t ticks =
      static_cast<int64_t>(std::floor(sim_.time_s() * sim_.scenario().clock_rate_hz + 1e-9));
  const bool tick = ticks > clock_ticks_;
  clock_ticks_ = ticks;
  PublishOutputs();
  if (tick) {
    const Clock::time_point now = Clock::now();
    if (Seconds(now - last_clock_) >= 1.0 / params_.max_clock_rate_hz) {
      last_clock_ = now;
      PublishClock();
    }
  }
}

void SimService::StepAndPublish(int steps) {
  for (int i = 0; i < steps; ++i) StepOnce();
  UpdateRealTimeFactor();
}

// --- pacing ------------------------------------------------------------------------------------

bool SimService::RunOnce(int max_wait_ms) {
  HandlePending();
  if (!node_.SpinOnce(0)) return false;  // timers (heartbeat) and one more message
  UpdateRealTimeFactor();

  if (paused_) {
    const Clock::time_point now = Clock::now();
    if (Seconds(now - last_paused_clock_) >= 1.0 / params_.paused_clock_rate_hz) {
      last_paused_clock_ = now;
      rtf_ = 0.0;
      PublishClock();
    }
    node_.SpinOnce(max_wait_ms);
    return !node_.stopping();
  }

  // Work for a few milliseconds at most between looks at the bus.
  const Clock::time_point budget_end = Clock::now() + std::chrono::milliseconds(5);
  const double dt = sim_.timestep_s();
  int64_t steps = 0;
  if (speed_ <= 0.0) {
    do {
      StepOnce();
      ++steps;
    } while (Clock::now() < budget_end);
  } else {
    const double target = anchor_sim_s_ + speed_ * Seconds(Clock::now() - anchor_wall_);
    if (target - sim_.time_s() > params_.max_lag_s) {
      // Too far behind: stop trying to catch up.
      anchor_sim_s_ = sim_.time_s();
      anchor_wall_ = Clock::now();
    }
    while (sim_.time_s() + dt <= target + 1e-12 && Clock::now() < budget_end) {
      StepOnce();
      ++steps;
    }
    if (steps == 0) {
      // Ahead of the pace: wait for the next step (or a message).
      const double wait_s = (sim_.time_s() + dt - target) / speed_;
      const int wait_ms = static_cast<int>(std::ceil(wait_s * 1000.0));
      node_.SpinOnce(std::max(0, std::min(max_wait_ms, wait_ms)));
    }
  }
  if (steps > 0) node_.Count("physics_steps", steps);
  // MuJoCo's warnings go to the log through the hooks; HEALTH counts them.
  const int64_t warnings = MujocoWarningCount();
  if (warnings > warnings_reported_) {
    node_.Count("mujoco_warnings", warnings - warnings_reported_);
    warnings_reported_ = warnings;
  }
  return !node_.stopping();
}

int SimService::Run() {
  node_.SetState(runtime::HealthState::kReady, "simulating");
  PublishClock();
  while (RunOnce()) {
  }
  node_.SetState(runtime::HealthState::kStopping, "shutting down");
  node_.PublishHealth();
  return 0;
}

}  // namespace cairn::sim
