// cairn-sim as a real process on a private LCM bus: sensor rates, physics on the tunnel's
// features, SIM.CONTROL, bad input, repeatability, start-up errors and --help.

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <set>

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>

#include "cairn/lcmt_laser_scan.hpp"
#include "cairn/lcmt_lidar_ranges.hpp"
#include "cairn/lcmt_pose.hpp"
#include "cairn/lcmt_sim_clock.hpp"
#include "cairn/lcmt_sim_control_reply.hpp"
#include "cairn/lcmt_sim_control_request.hpp"
#include "cairn/lcmt_velocity_command.hpp"

#include "services/runtime/conversions.h"
#include "tests/support/harness.h"

namespace cairn::testing {
namespace {

using Request = cairn::lcmt_sim_control_request;
using Reply = cairn::lcmt_sim_control_reply;

void PumpAll(Bus& bus) {
  bus.Pump(5);
  for (int i = 0; i < 200; ++i) {
    if (bus.lcm().handleTimeout(0) <= 0) break;
  }
}

std::string WriteFile(const std::string& dir, const std::string& name, const std::string& text) {
  const std::string path = dir + "/" + name;
  std::ofstream(path) << text;
  return path;
}

void SendCommand(Bus& bus, const std::string& robot, double v, double w) {
  cairn::lcmt_velocity_command cmd{};
  cmd.utime = 0;
  cmd.robot = robot;
  cmd.source = "sim_integration_test";
  cmd.linear_mps = v;
  cmd.angular_radps = w;
  bus.Publish(robot + ".CMD_VEL", cmd);
}

std::optional<cairn::lcmt_pose> Pose(const Bus& bus, const std::string& robot) {
  return bus.Last<cairn::lcmt_pose>(robot + ".POSE");
}

double Yaw(const cairn::lcmt_pose& p) {
  const double* q = p.orientation_wxyz;
  return std::atan2(2.0 * (q[0] * q[3] + q[1] * q[2]), 1.0 - 2.0 * (q[2] * q[2] + q[3] * q[3]));
}

// Drives `robot` along the line y = lane_y towards +x with a heading controller, sending
// commands at about 20 Hz of wall time, until `done(pose)` or the timeout. Returns the poses
// seen on the way.
std::vector<cairn::lcmt_pose> DriveAlongLane(
    Bus& bus, const std::string& robot, double lane_y, double speed_mps, double timeout_s,
    const std::function<bool(const cairn::lcmt_pose&)>& done) {
  std::vector<cairn::lcmt_pose> seen;
  auto last_send = std::chrono::steady_clock::now() - std::chrono::seconds(1);
  WaitFor(
      [&] {
        auto pose = Pose(bus, robot);
        if (pose && (seen.empty() || pose->utime != seen.back().utime)) seen.push_back(*pose);
        if (pose && done(*pose)) return true;
        const auto now = std::chrono::steady_clock::now();
        if (pose && now - last_send > std::chrono::milliseconds(50)) {
          const double heading = -0.8 * (pose->position_m[1] - lane_y) - 1.5 * Yaw(*pose);
          SendCommand(bus, robot, speed_mps, std::clamp(heading, -0.5, 0.5));
          last_send = now;
        }
        return false;
      },
      timeout_s, [&] { PumpAll(bus); });
  SendCommand(bus, robot, 0.0, 0.0);
  return seen;
}

Reply SendControl(Bus& bus, Request request, double timeout_s = 10.0) {
  request.requester = "sim_integration_test";
  bus.Publish("SIM.CONTROL", request);
  std::optional<Reply> reply;
  WaitFor(
      [&] {
        auto r = bus.Last<Reply>("SIM.CONTROL_REPLY");
        if (r && r->request_id == request.request_id) reply = r;
        return reply.has_value();
      },
      timeout_s, [&] { PumpAll(bus); });
  EXPECT_TRUE(reply.has_value()) << "no reply to request " << request.request_id;
  return reply.value_or(Reply{});
}

std::map<std::string, double> OutgoingRates(const cairn::lcmt_health& h) {
  std::map<std::string, double> rates;
  for (const auto& c : h.channels) {
    if (c.outgoing) rates[c.channel] = c.rate_hz;
  }
  return rates;
}

int64_t Counter(const cairn::lcmt_health& h, const std::string& name) {
  for (int i = 0; i < h.num_counters; ++i) {
    if (h.counter_names[i] == name) return h.counter_values[i];
  }
  return 0;
}

// --- rates -------------------------------------------------------------------------------------

TEST(SimIntegrationTest, PublishesEverySensorAtItsConfiguredRate) {
  ProcessSet procs(PrivateLcmUrl());
  // Every sensor on, several at rates other than their defaults.
  const std::string scenario = WriteFile(procs.dir(), "rates.yaml", R"(
world: tunnel
seed: 3
clock_rate_hz: 50
robots:
  - id: p3at
    model: pioneer3at
    spawn: {x_m: 4.0, y_m: 6.0, yaw_deg: 0}
    sensors:
      hdl32e: {}
      planar_laser: {rate_hz: 15}
      turret: {line_rate_hz: 40}
      odometry: {rate_hz: 40}
      imu: {rate_hz: 80}
      ground_truth: {rate_hz: 25}
)");
  ChildProcess& sim = procs.Start("cairn-sim", {"--scenario", scenario, "--speed", "1"});
  Bus bus(procs.url());
  const std::map<std::string, double> expected = {
      {"p3at.LIDAR_RANGES", 10.0 * 10},  // 10 revolutions/s, 10 slices each
      {"p3at.SCAN", 15.0},
      {"p3at.TURRET_SCAN", 40.0},
      {"p3at.ODOM", 40.0},
      {"p3at.IMU", 80.0},
      {"p3at.POSE", 25.0},
      {"SIM.CLOCK", 50.0}};
  auto within = [&](const std::map<std::string, double>& rates) {
    for (const auto& [channel, hz] : expected) {
      auto it = rates.find(channel);
      if (it == rates.end() || std::abs(it->second - hz) > 0.12 * hz) return false;
    }
    return true;
  };
  std::map<std::string, double> rates;
  const bool ok = WaitFor(
      [&] {
        auto h = bus.Health("cairn-sim");
        if (!h) return false;
        rates = OutgoingRates(*h);
        return within(rates);
      },
      30.0, [&] { PumpAll(bus); });
  for (const auto& [channel, hz] : expected) {
    EXPECT_NEAR(rates[channel], hz, 0.12 * hz) << channel;
  }
  EXPECT_TRUE(ok);
  EXPECT_TRUE(sim.Running());
  // Messages carry sim time and the slices decode into a full turn.
  auto clock = bus.Last<cairn::lcmt_sim_clock>("SIM.CLOCK");
  auto pose = Pose(bus, "p3at");
  ASSERT_TRUE(clock && pose);
  EXPECT_LT(std::abs(clock->utime - pose->utime), 1000000);
  EXPECT_GT(clock->real_time_factor, 0.8);
  EXPECT_EQ(clock->target_speed, 1.0);
  auto slice = bus.Last<cairn::lcmt_lidar_ranges>("p3at.LIDAR_RANGES");
  ASSERT_TRUE(slice.has_value());
  EXPECT_EQ(slice->slice_count, 10);
  EXPECT_EQ(slice->num_rays, 180 * 32);
  // 3 bytes a ray and a header: 17 KB, where points took 17 bytes each.
  EXPECT_LT(slice->getEncodedSize(), 3 * 180 * 32 + 512);
  auto points = cairn::runtime::FromLcm(*slice);
  ASSERT_TRUE(points.ok()) << points.status().ToString();
  EXPECT_GT(points->points.size(), 1000u);
  EXPECT_FALSE(bus.Seen("p3at.LIDAR"));  // no float points besides
  // SIGTERM: a clean exit.
  const int status = sim.Stop(10.0);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "status " << status;
}

// --- many robots --------------------------------------------------------------------------------

TEST(SimIntegrationTest, EightPioneersInTheTunnelStartAndPublishEveryRobotsStreams) {
  // Formerly refused at start ("could not create mjData": buffers sized 300 contacts and 1800
  // constraint rows per robot, some of them squared). Every robot's every stream must be on the
  // bus within a bounded wait, and MuJoCo must not have warned (a full contact buffer would).
  ProcessSet procs(PrivateLcmUrl());
  std::vector<std::string> args = {"--world", "tunnel", "--speed", "1"};
  std::vector<std::string> robots;
  for (int i = 0; i < 8; ++i) {
    robots.push_back("fleet" + std::to_string(i));
    args.push_back("--robot");
    args.push_back(robots.back() + ":pioneer3at::4," + std::to_string(2 + 4 * i));
  }
  const auto start = std::chrono::steady_clock::now();
  ChildProcess& sim = procs.Start("cairn-sim", args);
  Bus bus(procs.url());
  const std::vector<std::string> streams = {"LIDAR_RANGES", "SCAN", "ODOM", "POSE", "IMU"};
  std::vector<std::string> missing;
  const bool all = WaitFor(
      [&] {
        missing.clear();
        for (const auto& r : robots) {
          for (const auto& s : streams) {
            if (!bus.Seen(r + "." + s)) missing.push_back(r + "." + s);
          }
        }
        return missing.empty();
      },
      20.0, [&] { PumpAll(bus); });
  const double waited_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_TRUE(all) << missing.size() << " streams never seen, the first "
                   << (missing.empty() ? "" : missing.front());
  std::printf("8 robots: every stream seen %.2f s after the start\n", waited_s);
  ASSERT_TRUE(sim.Running());
  for (const auto& r : robots) {
    auto slice = bus.Last<cairn::lcmt_lidar_ranges>(r + ".LIDAR_RANGES");
    ASSERT_TRUE(slice.has_value()) << r;
    EXPECT_EQ(slice->robot, r);
    auto points = cairn::runtime::FromLcm(*slice);
    ASSERT_TRUE(points.ok()) << r << ": " << points.status().ToString();
    EXPECT_GT(points->points.size(), 0u) << r;
    auto pose = Pose(bus, r);
    ASSERT_TRUE(pose.has_value()) << r;
    EXPECT_NEAR(pose->position_m[1], 2.0 + 4.0 * (&r - robots.data()), 0.2) << r;
  }
  std::optional<cairn::lcmt_health> health;
  ASSERT_TRUE(WaitFor([&] { return (health = bus.Health("cairn-sim")).has_value(); }, 5.0,
                      [&] { PumpAll(bus); }));
  EXPECT_EQ(Counter(*health, "mujoco_warnings"), 0);
  const int status = sim.Stop(10.0);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "status " << status;
}

// --- physics on the tunnel's lanes -------------------------------------------------------------

TEST(SimIntegrationTest, Pioneer3AtDrivenUpTheFiveDegreeRampReachesTheTop) {
  ProcessSet procs(PrivateLcmUrl());
  // Lane 1 of tunnel_lanes.yaml: 5 deg ramp x 8.0..11.43 up to a 0.3 m platform.
  procs.Start("cairn-sim",
              {"--world", "tunnel", "--robot", "p3at:pioneer3at:pioneer3at:4,6,0", "--speed", "3"});
  Bus bus(procs.url());
  ASSERT_TRUE(WaitFor([&] { return Pose(bus, "p3at").has_value(); }, 20.0, [&] { PumpAll(bus); }));
  const auto poses = DriveAlongLane(bus, "p3at", 6.0, 0.5, 60.0, [](const cairn::lcmt_pose& p) {
    return p.position_m[0] > 13.5;
  });
  ASSERT_FALSE(poses.empty());
  const auto& last = poses.back();
  EXPECT_GT(last.position_m[0], 13.5) << "did not get past the ramp";
  // On the platform: base at 0.3 m + wheel radius.
  EXPECT_NEAR(last.position_m[2], 0.3 + 0.1075, 0.03);
  EXPECT_NEAR(last.position_m[1], 6.0, 0.5);
}

TEST(SimIntegrationTest, Pioneer3AtDrivenAtTheTwentyCentimetreStepDoesNotClimbIt) {
  ProcessSet procs(PrivateLcmUrl());
  // Lane 5: a 20 cm block from x = 10.0 to the end wall.
  procs.Start("cairn-sim", {"--world", "tunnel", "--robot", "p3at:pioneer3at:pioneer3at:4,22,0",
                            "--speed", "3"});
  Bus bus(procs.url());
  ASSERT_TRUE(WaitFor([&] { return Pose(bus, "p3at").has_value(); }, 20.0, [&] { PumpAll(bus); }));
  // Push against the step for 20 s of sim time after reaching it.
  double reached_utime = -1;
  const auto poses = DriveAlongLane(bus, "p3at", 22.0, 0.5, 45.0, [&](const cairn::lcmt_pose& p) {
    if (reached_utime < 0 && p.position_m[0] > 9.3) reached_utime = static_cast<double>(p.utime);
    return reached_utime >= 0 && p.utime - reached_utime > 20e6;
  });
  ASSERT_GT(reached_utime, 0) << "never reached the step";
  double max_x = 0.0, max_z = 0.0;
  for (const auto& p : poses) {
    max_x = std::max(max_x, p.position_m[0]);
    max_z = std::max(max_z, p.position_m[2]);
  }
  EXPECT_LT(max_x, 10.0 - 0.2) << "the base went over the step edge";
  EXPECT_LT(max_z, 0.1075 + 0.08) << "the base rose onto the step";
}

// --- SIM.CONTROL -------------------------------------------------------------------------------

// Counts lidar points of one full revolution (the first after a given time) inside a box of
// the sensor frame, as the slices arrive.
class SliceCounter {
 public:
  explicit SliceCounter(Bus& bus) : bus_(bus) {
    bus.lcm().subscribe("p3at.LIDAR_RANGES", &SliceCounter::OnSlice, this);
  }

