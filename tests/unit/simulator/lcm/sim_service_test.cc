#include "simulator/lcm/sim_service.h"

#include <chrono>
#include <cmath>
#include <limits>
#include <map>

#include <gtest/gtest.h>

#include "cairn/lcmt_imu.hpp"
#include "cairn/lcmt_laser_scan.hpp"
#include "cairn/lcmt_lidar_ranges.hpp"
#include "cairn/lcmt_odometry.hpp"
#include "cairn/lcmt_pose.hpp"
#include "cairn/lcmt_sim_clock.hpp"

#include "common/channels.h"
#include "services/runtime/conversions.h"
#include "simulator/sensors/turret_sensor.h"
#include "tests/unit/simulator/sim_test_util.h"

namespace cairn::sim {
namespace {

using Request = cairn::lcmt_sim_control_request;
using Reply = cairn::lcmt_sim_control_reply;
using testing::FlatWorld;
using testing::InlineScenario;

class SimServiceTest : public testing::SimTest {
 protected:
  void SetUp() override {
    SimTest::SetUp();
    Scenario s = InlineScenario(FlatWorld(), "r", "pioneer3at");
    s.robots[0].sensors.Set<TurretSensor>(Turret());
    sim_ = std::make_unique<MujocoSim>(s);
    runtime::NodeOptions options;
    options.process_name = "cairn-sim";
    options.lcm_url = "memq://";
    options.install_signal_handlers = false;
    node_ = std::make_unique<runtime::Node>(options);
    SimServiceParams params;
    params.max_clock_rate_hz = 1e9;  // one SIM.CLOCK per clock tick, however fast the test runs
    dut_ = std::make_unique<SimService>(*node_, *sim_, params);
    // Record every message by channel (memq delivers to the same LCM instance).
    node_->SubscribeRaw(".*", [this](const std::string& channel, const void*, int, int64_t) {
      ++counts_[channel];
    });
    node_->Subscribe<Reply>(channels::kSimControlReply,
                            [this](const Reply& reply) { replies_.push_back(reply); });
  }

  /// The robot's turret (continuous by default).
  virtual TurretParams Turret() const { return TurretParams{}; }

  Reply Send(Request request) {
    request.requester = "test";
    const size_t before = replies_.size();
    node_->Publish(channels::kSimControl, request);
    dut_->HandlePending();
    EXPECT_EQ(replies_.size(), before + 1);
    return replies_.empty() ? Reply{} : replies_.back();
  }

  Request Make(int8_t op, const std::string& name, int64_t id) {
    Request r{};
    r.op = op;
    r.name = name;
    r.request_id = id;
    return r;
  }

  void Command(double v, double w, const std::string& robot = "") {
    cairn::lcmt_velocity_command cmd{};
    cmd.robot = robot;
    cmd.linear_mps = v;
    cmd.angular_radps = w;
    node_->Publish("r.CMD_VEL", cmd);
    dut_->HandlePending();
  }

