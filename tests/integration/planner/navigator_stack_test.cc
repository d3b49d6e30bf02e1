// The whole navigation stack as real processes on a private LCM bus: cairn-sim (MuJoCo, the
// tunnel world of seed 000, one Pioneer 3-AT), cairn-mapper (terrain and cost layers) and
// cairn-navigator, a graph under cairn-launch. Lanes, starts and goals:
// simulator/worlds/tunnel_lanes.yaml.

#include <chrono>
#include <csignal>
#include <fstream>
#include <optional>
#include <regex>
#include <sstream>

#include <gtest/gtest.h>

#include "cairn/lcmt_goal.hpp"
#include "cairn/lcmt_grid_manifest.hpp"
#include "cairn/lcmt_nav_status.hpp"
#include "cairn/lcmt_obstacle_registry.hpp"
#include "cairn/lcmt_path.hpp"
#include "cairn/lcmt_pose.hpp"
#include "cairn/lcmt_sim_clock.hpp"
#include "cairn/lcmt_sim_control_reply.hpp"
#include "cairn/lcmt_sim_control_request.hpp"
#include "cairn/lcmt_velocity_command.hpp"

#include "common/channels.h"
#include "common/robot_profile.h"
#include "planner/footprint.h"
#include "services/launch/status.h"
#include "services/runtime/conversions.h"
#include "tests/support/geometry.h"
#include "tests/support/harness.h"
#include "tests/support/registry.h"

namespace cairn::planner {
namespace {

namespace ch = cairn::channels;
using common::Pose2;
using common::Vector2;
using testing::Bus;
using testing::ConvexOverlap;
using testing::ProcessSet;
using testing::WaitFor;

constexpr int kStateReached = cairn::lcmt_nav_status::STATE_REACHED;
constexpr int kStateFailed = cairn::lcmt_nav_status::STATE_FAILED;
constexpr int kStateStopped = cairn::lcmt_nav_status::STATE_STOPPED;
constexpr int kStateDriving = cairn::lcmt_nav_status::STATE_DRIVING;
constexpr int kReasonNoPath = cairn::lcmt_nav_status::REASON_NO_PATH;
constexpr int kReasonStaleMap = cairn::lcmt_nav_status::REASON_STALE_MAP;
constexpr char kRobot[] = "p3at";

std::vector<Vector2> Box(double x0, double y0, double x1, double y1) {
  return {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}};
}

class NavigatorStackTest : public ::testing::Test {
 protected:
  NavigatorStackTest() : url_(testing::PrivateLcmUrl()), procs_(url_), bus_(url_) {
    footprint_ =
        common::LoadRobotProfileFile(testing::SourcePath("config/profiles/pioneer3at.yaml"))
            .footprint_m;
    bus_.Keep(ch::ForRobot(kRobot, ch::kPose));
    bus_.Keep(ch::ForRobot(kRobot, ch::kCmdVel));
    bus_.Keep(ch::ForRobot(kRobot, ch::kMapManifest));
  }

  // The mapper's shipped configuration with the cost layer published every 0.2 s (more often
  // than the navigator's 0.5 s age limit) and only the pioneer3at profile.
  std::string MapperConfig() {
    std::ifstream in(testing::SourcePath("config/mapping/mapper.yaml"));
    std::stringstream text;
    text << in.rdbuf();
    std::string yaml = text.str();
    yaml = std::regex_replace(yaml, std::regex("\\npublish_period_s: [0-9.]+"),
                              "\npublish_period_s: 0.2");
    yaml = std::regex_replace(yaml, std::regex("\\nprofiles: \\[[^\\]]*\\]"),
                              "\nprofiles: [pioneer3at]");
    const std::string path = procs_.dir() + "/mapper.yaml";
    std::ofstream(path) << yaml;
    return path;
  }

  // The shipped navigator configuration, told not to count on unexplored space farther than
  // 12 m from the robot (or 2 m from the goal) when it decides whether a goal is reachable.
  std::string HorizonNavigatorConfig() {
    std::ifstream in(testing::SourcePath("config/navigator/navigator.yaml"));
    std::stringstream text;
    text << in.rdbuf();
    const std::string yaml = std::regex_replace(
        text.str(), std::regex("unknown_horizon_m: [0-9.]+"), "unknown_horizon_m: 12.0");
    EXPECT_NE(yaml, text.str()) << "the navigator config no longer names unknown_horizon_m";
    const std::string path = procs_.dir() + "/navigator.yaml";
    std::ofstream(path) << yaml;
    return path;
  }

