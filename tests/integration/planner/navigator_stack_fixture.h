#pragma once

// The navigation stack as real processes on a private LCM bus: cairn-sim (MuJoCo, one Pioneer
// 3-AT in a lane world: the tunnel of seed 000 or the terraces), cairn-mapper (terrain and cost
// layers) and cairn-navigator, a graph under cairn-launch. Lanes, starts and goals:
// simulator/worlds/<world>_lanes.yaml.

#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <optional>
#include <regex>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "cairn/lcmt_goal.hpp"
#include "cairn/lcmt_grid_manifest.hpp"
#include "cairn/lcmt_grid_tile.hpp"
#include "cairn/lcmt_nav_status.hpp"
#include "cairn/lcmt_obstacle_registry.hpp"
#include "cairn/lcmt_path.hpp"
#include "cairn/lcmt_pose.hpp"
#include "cairn/lcmt_sim_clock.hpp"
#include "cairn/lcmt_sim_control_reply.hpp"
#include "cairn/lcmt_sim_control_request.hpp"
#include "cairn/lcmt_velocity_command.hpp"

#include "common/channels.h"
#include "common/layers.h"
#include "common/robot_profile.h"
#include "planner/footprint.h"
#include "services/launch/status.h"
#include "services/runtime/conversions.h"
#include "services/runtime/layer_assembler.h"
#include "tests/support/geometry.h"
#include "tests/support/harness.h"
#include "tests/support/registry.h"

namespace cairn::planner::testing_stack {

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

inline std::vector<Vector2> Box(double x0, double y0, double x1, double y1) {
  return {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}};
}

class NavigatorStackTest : public ::testing::Test {
 protected:
  explicit NavigatorStackTest(std::string world = "tunnel")
      : world_(std::move(world)), url_(testing::PrivateLcmUrl()), procs_(url_), bus_(url_) {
    footprint_ =
        common::LoadRobotProfileFile(testing::SourcePath("config/profiles/pioneer3at.yaml"))
            .footprint_m;
    bus_.Keep(ch::ForRobot(kRobot, ch::kPose));
    bus_.Keep(ch::ForRobot(kRobot, ch::kCmdVel));
    bus_.Keep(ch::ForRobot(kRobot, ch::kMapManifest));
    bus_.lcm().subscribe(ch::ForRobot(kRobot, ch::kMapTiles), &NavigatorStackTest::OnTile, this);
    bus_.lcm().subscribe(ch::ForRobot(kRobot, ch::kMapManifest), &NavigatorStackTest::OnManifest,
                         this);
  }