  int Count(int64_t after_utime, double x0, double x1, double half_width, double z_min) {
    after_utime_ = after_utime;
    x0_ = x0;
    x1_ = x1;
    half_width_ = half_width;
    z_min_ = z_min;
    revolution_ = -1;
    slice_count_ = 0;
    slices_.clear();
    WaitFor([&] { return slice_count_ > 0 && slices_.size() == slice_count_; }, 20.0,
            [&] { PumpAll(bus_); });
    EXPECT_EQ(slices_.size(), 10u) << "missing slices of a revolution";
    int total = 0;
    for (const auto& [index, n] : slices_) total += n;
    after_utime_ = std::numeric_limits<int64_t>::max();
    return total;
  }

 private:
  void OnSlice(const lcm::ReceiveBuffer*, const std::string&, const cairn::lcmt_lidar_ranges* s) {
    if (s->utime <= after_utime_) return;
    if (revolution_ < 0 && s->slice_index == 0) {
      revolution_ = s->revolution;
      slice_count_ = static_cast<size_t>(s->slice_count);
    }
    if (s->revolution != revolution_) return;
    auto slice = cairn::runtime::FromLcm(*s);
    ASSERT_TRUE(slice.ok()) << slice.status().ToString();
    int n = 0;
    for (const auto& p : slice->points) {
      if (p.x_m > x0_ && p.x_m < x1_ && std::abs(p.y_m) < half_width_ && p.z_m > z_min_) ++n;
    }
    slices_[s->slice_index] = n;
  }