  // The shipped navigator configuration driving on the simulator's wheel odometry
  // (<robot>.ODOM) instead of ground truth.
  std::string OdometryNavigatorConfig() {
    std::ifstream in(testing::SourcePath("config/navigator/navigator.yaml"));
    std::stringstream text;
    text << in.rdbuf();
    const std::string yaml =
        std::regex_replace(text.str(), std::regex("\npose_source: pose"), "\npose_source: odom");
    EXPECT_NE(yaml, text.str()) << "the navigator config no longer names pose_source: pose";
    const std::string path = procs_.dir() + "/navigator_odom.yaml";
    std::ofstream(path) << yaml;
    return path;
  }

  // The three processes as a graph under cairn-launch (as a user starts them), on the test's
  // private bus; their logs are printed when a test fails. Nothing restarts: a crash fails the
  // test instead of hiding in a restart. `mapper_args` are added to the mapper's arguments.
  void StartStack(double x, double y, double yaw_deg, const std::string& nav_config = "",
                  const std::string& mapper_args = "") {
    const std::string dir = procs_.dir();
    std::ostringstream robot;
    robot << kRobot << ":pioneer3at:pioneer3at:" << x << "," << y << "," << yaw_deg;
    const std::string graph = dir + "/tunnel.yaml";
    {
      std::ofstream out(graph);
      out << "name: tunnel-test\n"
          << "lcm_url: " << url_ << "\n"
          << "processes:\n"
          << "  sim:\n"
          << "    command: " << testing::BinPath("cairn-sim") << "\n"
          << "    args: [--world, tunnel, --robot, '" << robot.str() << "', --speed, '1']\n"
          << "    restart: never\n"
          << "  mapper:\n"
          << "    command: " << testing::BinPath("cairn-mapper") << "\n"
          << "    args: [--robot, " << kRobot << ", --config, " << MapperConfig()
          << (mapper_args.empty() ? std::string() : ", " + mapper_args) << "]\n"
          << "    robot: " << kRobot << "\n"
          << "    depends_on: [sim]\n"
          << "    restart: never\n"
          << "    required: false\n"  // one test kills it and watches the navigator stop
          << "  navigator:\n"
          << "    command: " << testing::BinPath("cairn-navigator") << "\n"
          << "    args: [--robot, " << kRobot << ", --profile, pioneer3at"
          << (nav_config.empty() ? std::string() : ", --config, " + nav_config) << "]\n"
          << "    robot: " << kRobot << "\n"
          << "    depends_on: [mapper]\n"
          << "    restart: never\n";
    }
    run_dir_ = dir + "/run";
    procs_.AddLogDir(run_dir_ + "/logs");
    procs_.StartRaw("cairn-launch",
                    {testing::BinPath("cairn-launch"), "up", graph, "--run-dir", run_dir_});
    // Ready when cairn-launch says so, the cost layer is on the bus and the navigator reports.
    ASSERT_TRUE(WaitFor(
        [&] {
          const auto status = GraphStatus();
          return status && status->state == "ready" && CostManifestSeen() &&
                 bus_.Health("cairn-navigator", kRobot).has_value();
        },
        90.0, [&] { bus_.Pump(20); }))
        << "the stack did not come up";
  }
  std::optional<launch::GraphStatus> GraphStatus() const {
    std::string error;
    return launch::ReadStatusFile(run_dir_ + "/status.json", &error);
  }
  // A process of the graph as cairn-launch reports it.
  std::optional<launch::ProcessRow> Process(const std::string& name) const {
    const auto status = GraphStatus();
    if (!status) return std::nullopt;
    const launch::ProcessRow* row = launch::FindProcess(*status, name);
    return row ? std::optional<launch::ProcessRow>(*row) : std::nullopt;
  }
  bool CostManifestSeen() {
    for (const auto& bytes : bus_.Kept(ch::ForRobot(kRobot, ch::kMapManifest))) {
      cairn::lcmt_grid_manifest m;
      if (m.decode(bytes.data(), 0, static_cast<int>(bytes.size())) >= 0 &&
          m.layer == "cost/pioneer3at" && m.num_tiles > 0) {
        return true;
      }
    }
    return false;
  }