  std::unique_ptr<MujocoSim> sim_;
  std::unique_ptr<runtime::Node> node_;
  std::unique_ptr<SimService> dut_;
  std::map<std::string, int64_t> counts_;
  std::vector<Reply> replies_;
};

TEST_F(SimServiceTest, PublishesEverySensorAndTheClockInSimTime) {
  cairn::lcmt_lidar_ranges last_slice;
  cairn::lcmt_pose last_pose;
  node_->Subscribe<cairn::lcmt_lidar_ranges>(
      "r.LIDAR_RANGES", [&](const cairn::lcmt_lidar_ranges& m) { last_slice = m; });
  node_->Subscribe<cairn::lcmt_pose>("r.POSE", [&](const cairn::lcmt_pose& m) { last_pose = m; });
  dut_->StepAndPublish(500);  // 1 s
  dut_->HandlePending();
  EXPECT_EQ(counts_["r.LIDAR_RANGES"], 100);  // ranges, 3 bytes a ray; no points
  EXPECT_EQ(counts_["r.LIDAR"], 0);
  EXPECT_EQ(counts_["r.SCAN"], 10);
  EXPECT_EQ(counts_["r.TURRET_SCAN"], 50);
  EXPECT_EQ(counts_["r.ODOM"], 50);
  EXPECT_EQ(counts_["r.POSE"], 50);
  EXPECT_EQ(counts_["r.IMU"], 100);
  EXPECT_EQ(counts_["SIM.CLOCK"], 100);
  EXPECT_EQ(last_pose.utime, 1000000);
  EXPECT_EQ(last_pose.robot, "r");
  EXPECT_EQ(last_slice.utime, 1000000);
  EXPECT_EQ(last_slice.slice_index, 9);
  EXPECT_EQ(last_slice.slice_count, 10);
  // The slice round-trips through the product's conversion.
  const auto slice = runtime::FromLcm(last_slice);
  ASSERT_TRUE(slice.ok()) << slice.status().ToString();
  EXPECT_GT(slice->points.size(), 1000u);
  EXPECT_EQ(last_slice.num_rays, 180 * 32);
  EXPECT_DOUBLE_EQ(last_slice.range_resolution_m, 0.002);
}

TEST(SimServiceClockTest, ClockIsCappedInWallTimeWhenRunningFast) {
  InstallMujocoLogHooks();
  Scenario s = InlineScenario(FlatWorld(), "", "");
  MujocoSim sim(s);
  runtime::NodeOptions options;
  options.process_name = "cairn-sim";
  options.lcm_url = "memq://";
  options.install_signal_handlers = false;
  runtime::Node node(options);
  int64_t clocks = 0;
  node.SubscribeRaw("SIM.CLOCK", [&](const std::string&, const void*, int, int64_t) { ++clocks; });
  SimServiceParams params;
  params.max_clock_rate_hz = 50.0;
  SimService dut(node, sim, params);
  const auto start = std::chrono::steady_clock::now();
  dut.StepAndPublish(2500);  // 5 s of simulated time: 500 clock ticks
  const double wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  dut.HandlePending();
  EXPECT_LE(clocks, static_cast<int64_t>(50.0 * wall_s) + 2);
  EXPECT_GE(clocks, 1);
}

TEST_F(SimServiceTest, NanCommandsAreDroppedAndCountedClampedOnesCounted) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  Command(nan, 0.0);
  Command(0.1, std::numeric_limits<double>::infinity());
  EXPECT_EQ(node_->counter("nan_commands"), 2);
  EXPECT_EQ(node_->MakeHealth().dropped_inputs, 2);
  Command(3.0, 0.0);
  EXPECT_EQ(node_->counter("clamped_commands"), 1);
  Command(0.2, 0.0, "someone_else");
  EXPECT_EQ(node_->counter("wrong_robot_commands"), 1);
  // A good command still drives the robot.
  for (int i = 0; i < 10; ++i) {
    Command(0.4, 0.0, "r");
    dut_->StepAndPublish(50);
  }
  EXPECT_GT(sim_->RobotPose("r").position_m.x(), 0.3);
}

// The velocity bridge's requests on <robot>.BODY_VELOCITY_REQ drive the robot by surge and yaw;
// disabled axes are ignored, enabled axes it cannot follow are counted and ignored, NaN is
// dropped, another robot's request is dropped.
TEST_F(SimServiceTest, BodyVelocityRequestsDriveBySurgeAndYaw) {
  auto request = [&](double vx, double wz, const std::string& robot = "r") {
    cairn::lcmt_body_velocity_request r{};
    r.robot = robot;
    r.requester = "Twist2BVR";
    r.twist[0] = vx;
    r.twist[5] = wz;
    for (int i = 0; i < 6; ++i) r.disable_axis[i] = i != 0 && i != 5;
    return r;
  };
  auto send = [&](const cairn::lcmt_body_velocity_request& r) {
    node_->Publish("r.BODY_VELOCITY_REQ", r);
    dut_->HandlePending();
  };
  send(request(std::numeric_limits<double>::quiet_NaN(), 0.0));
  EXPECT_EQ(node_->counter("nan_commands"), 1);
  send(request(0.2, 0.0, "someone_else"));
  EXPECT_EQ(node_->counter("wrong_robot_commands"), 1);
  auto heave = request(0.3, 0.0);
  heave.disable_axis[2] = false;
  heave.twist[2] = 0.5;
  send(heave);
  EXPECT_EQ(node_->counter("ignored_axis_requests"), 1);
  EXPECT_EQ(sim_->drive("r").target_linear_mps(), 0.3);
  auto no_yaw = request(0.3, 0.4);
  no_yaw.disable_axis[5] = true;  // a disabled yaw is no turn
  send(no_yaw);
  EXPECT_EQ(sim_->drive("r").target_angular_radps(), 0.0);
  for (int i = 0; i < 10; ++i) {
    send(request(0.4, 0.0));
    dut_->StepAndPublish(50);
  }
  EXPECT_GT(sim_->RobotPose("r").position_m.x(), 0.3);
}

TEST_F(SimServiceTest, ControlRepliesAndReplays) {
  Request spawn = Make(Request::OP_SPAWN, "crate", 1);
  spawn.shape = Request::SHAPE_BOX;
  spawn.size_m[0] = spawn.size_m[1] = spawn.size_m[2] = 0.2;
  spawn.position_m[0] = 3.0;
  spawn.position_m[2] = 0.2;
  Reply reply = Send(spawn);
  EXPECT_EQ(reply.request_id, 1);
  EXPECT_EQ(reply.status, +Reply::STATUS_OK) << reply.message;
  // The same request id again: the first answer, and nothing happens twice.
  reply = Send(spawn);
  EXPECT_EQ(reply.status, +Reply::STATUS_OK);
  EXPECT_EQ(sim_->ObjectNames().size(), 1u);
  // A new id for the same name: already exists.
  spawn.request_id = 2;
  EXPECT_EQ(Send(spawn).status, +Reply::STATUS_ALREADY_EXISTS);
  spawn.request_id = 3;
  spawn.name = "blob";
  spawn.shape = 42;
  EXPECT_EQ(Send(spawn).status, +Reply::STATUS_INVALID);
  EXPECT_GE(node_->counter("bad_control_requests"), 1);

  Request move = Make(Request::OP_MOVE, "crate", 4);
  move.position_m[0] = 5.0;
  EXPECT_EQ(Send(move).status, +Reply::STATUS_OK);
  EXPECT_EQ(Send(Make(Request::OP_REMOVE, "nothing", 5)).status, +Reply::STATUS_NOT_FOUND);
  EXPECT_EQ(Send(Make(Request::OP_OPEN_DOOR, "nope", 6)).status, +Reply::STATUS_NOT_FOUND);

  Reply list = Send(Make(Request::OP_LIST, "", 7));
  EXPECT_EQ(list.status, +Reply::STATUS_OK);
  EXPECT_EQ(list.names, (std::vector<std::string>{"robot:r", "object:crate"}));
  EXPECT_EQ(list.num_names, 2);

  Request reset = Make(Request::OP_RESET_ROBOT, "r", 8);
  reset.position_m[0] = 2.0;
  reset.position_m[1] = -1.0;
  reset.yaw_rad = 0.5;
  EXPECT_EQ(Send(reset).status, +Reply::STATUS_OK);
  EXPECT_NEAR(sim_->RobotPose("r").position_m.x(), 2.0, 1e-9);
  reset.request_id = 9;
  reset.position_m[0] = std::nan("");
  EXPECT_EQ(Send(reset).status, +Reply::STATUS_INVALID);

  EXPECT_EQ(Send(Make(Request::OP_PAUSE, "", 10)).status, +Reply::STATUS_OK);
  EXPECT_TRUE(dut_->paused());
  EXPECT_EQ(Send(Make(Request::OP_RESUME, "", 11)).status, +Reply::STATUS_OK);
  EXPECT_FALSE(dut_->paused());
  Request speed = Make(Request::OP_SET_SPEED, "", 12);
  speed.speed = 4.0;
  EXPECT_EQ(Send(speed).status, +Reply::STATUS_OK);
  EXPECT_EQ(dut_->speed(), 4.0);
  speed.request_id = 13;
  speed.speed = -1.0;
  EXPECT_EQ(Send(speed).status, +Reply::STATUS_INVALID);
  EXPECT_EQ(Send(Make(99, "", 14)).status, +Reply::STATUS_INVALID);
}

TEST_F(SimServiceTest, PausedSimulationStandsStill) {
  EXPECT_EQ(Send(Make(Request::OP_PAUSE, "", 1)).status, +Reply::STATUS_OK);
  const int64_t steps = sim_->physics_steps();
  for (int i = 0; i < 20; ++i) dut_->RunOnce(1);
  EXPECT_EQ(sim_->physics_steps(), steps);
  EXPECT_EQ(Send(Make(Request::OP_RESUME, "", 2)).status, +Reply::STATUS_OK);
  Request speed = Make(Request::OP_SET_SPEED, "", 3);
  speed.speed = 0.0;  // flat out
  Send(speed);
  dut_->RunOnce(1);
  EXPECT_GT(sim_->physics_steps(), steps);
}

TEST_F(SimServiceTest, TriggerSensorParsesRobotSlashSensor) {
  // A continuous turret accepts the trigger (and sweeps on as before).
  Reply reply = Send(Make(Request::OP_TRIGGER_SENSOR, "r/turret", 1));
  EXPECT_EQ(reply.status, +Reply::STATUS_OK) << reply.message;
  EXPECT_EQ(reply.message, "triggered r/turret");
  int64_t id = 2;
  for (const char* bad : {"r", "", "/turret", "r/", "/"}) {
    reply = Send(Make(Request::OP_TRIGGER_SENSOR, bad, id++));
    EXPECT_EQ(reply.status, +Reply::STATUS_INVALID) << "'" << bad << "': " << reply.message;
  }
  EXPECT_EQ(node_->counter("bad_control_requests"), 5);
  for (const char* missing : {"nobody/turret", "r/sonar", "r/turret/x"}) {
    reply = Send(Make(Request::OP_TRIGGER_SENSOR, missing, id++));
    EXPECT_EQ(reply.status, +Reply::STATUS_NOT_FOUND) << missing << ": " << reply.message;
  }
  // A sensor kind without an on-request mode.
  reply = Send(Make(Request::OP_TRIGGER_SENSOR, "r/planar_laser", id++));
  EXPECT_EQ(reply.status, +Reply::STATUS_INVALID) << reply.message;
  EXPECT_NE(reply.message.find("no on-request mode"), std::string::npos) << reply.message;
}

class SimServiceOnRequestTest : public SimServiceTest {
 protected:
  TurretParams Turret() const override {
    TurretParams turret;
    turret.pan_range_deg = 10.0;  // 20 lines a sweep
    turret.pan_step_deg = 0.5;
    turret.on_request = true;
    return turret;
  }
};

TEST_F(SimServiceOnRequestTest, TriggeredTurretPublishesOneSweep) {
  std::vector<cairn::lcmt_laser_scan> lines;
  node_->Subscribe<cairn::lcmt_laser_scan>(
      "r.TURRET_SCAN", [&](const cairn::lcmt_laser_scan& m) { lines.push_back(m); });
  dut_->StepAndPublish(250);  // 0.5 s: idle
  dut_->HandlePending();
  EXPECT_TRUE(lines.empty());
  const Reply reply = Send(Make(Request::OP_TRIGGER_SENSOR, "r/turret", 1));
  ASSERT_EQ(reply.status, +Reply::STATUS_OK) << reply.message;
  dut_->StepAndPublish(500);  // 1 s: one 0.4 s sweep
  dut_->HandlePending();
  ASSERT_EQ(lines.size(), 20u);
  for (size_t k = 0; k < lines.size(); ++k) {
    EXPECT_NEAR(lines[k].turret_angle_rad, k * 0.5 * M_PI / 180.0, 1e-6) << k;
  }
  EXPECT_GT(lines.front().utime, 500000);
}

TEST(ParseSpeedTest, AcceptsMaxAndNonNegativeNumbers) {
  EXPECT_EQ(ParseSpeed("max"), 0.0);
  EXPECT_EQ(ParseSpeed("1"), 1.0);
  EXPECT_EQ(ParseSpeed("2.5"), 2.5);
  EXPECT_THROW(ParseSpeed("fast"), std::invalid_argument);
  EXPECT_THROW(ParseSpeed("-1"), std::invalid_argument);
  EXPECT_THROW(ParseSpeed("nan"), std::invalid_argument);
}

}  // namespace
}  // namespace cairn::sim
