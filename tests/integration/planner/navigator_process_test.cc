// cairn-navigator as a real process on a private LCM bus. The test process plays the rest of
// the stack: a simulator clock, a kinematic robot that follows CMD_VEL and reports its pose,
// and a mapper that publishes a cost layer as tiles and manifests.

#include <csignal>
#include <fstream>

#include <gtest/gtest.h>
#include <sys/wait.h>

#include "cairn/lcmt_goal.hpp"
#include "cairn/lcmt_grid_manifest.hpp"
#include "cairn/lcmt_grid_tile.hpp"
#include "cairn/lcmt_nav_status.hpp"
#include "cairn/lcmt_path.hpp"
#include "cairn/lcmt_pose.hpp"
#include "cairn/lcmt_sim_clock.hpp"
#include "cairn/lcmt_tile_resend_request.hpp"
#include "cairn/lcmt_velocity_command.hpp"

#include "common/channels.h"
#include "common/grid_map.h"
#include "common/layers.h"
#include "common/robot_profile.h"
#include "planner/cost_map.h"
#include "services/runtime/conversions.h"
#include "services/runtime/tiler.h"
#include "tests/support/harness.h"

namespace cairn::planner {
namespace {

namespace ch = cairn::channels;
using common::Pose2;
using testing::Bus;
using testing::ProcessSet;

constexpr int kStateReached = cairn::lcmt_nav_status::STATE_REACHED;
constexpr int kStateStopped = cairn::lcmt_nav_status::STATE_STOPPED;
constexpr int kStateDriving = cairn::lcmt_nav_status::STATE_DRIVING;
constexpr int kReasonStaleMap = cairn::lcmt_nav_status::REASON_STALE_MAP;
constexpr int kReasonStaleOdom = cairn::lcmt_nav_status::REASON_STALE_ODOM;

using Clock = std::chrono::steady_clock;

// The stand-in world: 16 m × 8 m at 0.1 m with a wall across x = 8 and a 1.2 m gap.
class FakeWorld {
 public:
  explicit FakeWorld(const std::string& url) : bus_(url), tiler_("r1", "live", 50) {
    common::GridGeometry g;
    g.resolution_m = 0.1;
    g.size_x = 160;
    g.size_y = 80;
    map_ = common::GridMap(g);
    auto& cost = map_.AddLayer(layers::CostLayer("pioneer3at"), 0.0f);
    for (int iy = 0; iy < g.size_y; ++iy) {
      for (int ix = 78; ix < 82; ++ix) {
        const double y = (iy + 0.5) * 0.1;
        if (y < 5.0 || y > 6.2) cost(ix, iy) = 100.0f;
      }
    }
    truth_ = std::make_unique<CostMap>(g, cost, common::RectangleFootprint(0.63, 0.50));
    bus_.Keep(ch::ForRobot("r1", ch::kCmdVel));
    bus_.Keep(ch::ForRobot("r1", ch::kMapTileResend));
    start_ = Clock::now();
  }

  // Runs the world in real time until `done` or the timeout (seconds of wall time).
  bool RunUntil(const std::function<bool()>& done, double timeout_s) {
    const auto deadline = Clock::now() + std::chrono::duration<double>(timeout_s);
    while (Clock::now() < deadline) {
      Tick();
      if (done()) return true;
    }
    return false;
  }