  // Highest layer version of the cost layer seen so far.
  int64_t CostVersion() {
    int64_t v = 0;
    for (const auto& bytes : bus_.Kept(ch::ForRobot(kRobot, ch::kMapManifest))) {
      cairn::lcmt_grid_manifest m;
      if (m.decode(bytes.data(), 0, static_cast<int>(bytes.size())) >= 0 &&
          m.layer == "cost/pioneer3at") {
        v = std::max(v, m.layer_version);
      }
    }
    return v;
  }

  void SendGoal(int64_t id, double x, double y) {
    cairn::lcmt_goal g{};
    g.robot = kRobot;
    g.goal_id = id;
    g.kind = cairn::lcmt_goal::KIND_POSE;
    g.x_m = x;
    g.y_m = y;
    // Re-sent until the status names it (a message on the bus can be lost; re-sends of a goal
    // id are idempotent).
    auto last_sent = std::chrono::steady_clock::now() - std::chrono::seconds(2);
    EXPECT_TRUE(WaitFor(
        [&] {
          auto s = bus_.Last<cairn::lcmt_nav_status>(ch::ForRobot(kRobot, ch::kNavStatus));
          if (s && s->goal_id == id) return true;
          if (std::chrono::steady_clock::now() - last_sent > std::chrono::seconds(1)) {
            bus_.Publish(ch::ForRobot(kRobot, ch::kGoal), g);
            last_sent = std::chrono::steady_clock::now();
          }
          return false;
        },
        15.0, [&] { bus_.Pump(20); }))
        << "the navigator never took goal " << id;
  }
  std::optional<cairn::lcmt_nav_status> Status() {
    return bus_.Last<cairn::lcmt_nav_status>(ch::ForRobot(kRobot, ch::kNavStatus));
  }
  bool WaitState(int state, double timeout_s) {
    return WaitFor(
        [&] {
          auto s = Status();
          return s && s->state == state;
        },
        timeout_s, [&] { bus_.Pump(20); });
  }
  std::string StatusText() {
    auto s = Status();
    if (!s) return "no status";
    std::ostringstream out;
    out << "state " << int(s->state) << " reason " << int(s->reason) << ": " << s->message;
    out << "\nthe navigator's last events:\n"
        << testing::TailOfFile(run_dir_ + "/logs/navigator.log", 25);
    const auto poses = Poses();
    if (!poses.empty()) {
      out << "the robot is at x " << poses.back().position_m[0] << ", y "
          << poses.back().position_m[1] << "\n";
    }
    // What the mapper found explains most failures (a feature labelled wrong blocks a route).
    const auto registry =
        bus_.Last<cairn::lcmt_obstacle_registry>(ch::ForRobot(kRobot, ch::kMapObstacles));
    if (registry) out << "\nthe mapper's registry:\n" << testing::Describe(*registry);
    return out.str();
  }

  // Ground-truth poses so far.
  std::vector<cairn::lcmt_pose> Poses() {
    std::vector<cairn::lcmt_pose> out;
    for (const auto& bytes : bus_.Kept(ch::ForRobot(kRobot, ch::kPose))) {
      cairn::lcmt_pose p;
      if (p.decode(bytes.data(), 0, static_cast<int>(bytes.size())) >= 0) out.push_back(p);
    }
    return out;
  }
  static Pose2 ToPose2(const cairn::lcmt_pose& p) {
    const auto pose = runtime::FromLcm(p);
    return pose.ok() ? pose->ToPose2() : Pose2{};
  }
  // The footprint polygon at a pose.
  // Starts the stack at (x, lane_y) with the 12 m unknown horizon, sends a goal at
  // (goal_x, lane_y) and expects "no path"; whatever the status says, the footprint never
  // overlaps `forbidden` and, with `flat`, the base never rises.
  void ExpectNoPathNeverEntering(double x, double lane_y, int64_t goal_id, double goal_x,
                                 const std::vector<Vector2>& forbidden, double timeout_s,
                                 bool flat) {
    StartStack(x, lane_y, 0.0, HorizonNavigatorConfig());
    if (HasFatalFailure()) return;
    // Let the mapper integrate a few revolutions (the feature in view) before asking.
    ASSERT_TRUE(WaitFor([&] { return CostVersion() >= 5; }, 30.0, [&] { bus_.Pump(20); }));
    SendGoal(goal_id, goal_x, lane_y);
    EXPECT_TRUE(WaitState(kStateFailed, timeout_s)) << StatusText();
    ASSERT_TRUE(Status().has_value());
    EXPECT_EQ(Status()->reason, kReasonNoPath) << StatusText();
    const auto poses = Poses();
    ASSERT_FALSE(poses.empty());
    const double start_z = poses.front().position_m[2];
    for (const auto& p : poses) {
      ASSERT_FALSE(ConvexOverlap(FootprintAt(ToPose2(p)), forbidden, 0.0))
          << "entered the forbidden area at x " << p.position_m[0] << ", y " << p.position_m[1];
      if (flat) {
        ASSERT_LT(p.position_m[2] - start_z, 0.02) << "rose at x " << p.position_m[0];
      }
    }
  }