  Bus& bus_;
  int64_t after_utime_{std::numeric_limits<int64_t>::max()};
  double x0_{0}, x1_{0}, half_width_{0}, z_min_{0};
  int64_t revolution_{-1};
  size_t slice_count_{0};  // of that revolution
  std::map<int, int> slices_;
};

TEST(SimIntegrationTest, ObjectSpawnedThroughSimControlIsHitByTheLidar) {
  ProcessSet procs(PrivateLcmUrl());
  // Lane 0, facing +x; the lane's cube is 4.9 m ahead of the lidar.
  procs.Start("cairn-sim", {"--world", "tunnel", "--robot", "p3at:pioneer3at:pioneer3at:4,2,0"});
  Bus bus(procs.url());
  SliceCounter counter(bus);
  ASSERT_TRUE(WaitFor([&] { return Pose(bus, "p3at").has_value(); }, 20.0, [&] { PumpAll(bus); }));
  const double sensor_x = 4.0 + 0.12;  // lidar mount on the base

  // Before: nothing above the floor 1.5..1.9 m ahead of the lidar (the floor is at z = -0.33).
  const int before = counter.Count(Pose(bus, "p3at")->utime, 1.5, 1.9, 0.45, -0.25);
  EXPECT_EQ(before, 0);

  Request spawn{};
  spawn.request_id = 1;
  spawn.op = Request::OP_SPAWN;
  spawn.name = "crate";
  spawn.shape = Request::SHAPE_BOX;
  spawn.size_m[0] = 0.2;
  spawn.size_m[1] = 0.5;
  spawn.size_m[2] = 0.4;
  spawn.position_m[0] = 6.0;  // near face at x = 5.8
  spawn.position_m[1] = 2.0;
  spawn.position_m[2] = 0.4;
  const Reply reply = SendControl(bus, spawn);
  ASSERT_EQ(reply.status, +Reply::STATUS_OK) << reply.message;

  const double face = 5.8 - sensor_x;
  const int after = counter.Count(reply.utime, face - 0.1, face + 0.1, 0.45, -0.25);
  EXPECT_GT(after, 50) << "the lidar does not see the spawned box";

  // Removed again: gone from the cloud.
  Request remove{};
  remove.request_id = 2;
  remove.op = Request::OP_REMOVE;
  remove.name = "crate";
  const Reply removed = SendControl(bus, remove);
  ASSERT_EQ(removed.status, +Reply::STATUS_OK) << removed.message;
  EXPECT_EQ(counter.Count(removed.utime, 1.5, 1.9, 0.45, -0.25), 0);
  // Replaying request 1 returns its first reply and spawns nothing.
  const Reply replay = SendControl(bus, spawn);
  EXPECT_EQ(replay.status, +Reply::STATUS_OK);
  EXPECT_EQ(replay.utime, reply.utime);
  Request list{};
  list.request_id = 3;
  list.op = Request::OP_LIST;
  EXPECT_EQ(SendControl(bus, list).names, std::vector<std::string>{"robot:p3at"});
}

// --- bad input ---------------------------------------------------------------------------------

TEST(SimIntegrationTest, MalformedAndNanCommandsAreCountedAndTheProcessKeepsRunning) {
  ProcessSet procs(PrivateLcmUrl());
  ChildProcess& sim = procs.Start(
      "cairn-sim",
      {"--world", "tunnel", "--robot", "p3at:pioneer3at:pioneer3at:4,14,0", "--speed", "2"});
  Bus bus(procs.url());
  ASSERT_TRUE(WaitFor([&] { return Pose(bus, "p3at").has_value(); }, 20.0, [&] { PumpAll(bus); }));
  // Garbage bytes, a truncated command, NaN and infinite values.
  const char garbage[] = "definitely not a velocity command";
  bus.lcm().publish("p3at.CMD_VEL", garbage, sizeof(garbage));
  cairn::lcmt_velocity_command cmd{};
  cmd.robot = "p3at";
  cmd.linear_mps = 0.3;
  std::vector<uint8_t> bytes(cmd.getEncodedSize());
  cmd.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  bus.lcm().publish("p3at.CMD_VEL", bytes.data(), static_cast<int>(bytes.size()) / 2);
  SendCommand(bus, "p3at", std::numeric_limits<double>::quiet_NaN(), 0.0);
  SendCommand(bus, "p3at", 0.2, std::numeric_limits<double>::infinity());
  SendCommand(bus, "p3at", 9.0, 0.0);  // beyond the profile: clamped
  std::optional<cairn::lcmt_health> health;
  EXPECT_TRUE(WaitFor(
      [&] {
        health = bus.Health("cairn-sim");
        return health && health->decode_errors >= 2 && health->dropped_inputs >= 2 &&
               Counter(*health, "clamped_commands") >= 1;
      },
      15.0, [&] { PumpAll(bus); }));
  ASSERT_TRUE(health.has_value());
  EXPECT_GE(health->decode_errors, 2);
  EXPECT_GE(Counter(*health, "nan_commands"), 2);
  EXPECT_GE(Counter(*health, "clamped_commands"), 1);
  EXPECT_TRUE(sim.Running());
  // Still obeys good commands.
  const double x0 = Pose(bus, "p3at")->position_m[0];
  const auto poses = DriveAlongLane(bus, "p3at", 14.0, 0.4, 30.0, [&](const cairn::lcmt_pose& p) {
    return p.position_m[0] > x0 + 1.0;
  });
  EXPECT_GT(poses.back().position_m[0], x0 + 1.0);
  EXPECT_TRUE(sim.Running());
}

TEST(SimIntegrationTest, BrokenWorldOrUnknownRobotStopsStartUpWithTheReason) {
  ProcessSet procs(PrivateLcmUrl());
  const std::string bad = WriteFile(procs.dir(), "bad_world.xml",
                                    "<mujoco>\n<worldbody>\n<geom type=\"box\" size=\"1 1\"/>\n"
                                    "</worldbody>\n</mujoco>\n");
  ChildProcess& broken = procs.Start("cairn-sim", {"--world", bad, "--robot", "a:kobuki"});
  auto status = broken.WaitExit(20.0);
  ASSERT_TRUE(status.has_value());
  EXPECT_TRUE(WIFEXITED(*status) && WEXITSTATUS(*status) != 0);
  EXPECT_NE(broken.Log().find("bad_world.xml"), std::string::npos) << broken.Log();
  EXPECT_NE(broken.Log().find("size"), std::string::npos) << broken.Log();  // MuJoCo's words

  ChildProcess& unknown =
      procs.Start("cairn-sim", {"--world", "tunnel", "--robot", "a:hovercraft"});
  status = unknown.WaitExit(20.0);
  ASSERT_TRUE(status.has_value());
  EXPECT_TRUE(WIFEXITED(*status) && WEXITSTATUS(*status) != 0);
  EXPECT_NE(unknown.Log().find("unknown robot model 'hovercraft'"), std::string::npos)
      << unknown.Log();
}

TEST(SimIntegrationTest, HelpListsWorldsRobotsAndSensors) {
  ProcessSet procs(PrivateLcmUrl());
  ChildProcess& help = procs.StartRaw("cairn-sim", {BinPath("cairn-sim"), "--help"});
  auto status = help.WaitExit(20.0);
  ASSERT_TRUE(status.has_value());
  EXPECT_TRUE(WIFEXITED(*status) && WEXITSTATUS(*status) == 0);
  const std::string text = help.Log();
  for (const char* word : {"worlds:", "tunnel", "apartment", "outdoor", "arena", "robots:",
                           "pioneer3at", "kobuki", "p3dx", "sensors:", "hdl32e", "planar_laser",
                           "turret", "odometry", "imu", "ground_truth", "--speed", "--scenario"}) {
    EXPECT_NE(text.find(word), std::string::npos) << word;
  }
}

// --- repeatability -----------------------------------------------------------------------------

TEST(SimIntegrationTest, DataAndConfigFoldersComeFromTheFlags) {
  ProcessSet procs(PrivateLcmUrl());
  // An empty data folder has no shipped worlds; the message lists what it found (none).
  ChildProcess& empty = procs.Start(
      "cairn-sim", {"--data-dir", procs.dir(), "--world", "tunnel", "--robot", "a:kobuki"});
  auto status = empty.WaitExit(20.0);
  ASSERT_TRUE(status.has_value());
  EXPECT_TRUE(WIFEXITED(*status) && WEXITSTATUS(*status) != 0);
  EXPECT_NE(empty.Log().find("unknown world 'tunnel'"), std::string::npos) << empty.Log();
  // The config folder holds the profiles.
  ChildProcess& no_profiles = procs.Start(
      "cairn-sim", {"--config-dir", procs.dir(), "--world", "tunnel", "--robot", "a:kobuki"});
  status = no_profiles.WaitExit(20.0);
  ASSERT_TRUE(status.has_value());
  EXPECT_TRUE(WIFEXITED(*status) && WEXITSTATUS(*status) != 0);
  EXPECT_NE(no_profiles.Log().find("unknown profile 'kobuki'"), std::string::npos)
      << no_profiles.Log();
}

TEST(SimIntegrationTest, SameSeedAtMaxSpeedRepeatsTheRun) {
  // Three runs, each on its own bus: seeds 5, 5 and 6.
  ProcessSet procs(PrivateLcmUrl());
  // Scripted driving into the cube of lane 0 (contact-rich), noisy laser and odometry.
  const std::string scenario = WriteFile(procs.dir(), "repeat.yaml", R"(
world: tunnel
seed: 5
clock_rate_hz: 10  # at full speed (over 100x) the default rates would flood the test's bus
robots:
  - id: r
    model: pioneer3at
    spawn: {x_m: 4.0, y_m: 2.3, yaw_deg: 0}
    sensors:
      planar_laser: {rate_hz: 5}
      odometry: {rate_hz: 10, slip_noise_ratio: 0.05}
      ground_truth: {rate_hz: 10}
    commands:
      - {at_s: 0.0, duration_s: 12.0, linear_mps: 0.5, angular_radps: 0.05}
      - {at_s: 12.0, duration_s: 4.0, linear_mps: -0.2, angular_radps: 0.6}
)");
  struct Run {
    ChildProcess* process;
    std::unique_ptr<Bus> bus;
  };
  // One run after another, each on its own bus: three simulators at full speed at once would
  // outrun the test's receive buffer on a 2-core machine.
  std::vector<Run> runs;
  for (int seed : {5, 5, 6}) {
    const std::string url = runs.empty() ? procs.url() : PrivateLcmUrl();
    Run run;
    run.bus = std::make_unique<Bus>(url);
    run.bus->Keep("r.POSE");
    run.bus->Keep("r.SCAN");
    run.process =
        &procs.StartRaw("cairn-sim", {BinPath("cairn-sim"), "--scenario", scenario, "--speed",
                                      "max", "--seed", std::to_string(seed), "--lcm-url", url});
    // Until it has published 16 s of simulated time.
    ASSERT_TRUE(WaitFor(
        [&] {
          PumpAll(*run.bus);
          auto pose = Pose(*run.bus, "r");
          return pose && pose->utime >= 16000000;
        },
        120.0))
        << "seed " << seed;
    run.process->Stop();
    PumpAll(*run.bus);
    runs.push_back(std::move(run));
  }
  auto poses = [](Bus& bus) {
    std::map<int64_t, cairn::lcmt_pose> out;
    for (const auto& bytes : bus.Kept("r.POSE")) {
      cairn::lcmt_pose p;
      if (p.decode(bytes.data(), 0, static_cast<int>(bytes.size())) >= 0) out[p.utime] = p;
    }
    return out;
  };
  auto scans = [](Bus& bus) {
    std::map<int64_t, std::vector<float>> out;
    for (const auto& bytes : bus.Kept("r.SCAN")) {
      cairn::lcmt_laser_scan s;
      if (s.decode(bytes.data(), 0, static_cast<int>(bytes.size())) >= 0) out[s.utime] = s.ranges_m;
    }
    return out;
  };
  const auto a = poses(*runs[0].bus), b = poses(*runs[1].bus), c = poses(*runs[2].bus);
  int compared = 0;
  double moved = 0.0;
  for (const auto& [utime, pa] : a) {
    auto it = b.find(utime);
    if (it == b.end()) continue;  // lost on the bus
    ++compared;
    for (int i = 0; i < 3; ++i) ASSERT_EQ(pa.position_m[i], it->second.position_m[i]) << utime;
    for (int i = 0; i < 4; ++i) {
      ASSERT_EQ(pa.orientation_wxyz[i], it->second.orientation_wxyz[i]) << utime;
    }
    moved = std::max(moved, std::hypot(pa.position_m[0] - 4.0, pa.position_m[1] - 2.3));
  }
  // At full speed UDP may drop some messages; every pair received from both runs must match.
  EXPECT_GT(compared, 80);
  EXPECT_GT(moved, 3.0);  // it really drove (into the cube)
  // Physics does not depend on the seed; sensor noise does.
  int same_pose = 0;
  for (const auto& [utime, pa] : a) {
    auto it = c.find(utime);
    if (it != c.end() && pa.position_m[0] == it->second.position_m[0]) ++same_pose;
  }
  EXPECT_GT(same_pose, 80);
  const auto sa = scans(*runs[0].bus), sb = scans(*runs[1].bus), sc = scans(*runs[2].bus);
  int same_seed_equal = 0, other_seed_equal = 0, both = 0;
  for (const auto& [utime, ra] : sa) {
    auto ib = sb.find(utime);
    auto ic = sc.find(utime);
    if (ib == sb.end() || ic == sc.end()) continue;
    ++both;
    // Bitwise, so readings too close to measure (NaN) compare equal to themselves.
    auto same = [](const std::vector<float>& x, const std::vector<float>& y) {
      return x.size() == y.size() && std::memcmp(x.data(), y.data(), x.size() * sizeof(float)) == 0;
    };
    if (same(ra, ib->second)) ++same_seed_equal;
    if (same(ra, ic->second)) ++other_seed_equal;
  }
  EXPECT_GT(both, 30);
  EXPECT_EQ(same_seed_equal, both);
  EXPECT_EQ(other_seed_equal, 0);
}

}  // namespace
}  // namespace cairn::testing