  void Tick() {
    bus_.Pump(5);
    const double t = std::chrono::duration<double>(Clock::now() - start_).count();
    const double dt = t - last_t_;
    if (dt < 0.02) return;
    last_t_ = t;
    // The robot follows the newest command for the elapsed time.
    if (auto cmd = bus_.Last<cairn::lcmt_velocity_command>(ch::ForRobot("r1", ch::kCmdVel))) {
      pose_.x_m += cmd->linear_mps * dt * std::cos(pose_.yaw_rad);
      pose_.y_m += cmd->linear_mps * dt * std::sin(pose_.yaw_rad);
      pose_.yaw_rad = common::WrapAngle(pose_.yaw_rad + cmd->angular_radps * dt);
    }
    if (!truth_->IsValid(pose_)) {
      if (collisions_++ % 20 == 0) {
        auto c = bus_.Last<cairn::lcmt_velocity_command>(ch::ForRobot("r1", ch::kCmdVel));
        auto st = Status();
        std::fprintf(
            stderr, "collision at t=%.2f: (%.2f, %.2f, %.2f) cmd (%.2f, %.2f) state %d: %s\n", t,
            pose_.x_m, pose_.y_m, pose_.yaw_rad, c ? c->linear_mps : 0.0,
            c ? c->angular_radps : 0.0, st ? st->state : -1, st ? st->message.c_str() : "");
      }
    }
    sim_utime_ = 1'000'000 + static_cast<int64_t>(t * 1e6);
    cairn::lcmt_sim_clock clock{};
    clock.utime = sim_utime_;
    bus_.Publish(ch::kSimClock, clock);
    if (publish_pose_) {
      common::Pose3 p;
      p.position_m = {pose_.x_m, pose_.y_m, 0.0};
      p.orientation =
          common::Quaternion(Eigen::AngleAxisd(pose_.yaw_rad, Eigen::Vector3d::UnitZ()));
      bus_.Publish(ch::ForRobot("r1", ch::kPose), runtime::ToLcmPose(p, sim_utime_, "r1", "world"));
    }
    // Answer the navigator's requests for tiles it missed (it starts after the first batch).
    const auto& resends = bus_.Kept(ch::ForRobot("r1", ch::kMapTileResend));
    for (; resends_answered_ < resends.size() && publish_map_; ++resends_answered_) {
      cairn::lcmt_tile_resend_request r;
      const auto& bytes = resends[resends_answered_];
      if (r.decode(bytes.data(), 0, static_cast<int>(bytes.size())) < 0) continue;
      for (const auto& tile : tiler_.Resend(r).tiles)
        bus_.Publish(ch::ForRobot("r1", ch::kMapTiles), tile);
    }
    if (publish_map_ && t - last_map_t_ >= 0.2) {
      last_map_t_ = t;
      last_map_utime_ = sim_utime_;
      auto batch = tiler_.Update(map_, layers::CostLayer("pioneer3at"),
                                 runtime::TileEncoding::kFloat, sim_utime_);
      for (const auto& tile : batch.tiles) bus_.Publish(ch::ForRobot("r1", ch::kMapTiles), tile);
      bus_.Publish(ch::ForRobot("r1", ch::kMapManifest), batch.manifest);
    }
  }

  void SendGoal(int64_t id, double x, double y) {
    cairn::lcmt_goal g{};
    g.robot = "r1";
    g.goal_id = id;
    g.kind = cairn::lcmt_goal::KIND_POSE;
    g.x_m = x;
    g.y_m = y;
    bus_.Publish(ch::ForRobot("r1", ch::kGoal), g);
  }
  std::optional<cairn::lcmt_nav_status> Status() {
    return bus_.Last<cairn::lcmt_nav_status>(ch::ForRobot("r1", ch::kNavStatus));
  }
  bool StatusIs(int state) {
    auto s = Status();
    return s && s->state == state;
  }
  std::vector<cairn::lcmt_velocity_command> Commands() {
    std::vector<cairn::lcmt_velocity_command> out;
    for (const auto& bytes : bus_.Kept(ch::ForRobot("r1", ch::kCmdVel))) {
      cairn::lcmt_velocity_command c;
      if (c.decode(bytes.data(), 0, static_cast<int>(bytes.size())) >= 0) out.push_back(c);
    }
    return out;
  }