  std::vector<Vector2> FootprintAt(const Pose2& pose) const {
    std::vector<Vector2> out;
    for (const Vector2& v : footprint_) out.push_back(pose.Transform(v));
    return out;
  }
  std::optional<cairn::lcmt_sim_control_reply> SimControl(cairn::lcmt_sim_control_request r) {
    r.request_id = ++request_id_;
    r.requester = "navigator_stack_test";
    bus_.Publish(ch::kSimControl, r);
    std::optional<cairn::lcmt_sim_control_reply> reply;
    WaitFor(
        [&] {
          auto m = bus_.Last<cairn::lcmt_sim_control_reply>(ch::kSimControlReply);
          if (m && m->request_id == r.request_id) reply = m;
          return reply.has_value();
        },
        10.0, [&] { bus_.Pump(20); });
    return reply;
  }

  std::string url_;
  ProcessSet procs_;
  Bus bus_;
  std::vector<Vector2> footprint_;
  std::string run_dir_;
  int64_t request_id_{0};
};

TEST_F(NavigatorStackTest, ReachesTheGoalBehindTheCubeWithoutTouchingIt) {
  StartStack(4.0, 2.0, 0.0);
  SendGoal(1, 14.0, 2.0);
  ASSERT_TRUE(WaitState(kStateReached, 100.0)) << StatusText();
  const auto poses = Poses();
  ASSERT_FALSE(poses.empty());
  const Pose2 last = ToPose2(poses.back());
  EXPECT_LT(std::hypot(last.x_m - 14.0, last.y_m - 2.0), 0.5);
  // Ground truth: the footprint never touched the 1 m cube (x 9..10, y 1.5..2.5) nor a lane
  // wall (y = 0 and y = 4, 0.2 m thick).
  const auto cube = Box(9.0, 1.5, 10.0, 2.5);
  for (const auto& p : poses) {
    const auto fp = FootprintAt(ToPose2(p));
    ASSERT_FALSE(ConvexOverlap(fp, cube, 0.0)) << "touched the cube at x " << p.position_m[0];
    ASSERT_FALSE(ConvexOverlap(fp, Box(3.0, -0.1, 24.0, 0.1), 0.0)) << "touched the south wall";
    ASSERT_FALSE(ConvexOverlap(fp, Box(3.0, 3.9, 24.0, 4.1), 0.0)) << "touched the lane wall";
  }
}

TEST_F(NavigatorStackTest, ClimbsTheFiveDegreeRampToItsTop) {
  StartStack(4.0, 6.0, 0.0);
  // Let the mapper integrate a few revolutions (the ramp in view) before asking: on the first
  // revolutions alone the ramp may still show edges, and the plan detours through unexplored
  // lanes.
  ASSERT_TRUE(WaitFor([&] { return CostVersion() >= 5; }, 30.0, [&] { bus_.Pump(20); }));
  SendGoal(2, 14.0, 6.0);
  ASSERT_TRUE(WaitState(kStateReached, 100.0)) << StatusText();
  const auto poses = Poses();
  ASSERT_FALSE(poses.empty());
  // On the platform at the top: x 14, z 0.3 (the base's height above the deck it stands on).
  const auto& last = poses.back();
  EXPECT_LT(std::hypot(last.position_m[0] - 14.0, last.position_m[1] - 6.0), 0.5);
  const double start_z = poses.front().position_m[2];
  EXPECT_NEAR(last.position_m[2] - start_z, 0.3, 0.05);
}

TEST_F(NavigatorStackTest, ReportsNoPathOverTheTenDegreeRampAndNeverDrivesOntoIt) {
  // The platform is walled in except for the ramp, but the other lanes (joined by the cross
  // corridor) are unexplored: counting on all unexplored space, the robot would explore them
  // before the verdict could be "no path". With a 12 m horizon the verdict comes at once.
  // Ground truth: the footprint never reaches the ramp (x >= 8.0) and the base never rises.
  ExpectNoPathNeverEntering(4.0, 10.0, 3, 14.0, Box(8.0, 8.1, 24.0, 11.9), 110.0, true);
}

TEST_F(NavigatorStackTest, ReportsNoPathOntoTheTwentyCentimetreStepAndNeverMountsIt) {
  // Lane 5: a 20 cm block from x = 10 to the end wall, wall to wall (pioneer3at: step up 3 cm).
  ExpectNoPathNeverEntering(4.0, 22.0, 6, 14.0, Box(10.0, 20.1, 24.0, 23.9), 110.0, true);
}

// The floor below the drop stays hidden until the robot is close; the rays that pass the edge
// prove only a few centimetres of it from afar, which is enough (traversability.unseen_drop_m):
// the edge is lethal long before the rays could prove more than the 10 cm step-down limit.
TEST_F(NavigatorStackTest, NeverCrossesTheEdgeOfTheTwentyCentimetreDrop) {
  // Lane 6: a 5 deg ramp up to a platform at 0.2 m that ends in a 20 cm drop at x = 13.29, wall
  // to wall; the goal lies past the drop (pioneer3at: step down 10 cm). The floor below the
  // edge is hidden from the robot until it is close: whatever it tries, it must not drive off.
  ExpectNoPathNeverEntering(4.0, 26.0, 7, 17.0, Box(13.3, 24.1, 24.0, 27.9), 150.0, false);
}

TEST_F(NavigatorStackTest, ReplansAroundAnObjectSpawnedOnItsPathAndArrives) {
  StartStack(4.0, 18.0, 0.0);  // lane 4: open floor, a 1 cm plate from x = 10 (traversable)
  SendGoal(4, 14.0, 18.0);
  ASSERT_TRUE(WaitFor(
      [&] {
        const auto poses = Poses();
        return !poses.empty() && poses.back().position_m[0] > 5.5;
      },
      60.0, [&] { bus_.Pump(20); }))
      << StatusText();
  // A 0.8 m crate appears across the straight route ahead.
  cairn::lcmt_sim_control_request spawn{};
  spawn.op = cairn::lcmt_sim_control_request::OP_SPAWN;
  spawn.name = "crate";
  spawn.shape = cairn::lcmt_sim_control_request::SHAPE_BOX;
  spawn.size_m[0] = 0.4;
  spawn.size_m[1] = 0.4;
  spawn.size_m[2] = 0.4;
  spawn.position_m[0] = 10.0;
  spawn.position_m[1] = 18.0;
  spawn.position_m[2] = 0.42;
  const auto reply = SimControl(spawn);
  ASSERT_TRUE(reply.has_value());
  ASSERT_EQ(reply->status, +cairn::lcmt_sim_control_reply::STATUS_OK) << reply->message;
  ASSERT_TRUE(WaitState(kStateReached, 100.0)) << StatusText();
  EXPECT_GE(Status()->replans, 1);
  // Seed 000 exp 5: the robot crossed onto the 1 cm plate (x >= 10) and stands on it.
  const auto poses = Poses();
  ASSERT_FALSE(poses.empty());
  EXPECT_GT(poses.back().position_m[0], 13.5);
  EXPECT_NEAR(poses.back().position_m[2] - poses.front().position_m[2], 0.01, 0.005)
      << "not on the plate";
  const auto crate = Box(9.6, 17.6, 10.4, 18.4);
  for (const auto& p : poses) {
    ASSERT_FALSE(ConvexOverlap(FootprintAt(ToPose2(p)), crate, 0.0))
        << "touched the crate at x " << p.position_m[0] << ", y " << p.position_m[1];
  }
}

TEST_F(NavigatorStackTest, StopsWithinHalfASecondOfSimTimeWhenTheMapperStops) {
  StartStack(4.0, 38.0, 0.0);  // lane 9, the demo route
  SendGoal(5, 21.0, 38.0);
  ASSERT_TRUE(WaitFor(
      [&] {
        auto c = bus_.Last<cairn::lcmt_velocity_command>(ch::ForRobot(kRobot, ch::kCmdVel));
        auto s = Status();
        return s && s->state == kStateDriving && c && c->linear_mps > 0.2;
      },
      60.0, [&] { bus_.Pump(20); }))
      << StatusText();
  // The mapper stops at sim time `killed_utime` or later: the newest pose seen before the kill.
  bus_.Pump(0);
  const auto before_kill = bus_.Last<cairn::lcmt_pose>(ch::ForRobot(kRobot, ch::kPose));
  ASSERT_TRUE(before_kill.has_value());
  const int64_t killed_utime = before_kill->utime;
  const auto mapper = Process("mapper");
  ASSERT_TRUE(mapper.has_value() && mapper->pid > 0);
  ASSERT_EQ(kill(mapper->pid, SIGKILL), 0);
  // cairn-launch sees it go (the graph restarts nothing).
  ASSERT_TRUE(WaitFor(
      [&] {
        const auto row = Process("mapper");
        return row && row->state != "ready" && row->state != "starting";
      },
      5.0, [&] { bus_.Pump(20); }));
  ASSERT_TRUE(WaitState(kStateStopped, 10.0)) << StatusText();
  EXPECT_EQ(Status()->reason, kReasonStaleMap);
  // The first zero command after the kill (sim time).
  int64_t stop_utime = -1;
  for (const auto& bytes : bus_.Kept(ch::ForRobot(kRobot, ch::kCmdVel))) {
    cairn::lcmt_velocity_command c;
    if (c.decode(bytes.data(), 0, static_cast<int>(bytes.size())) < 0) continue;
    if (c.utime > killed_utime && c.linear_mps == 0.0 && c.angular_radps == 0.0) {
      stop_utime = c.utime;
      break;
    }
  }
  ASSERT_GT(stop_utime, 0);
  // 0.5 s, and 0.1 s for the pose the test last saw lagging the sim and process scheduling.
  EXPECT_LE(stop_utime - killed_utime, 500'000 + 100'000)
      << "stopped " << (stop_utime - killed_utime) / 1e3 << " ms of sim time after the kill";
  // Not before the layer could have gone stale (the stop is the mapper's doing).
  EXPECT_GE(stop_utime - killed_utime, 200'000)
      << "stopped " << (stop_utime - killed_utime) / 1e3 << " ms of sim time after the kill";
  // And the robot really stops: its ground-truth speed falls to zero.
  EXPECT_TRUE(WaitFor(
      [&] {
        auto p = bus_.Last<cairn::lcmt_pose>(ch::ForRobot(kRobot, ch::kPose));
        return p && std::hypot(p->linear_velocity_mps[0], p->linear_velocity_mps[1]) < 0.02;
      },
      3.0, [&] { bus_.Pump(20); }));
}


// Every test above drives on ground-truth poses. Here the navigator drives on the simulator's
// wheel odometry (pose_source: odom; frame odom, which starts at the spawn pose) and the mapper
// builds its layers on the same odometry, as on a robot without localisation: map and pose share
// one frame and drift together. Arrival is judged on ground truth.
TEST_F(NavigatorStackTest, DrivesOnOdometryToAGoalAFewMetresAway) {
  StartStack(4.0, 18.0, 0.0, OdometryNavigatorConfig(), "--pose-source, odometry");
  if (HasFatalFailure()) return;
  // The navigator really listens to the odometry (it names its pose channel at start-up).
  EXPECT_NE(testing::TailOfFile(run_dir_ + "/logs/navigator.log", 200).find("pose from p3at.ODOM"),
            std::string::npos);
  SendGoal(8, 8.5, 18.5);  // lane 4, open floor (the 1 cm plate starts at x = 10)
  ASSERT_TRUE(WaitState(kStateReached, 100.0)) << StatusText();
  const auto poses = Poses();
  ASSERT_FALSE(poses.empty());
  const Pose2 start = ToPose2(poses.front());
  const Pose2 last = ToPose2(poses.back());
  EXPECT_GT(last.x_m - start.x_m, 4.0) << "it did not drive the 4.5 m";
  // The goal tolerance is 0.25 m in the odometry frame; a few metres of noise-free wheel
  // odometry on a skid-steer base drift by centimetres.
  EXPECT_LT(std::hypot(last.x_m - 8.5, last.y_m - 18.5), 0.4)
      << "ground truth (" << last.x_m << ", " << last.y_m << ")";
  // Ground truth: the footprint never touched a lane wall (y = 16 and y = 20, 0.2 m thick).
  for (const auto& p : poses) {
    const auto fp = FootprintAt(ToPose2(p));
    ASSERT_FALSE(ConvexOverlap(fp, Box(3.0, 15.9, 24.0, 16.1), 0.0)) << "touched the south wall";
    ASSERT_FALSE(ConvexOverlap(fp, Box(3.0, 19.9, 24.0, 20.1), 0.0)) << "touched the north wall";
  }
}

}  // namespace
}  // namespace cairn::planner
