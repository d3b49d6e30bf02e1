#pragma once

#include <chrono>
#include <cstdint>
#include <deque>
#include <map>
#include <string>
#include <utility>

#include "cairn/lcmt_body_velocity_request.hpp"
#include "cairn/lcmt_sim_control_reply.hpp"
#include "cairn/lcmt_sim_control_request.hpp"
#include "cairn/lcmt_velocity_command.hpp"

#include "services/runtime/node.h"
#include "simulator/lcm/sensor_publishers.h"
#include "simulator/mujoco_sim.h"

/// @file
/// SimService: cairn-sim's LCM face. It paces a MujocoSim against the wall clock, publishes its
/// readings (each sensor kind through its SensorPublisher) and SIM.CLOCK, takes velocity
/// commands and answers SIM.CONTROL.
///
/// Channels (per robot r): one per sensor kind (r.LIDAR_RANGES, r.SCAN, r.TURRET_SCAN, r.ODOM,
/// r.POSE, r.IMU for the built-in ones) out; r.CMD_VEL in. Fleet: SIM.CLOCK out, SIM.CONTROL in,
/// SIM.CONTROL_REPLY out. Every message's utime is simulation time.

namespace cairn::sim {

struct SimServiceParams {
  /// Multiple of real time; 0 runs as fast as the machine allows.
  double speed{1.0};
  bool start_paused{false};
  /// SIM.CLOCK messages per wall second while paused (time stands still but listeners learn it).
  double paused_clock_rate_hz{10.0};
  /// At most this many SIM.CLOCK messages per wall second when running fast (listeners only
  /// need the latest time).
  double max_clock_rate_hz{200.0};
  /// When the simulation falls behind its pace by more than this much sim time, it gives up
  /// catching up (the measured real-time factor then drops below the target).
  double max_lag_s{0.25};
  /// Replies remembered for replayed request ids.
  int reply_cache_size{1024};
};

class SimService {
 public:
  /// Subscribes to every robot's CMD_VEL and to SIM.CONTROL. `node`, `sim` and `publishers`
  /// must outlive it. @throws std::invalid_argument when a robot carries a sensor that has no
  /// publisher.
  SimService(runtime::Node& node, MujocoSim& sim, SimServiceParams params,
             const SensorPublishers& publishers = BuiltinSensorPublishers());
  SimService(const SimService&) = delete;
  SimService& operator=(const SimService&) = delete;

  /// Paces, steps and publishes until the node stops (Stop() or a signal). Returns 0.
  int Run();
  /// One round of Run(): handles waiting messages, steps as far as the pace allows (a few
  /// milliseconds of work at most), publishes, and waits up to `max_wait_ms` when ahead.
  /// Returns false once the node is stopping.
  bool RunOnce(int max_wait_ms = 10);
  /// Steps `steps` times regardless of pace or pause and publishes what they produced (tests).
  void StepAndPublish(int steps);
  /// Handles every message waiting on the bus without blocking.
  void HandlePending();

  double speed() const { return speed_; }
  bool paused() const { return paused_; }
  double real_time_factor() const { return rtf_; }

  /// Executes a control request (what SIM.CONTROL does, without the bus).
  cairn::lcmt_sim_control_reply Execute(const cairn::lcmt_sim_control_request& request);

 private:
  using Clock = std::chrono::steady_clock;

  void OnCommand(const std::string& robot, const cairn::lcmt_velocity_command& msg);
  /// A body-velocity request (the AUV's bridge): surge and yaw taken, disabled axes as 0.
  void OnBodyVelocity(const std::string& robot, const cairn::lcmt_body_velocity_request& msg);
  void ApplyCommand(const std::string& robot, double linear_mps, double angular_radps);
  void OnControl(const cairn::lcmt_sim_control_request& msg);
  /// Carries out every op but LIST; returns the outcome and what was done.
  std::pair<common::Status, std::string> Apply(const cairn::lcmt_sim_control_request& msg);
  /// Sets the reply's status and message, logs, counts refusals.
  void Finish(const cairn::lcmt_sim_control_request& msg, const common::Status& status,
              const std::string& done, cairn::lcmt_sim_control_reply* reply);
  void StepOnce();
  void PublishOutputs();
  void PublishClock();
  void Reanchor();
  void UpdateRealTimeFactor();

  runtime::Node& node_;
  MujocoSim& sim_;
  SimServiceParams params_;
  const SensorPublishers& publishers_;
  SimOutputs outputs_;
  double speed_{1.0};
  bool paused_{false};
  // Pace: sim time anchor_sim_s_ corresponds to wall time anchor_wall_.
  Clock::time_point anchor_wall_;
  double anchor_sim_s_{0.0};
  int64_t clock_ticks_{0};
  Clock::time_point last_paused_clock_;
  Clock::time_point last_clock_;
  // Real-time factor over about a second.
  Clock::time_point rtf_wall_;
  double rtf_sim_s_{0.0};
  double rtf_{0.0};
  std::map<std::pair<std::string, int64_t>, cairn::lcmt_sim_control_reply> replies_;
  std::deque<std::pair<std::string, int64_t>> reply_order_;
  int64_t warnings_reported_{0};
};

/// "max" or "0" -> 0 (as fast as possible), otherwise a positive finite number.
/// @throws std::invalid_argument for anything else.
double ParseSpeed(const std::string& text);

}  // namespace cairn::sim