  // The mapper's shipped configuration with the cost layer published every 0.2 s (more often
  // than the navigator's 0.5 s age limit) and only the test's profile.
  std::string MapperConfig() {
    std::ifstream in(testing::SourcePath("config/mapping/mapper.yaml"));
    std::stringstream text;
    text << in.rdbuf();
    std::string yaml = text.str();
    yaml = std::regex_replace(yaml, std::regex("\\npublish_period_s: [0-9.]+"),
                              "\npublish_period_s: 0.2");
    yaml = std::regex_replace(yaml, std::regex("\\nprofiles: \\[[^\\]]*\\]"),
                              "\nprofiles: [" + profile_arg_ + "]");
    if (terrain_resolution_m_ > 0) {
      const std::string before = yaml;
      yaml = std::regex_replace(
          yaml, std::regex("\nterrain:\n  resolution_m: [0-9.]+"),
          "\nterrain:\n  resolution_m: " + std::to_string(terrain_resolution_m_));
      EXPECT_NE(yaml, before)
          << "mapper.yaml no longer starts its terrain section with resolution_m";
    }
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
    robot << kRobot << ":" << body_ << ":" << body_ << ":" << x << "," << y << "," << yaw_deg;
    const std::string graph = dir + "/" + world_ + ".yaml";
    {
      std::ofstream out(graph);
      out << "name: " << world_ << "-test\n"
          << "lcm_url: " << url_ << "\n"
          << "processes:\n"
          << "  sim:\n"
          << "    command: " << testing::BinPath("cairn-sim") << "\n"
          << "    args: [--world, " << world_ << ", --robot, '" << robot.str()
          << "', --speed, '1']\n"
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
          << "    args: [--robot, " << kRobot << ", --profile, " << profile_arg_
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
          m.layer == "cost/" + profile_ && m.num_tiles > 0) {
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
          m.layer == "cost/" + profile_) {
        v = std::max(v, m.layer_version);
      }
    }
    return v;
  }

  void SendGoal(int64_t id, double x, double y) {
    EXPECT_TRUE(testing::SendPoseGoal(bus_, kRobot, id, x, y, 15.0))
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
    if (!poses.empty()) out << MapWindow(ToPose2(poses.back()));
    return out.str();
  }

  // The cost and directed layers the test assembled, 1.5 m around a pose, north up, one column
  // per cell: what the navigator last saw where it failed. Cost: '.' free, 1..9 graded (tens),
  // '#' lethal, '?' unknown, 'R' the robot's cell. Directed: '.' 0, '#' all headings, '?' NaN,
  // otherwise the mask in hex (bit k refuses heading k * 45 deg).
  std::string MapWindow(const Pose2& robot) const {
    const auto cost = tiles_.Layer(layers::CostLayer(profile_));
    if (!cost) return "\nno cost layer assembled\n";
    const auto directed = tiles_.Layer(layers::DirectedLayer(profile_));
    const auto centre = cost->IndexOf(robot.position());
    if (!centre) return "\nthe robot is outside the cost layer\n";
    const int half = static_cast<int>(std::lround(1.5 / cost->resolution_m()));
    std::ostringstream out;
    out << "\ncost (left) and directed (right) layers around the robot, rows from y "
        << cost->CenterOf({centre->ix, centre->iy + half}).y() << " down, columns from x "
        << cost->CenterOf({centre->ix - half, centre->iy}).x() << ":\n";
    const auto& c = cost->at(layers::CostLayer(profile_));
    for (int iy = centre->iy + half; iy >= centre->iy - half; --iy) {
      std::string left, right;
      for (int ix = centre->ix - half; ix <= centre->ix + half; ++ix) {
        if (!cost->Contains({ix, iy})) {
          left += ' ';
          right += "  ";
          continue;
        }
        const float v = c(ix, iy);
        char ch = std::isnan(v)              ? '?'
                  : v >= layers::kCostLethal ? '#'
                  : v <= 0.f                 ? '.'
                             : static_cast<char>('1' + std::min(8, static_cast<int>(v / 10.f)));
        if (ix == centre->ix && iy == centre->iy) ch = 'R';
        left += ch;
        if (!directed || directed->geometry() != cost->geometry()) continue;
        const float d = directed->at(layers::DirectedLayer(profile_))(ix, iy);
        char hex[4];
        if (std::isnan(d)) {
          right += " ?";
        } else if (d >= layers::kAllHeadingsBlocked) {
          right += d > layers::kAllHeadingsBlocked ? " U" : " #";
        } else if (d <= 0.f) {
          right += " .";
        } else {
          std::snprintf(hex, sizeof(hex), "%02x", static_cast<int>(d));
          right += hex;
        }
      }
      out << left << "   " << right << "\n";
    }
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
  // Starts the stack at (x, lane_y) with the 12 m unknown horizon, sends a goal at
  // (goal_x, lane_y) and expects "no path"; whatever the status says, the footprint never
  // overlaps `forbidden` and, with `flat`, the base never rises.
  void ExpectNoPathNeverEntering(double x, double lane_y, int64_t goal_id, double goal_x,
                                 const std::vector<Vector2>& forbidden, double timeout_s, bool flat,
                                 double start_yaw_deg = 0.0) {
    StartStack(x, lane_y, start_yaw_deg, HorizonNavigatorConfig());
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

  // Mapper and navigator serve the profile `name`: config/profiles/<base>.yaml with its name and
  // the `overrides` ("key" -> "value") changed, written to the test's folder. Call before
  // StartStack. The simulated robot stays a Pioneer 3-AT unless UseBody says otherwise.
  void UseProfile(const std::string& name, const std::string& base,
                  const std::vector<std::pair<std::string, std::string>>& overrides) {
    std::ifstream in(testing::SourcePath("config/profiles/" + base + ".yaml"));
    std::stringstream text;
    text << in.rdbuf();
    std::string yaml =
        std::regex_replace(text.str(), std::regex("\nname: [a-z0-9_]+"), "\nname: " + name);
    for (const auto& [key, value] : overrides) {
      const std::string before = yaml;
      yaml =
          std::regex_replace(yaml, std::regex("\n" + key + ": [^\n]*"), "\n" + key + ": " + value);
      EXPECT_NE(yaml, before) << base << ".yaml no longer names " << key;
    }
    profile_ = name;
    profile_arg_ = procs_.dir() + "/" + name + ".yaml";
    std::ofstream(profile_arg_) << yaml;
    footprint_ = common::LoadRobotProfileFile(profile_arg_).footprint_m;
  }

  // The simulator drives `model` (a robot of simulator/robots) instead of the Pioneer 3-AT.
  // Call before StartStack.
  void UseBody(const std::string& model) { body_ = model; }
  // The terrain layer's cell size for this test (0: the shipped config's).
  void UseTerrainResolution(double resolution_m) { terrain_resolution_m_ = resolution_m; }

  // The footprint polygon at a pose.
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

  void OnTile(const lcm::ReceiveBuffer*, const std::string&, const cairn::lcmt_grid_tile* t) {
    if (layers::IsCostLayer(t->layer) || layers::IsDirectedLayer(t->layer)) tiles_.OnTile(*t);
  }
  void OnManifest(const lcm::ReceiveBuffer*, const std::string&,
                  const cairn::lcmt_grid_manifest* m) {
    if (layers::IsCostLayer(m->layer) || layers::IsDirectedLayer(m->layer)) tiles_.OnManifest(*m);
  }

  std::string world_;
  std::string body_{"pioneer3at"};         // the simulated robot model (simulator/robots)
  double terrain_resolution_m_{0.0};       // UseTerrainResolution
  std::string profile_{"pioneer3at"};      // served and driven
  std::string profile_arg_{"pioneer3at"};  // its name or YAML path, as the processes take it
  std::string url_;
  ProcessSet procs_;
  Bus bus_;
  std::vector<Vector2> footprint_;
  std::string run_dir_;
  int64_t request_id_{0};
  runtime::LayerAssembler tiles_;  // cost and directed layers, for MapWindow
};

}  // namespace cairn::planner::testing_stack