  Bus bus_;
  runtime::LayerTiler tiler_;
  common::GridMap map_;
  std::unique_ptr<CostMap> truth_;
  Pose2 pose_{2.0, 2.0, 0.0};
  Clock::time_point start_;
  double last_t_{0.0};
  double last_map_t_{-1.0};
  int64_t sim_utime_{0};
  int64_t last_map_utime_{0};
  bool publish_pose_{true};
  bool publish_map_{true};
  int collisions_{0};
  size_t resends_answered_{0};
};

TEST(NavigatorProcessTest, DrivesThroughTheGapAndStopsWhenTheMapGoesStale) {
  const std::string url = testing::PrivateLcmUrl();
  ProcessSet procs(url);
  FakeWorld world(url);
  auto& nav = procs.Start("cairn-navigator", {"--robot", "r1", "--profile", "pioneer3at"});
  ASSERT_TRUE(
      world.RunUntil([&] { return world.bus_.Health("cairn-navigator", "r1").has_value(); }, 10.0));

  world.SendGoal(1, 13.0, 2.0);
  ASSERT_TRUE(world.RunUntil([&] { return world.StatusIs(kStateReached); }, 90.0))
      << (world.Status() ? world.Status()->message : "no status");
  EXPECT_EQ(world.collisions_, 0);
  EXPECT_LT(std::hypot(world.pose_.x_m - 13.0, world.pose_.y_m - 2.0), 0.5);
  const auto path = world.bus_.Last<cairn::lcmt_path>(ch::ForRobot("r1", ch::kPath));
  ASSERT_TRUE(path.has_value());
  EXPECT_EQ(path->goal_id, 1);
  // Every command within the profile's limits: 0.5 m/s, 1 rad/s; speed steps of at most one
  // control period of acceleration (0.8 m/s^2 × 50 ms) apart from the safety stop.
  const auto commands = world.Commands();
  ASSERT_GT(commands.size(), 50u);
  for (size_t i = 0; i < commands.size(); ++i) {
    EXPECT_LE(commands[i].linear_mps, 0.5 + 1e-9);
    EXPECT_GE(commands[i].linear_mps, -0.2 - 1e-9);
    EXPECT_LE(std::abs(commands[i].angular_radps), 1.0 + 1e-9);
    if (i > 0) {
      EXPECT_LE(std::abs(commands[i].linear_mps - commands[i - 1].linear_mps), 0.04 + 1e-9);
    }
  }

  // Drive back; on the way the map stops arriving: within 0.5 s of sim time past the cost
  // layer's age limit the robot is commanded to stop, and the status says why.
  world.SendGoal(2, 2.0, 2.0);
  ASSERT_TRUE(world.RunUntil(
      [&] {
        auto c = world.bus_.Last<cairn::lcmt_velocity_command>(ch::ForRobot("r1", ch::kCmdVel));
        return world.StatusIs(kStateDriving) && c && std::abs(c->linear_mps) > 0.2;
      },
      30.0));
  world.publish_map_ = false;
  const int64_t last_map = world.last_map_utime_;
  ASSERT_TRUE(world.RunUntil([&] { return world.StatusIs(kStateStopped); }, 5.0));
  const auto stopped = *world.Status();
  EXPECT_EQ(stopped.reason, kReasonStaleMap);
  const auto stop_cmd =
      world.bus_.Last<cairn::lcmt_velocity_command>(ch::ForRobot("r1", ch::kCmdVel));
  ASSERT_TRUE(stop_cmd.has_value());
  EXPECT_EQ(stop_cmd->linear_mps, 0.0);
  EXPECT_EQ(stop_cmd->angular_radps, 0.0);
  // The layer counts as stale 0.5 s after its last message; the stop follows within a control
  // period or two (plus the bus).
  EXPECT_LE(stop_cmd->utime - last_map, 500'000 + 200'000);
  world.publish_map_ = true;
  ASSERT_TRUE(world.RunUntil([&] { return world.StatusIs(kStateReached); }, 90.0));
  EXPECT_EQ(world.collisions_, 0);

  // Odometry stops: same, with its own reason.
  world.SendGoal(3, 13.0, 2.0);
  ASSERT_TRUE(world.RunUntil([&] { return world.StatusIs(kStateDriving); }, 10.0));
  world.publish_pose_ = false;
  ASSERT_TRUE(world.RunUntil([&] { return world.StatusIs(kStateStopped); }, 5.0));
  EXPECT_EQ(world.Status()->reason, kReasonStaleOdom);

  // SIGTERM: a clean exit.
  nav.Signal(SIGTERM);
  const auto status = nav.WaitExit(10.0);
  ASSERT_TRUE(status.has_value());
  EXPECT_TRUE(WIFEXITED(*status));
  EXPECT_EQ(WEXITSTATUS(*status), 0);
}

TEST(NavigatorProcessTest, HelpAndConfigurationErrors) {
  const std::string url = testing::PrivateLcmUrl();
  ProcessSet procs(url);
  const std::string dir = procs.dir();
  auto& help = procs.StartRaw("help", {testing::BinPath("cairn-navigator"), "--help"});
  auto exit_of = [](testing::ChildProcess& p) {
    const auto s = p.WaitExit(20.0);
    return s && WIFEXITED(*s) ? WEXITSTATUS(*s) : -1;
  };
  EXPECT_EQ(exit_of(help), 0);
  EXPECT_NE(help.Log().find("--robot"), std::string::npos);

  auto& no_profile = procs.Start("cairn-navigator", {"--robot", "r1", "--profile", "hovercraft"});
  EXPECT_EQ(exit_of(no_profile), 1);
  EXPECT_NE(no_profile.Log().find("hovercraft"), std::string::npos);

  const std::string bad = dir + "/bad.yaml";
  std::ofstream(bad) << "global_planner:\n  planer: RRTConnect\n";
  auto& bad_config = procs.Start("cairn-navigator", {"--robot", "r1", "--config", bad});
  EXPECT_EQ(exit_of(bad_config), 1);
  EXPECT_NE(bad_config.Log().find("bad.yaml:2"), std::string::npos) << bad_config.Log();

  auto& no_robot = procs.Start("cairn-navigator", {});
  EXPECT_EQ(exit_of(no_robot), 2);
}

}  // namespace
}  // namespace cairn::planner
