#include "planner/lcm/navigator_service.h"

#include <algorithm>
#include <chrono>
#include <functional>

#include <gtest/gtest.h>

#include "cairn/lcmt_body_velocity_request.hpp"
#include "cairn/lcmt_map_control_request.hpp"
#include "cairn/lcmt_path.hpp"
#include "cairn/lcmt_sim_clock.hpp"
#include "cairn/lcmt_tile_resend_request.hpp"
#include "cairn/lcmt_velocity_command.hpp"

#include "common/channels.h"
#include "common/layers.h"
#include "services/runtime/conversions.h"
#include "services/runtime/tiler.h"
#include "tests/support/memq_node.h"
#include "tests/unit/planner/test_maps.h"

namespace cairn::planner {
namespace {

namespace ch = cairn::channels;
using common::Pose2;
// The generated constants are declared in-class only: copy them (no odr-use in EXPECT_EQ).
constexpr int kReasonCancelled = cairn::lcmt_nav_status::REASON_CANCELLED;
constexpr int kReasonStaleMap = cairn::lcmt_nav_status::REASON_STALE_MAP;
constexpr int kReasonStaleOdom = cairn::lcmt_nav_status::REASON_STALE_ODOM;
constexpr int kReasonSuccess = cairn::lcmt_nav_status::REASON_SUCCESS;
constexpr int kReasonUnknownPlace = cairn::lcmt_nav_status::REASON_UNKNOWN_PLACE;
constexpr int kStateCancelled = cairn::lcmt_nav_status::STATE_CANCELLED;
constexpr int kStateDriving = cairn::lcmt_nav_status::STATE_DRIVING;
constexpr int kStateFailed = cairn::lcmt_nav_status::STATE_FAILED;
constexpr int kStateReached = cairn::lcmt_nav_status::STATE_REACHED;
constexpr int kStateStopped = cairn::lcmt_nav_status::STATE_STOPPED;

runtime::NodeOptions Options() {
  return cairn::testing::MemqNodeOptions("cairn-navigator", "r1", /*follow_sim_clock=*/true);
}

// The service on an in-process bus, with the test playing simulator (clock and pose), mapper
// (tiles and manifests) and a kinematic robot that follows the commands. Timers are not run:
// the test calls Tick() once per simulated 50 ms and lets no simulated time pass while a plan
// runs, so nothing depends on the machine's speed.
class NavigatorServiceTest : public ::testing::Test {
 protected:
  NavigatorServiceTest() : node_(Options()), tiler_("r1", "live", 50) {
    common::GridGeometry g;
    g.resolution_m = 0.1;
    g.size_x = 120;
    g.size_y = 80;
    map_ = common::GridMap(g);
    map_.AddLayer(layers::CostLayer("pioneer3at"), 0.0f);
    node_.Subscribe<cairn::lcmt_velocity_command>(
        ch::ForRobot("r1", ch::kCmdVel), [this](const auto& m) { commands_.push_back(m); });
    node_.Subscribe<cairn::lcmt_nav_status>(ch::ForRobot("r1", ch::kNavStatus),
                                            [this](const auto& m) { statuses_.push_back(m); });
    node_.Subscribe<cairn::lcmt_path>(ch::ForRobot("r1", ch::kPath),
                                      [this](const auto& m) { paths_.push_back(m); });
    node_.Subscribe<cairn::lcmt_tile_resend_request>(
        ch::ForRobot("r1", ch::kMapTileResend), [this](const auto& m) { resends_.push_back(m); });
    // The velocity bridge's requests drive the kinematic robot as commands do.
    node_.Subscribe<cairn::lcmt_body_velocity_request>(ch::ForRobot("r1", ch::kBodyVelocity),
                                                       [this](const auto& m) {
                                                         requests_.push_back(m);
                                                         cairn::lcmt_velocity_command c{};
                                                         c.robot = m.robot;
                                                         c.linear_mps = m.twist[0];
                                                         c.angular_radps = m.twist[5];
                                                         commands_.push_back(c);
                                                       });
  }

  void Start(std::vector<Place> places = {}, CommandOutput output = CommandOutput::kVelocity,
             ControlClock clock = ControlClock::kWall, bool map_thread = false) {
    NavigatorConfig config;
    config.command_output = output;
    config.control_clock = clock;
    // The test plays the mapper in lockstep with the ticks: the map is assembled as its tiles
    // are handled, unless a test asks for the map's own thread.
    config.map_thread = map_thread;
    // The test drives the clock and waits for every plan (Step), so a plan's wall-clock budget
    // must not decide the outcome on a loaded machine.
    config.global_planner.time_budget_s = 30.0;
    config.Finalize();
    dut_ = std::make_unique<NavigatorService>(node_, config, testing::PioneerProfile(), places);
  }

  void Pump() {
    while (node_.lcm().handleTimeout(0) > 0) {
    }
  }
  void PublishClock() {
    cairn::lcmt_sim_clock c{};
    c.utime = sim_utime_;
    node_.Publish(ch::kSimClock, c);
  }
  void PublishPose() {
    common::Pose3 p;
    p.position_m = {pose_.x_m, pose_.y_m, 0.0};
    p.orientation = common::Quaternion(Eigen::AngleAxisd(pose_.yaw_rad, Eigen::Vector3d::UnitZ()));
    node_.Publish(ch::ForRobot("r1", ch::kPose), runtime::ToLcmPose(p, sim_utime_, "r1", "world"));
  }
  // Tiles that changed (all the first time) and the manifest; `skip` leaves one tile out.
  void PublishMap(bool force = false, bool skip = false) {
    auto batch = tiler_.Update(map_, layers::CostLayer("pioneer3at"), runtime::TileEncoding::kFloat,
                               sim_utime_, force);
    for (size_t i = 0; i < batch.tiles.size(); ++i) {
      if (skip && i == 1) continue;
      node_.Publish(ch::ForRobot("r1", ch::kMapTiles), batch.tiles[i]);
    }
    node_.Publish(ch::ForRobot("r1", ch::kMapManifest), batch.manifest);
  }
  // One simulated control period.
  void Step(bool pose = true, bool map = true) {
    sim_utime_ += 50'000;
    ++ticks_;
    PublishClock();
    if (pose) PublishPose();
    if (map && ticks_ % 4 == 0) PublishMap();
    Pump();
    dut_->Tick();
    Pump();
    if (!commands_.empty() && commands_.size() != used_commands_) {
      used_commands_ = commands_.size();
      const auto& c = commands_.back();
      pose_.x_m += c.linear_mps * 0.05 * std::cos(pose_.yaw_rad);
      pose_.y_m += c.linear_mps * 0.05 * std::sin(pose_.yaw_rad);
      pose_.yaw_rad = common::WrapAngle(pose_.yaw_rad + c.angular_radps * 0.05);
    }
    // A plan started this cycle runs in wall time on the worker: the simulated time waits for
    // it, and its result is taken at the next cycle.
    ASSERT_TRUE(dut_->WaitForPlanner(60.0)) << "the planner did not finish within 60 s";
  }
  bool StepUntil(const std::function<bool()>& done, int max_ticks, bool pose = true,
                 bool map = true) {
    for (int k = 0; k < max_ticks; ++k) {
      Step(pose, map);
      if (HasFatalFailure()) return false;
      if (done()) return true;
    }
    return false;
  }
  void SendGoal(const cairn::lcmt_goal& g) {
    node_.Publish(ch::ForRobot("r1", ch::kGoal), g);
    Pump();
  }
  static cairn::lcmt_goal PoseGoal(int64_t id, double x, double y) {
    cairn::lcmt_goal g{};
    g.robot = "r1";
    g.goal_id = id;
    g.kind = cairn::lcmt_goal::KIND_POSE;
    g.x_m = x;
    g.y_m = y;
    return g;
  }
  int8_t LastState() const { return statuses_.empty() ? -1 : statuses_.back().state; }

  runtime::Node node_;
  runtime::LayerTiler tiler_;
  common::GridMap map_;
  std::unique_ptr<NavigatorService> dut_;
  Pose2 pose_{1.0, 4.0, 0.0};
  int64_t sim_utime_{5'000'000};
  int ticks_{0};
  size_t used_commands_{0};
  std::vector<cairn::lcmt_velocity_command> commands_;
  std::vector<cairn::lcmt_body_velocity_request> requests_;
  std::vector<cairn::lcmt_nav_status> statuses_;
  std::vector<cairn::lcmt_path> paths_;
  std::vector<cairn::lcmt_tile_resend_request> resends_;
};

TEST_F(NavigatorServiceTest, GoalBecomesAPathAndCommandsUntilReached) {
  Start();
  PublishMap(true);
  for (int k = 0; k < 4; ++k) Step();
  SendGoal(PoseGoal(7, 10.0, 4.0));
  ASSERT_TRUE(StepUntil([&] { return !paths_.empty(); }, 100));
  EXPECT_EQ(paths_.back().goal_id, 7);
  EXPECT_EQ(paths_.back().planner, "RRTConnect");
  ASSERT_GT(paths_.back().num_poses, 2);
  EXPECT_NEAR(paths_.back().x_m.back(), 10.0, 0.06);
  ASSERT_TRUE(StepUntil([&] { return LastState() == kStateReached; }, 800));
  EXPECT_EQ(statuses_.back().reason, kReasonSuccess);
  EXPECT_EQ(statuses_.back().num_critics, 5);
  EXPECT_NEAR(pose_.x_m, 10.0, 0.5);
  // Every command within the profile's limits and stamped for this robot.
  double last_v = 0.0;
  for (const auto& c : commands_) {
    EXPECT_EQ(c.robot, "r1");
    EXPECT_LE(c.linear_mps, 0.5 + 1e-9);
    EXPECT_LE(std::abs(c.linear_mps - last_v), 0.8 * 0.05 + 1e-9);
    last_v = c.linear_mps;
  }
  EXPECT_GE(node_.counter("plans"), 1);
}

// Seed 004 test 11 in the service: with command_output body_velocity every command goes out as
// exactly one body-velocity request (the twist copied, x and yaw enabled, the rest disabled,
// priority NORMAL, requester "Twist2BVR", id 0, the profile's name as frame) and no CMD_VEL.
TEST_F(NavigatorServiceTest, TheVelocityBridgeSendsOneBodyVelocityRequestPerCommand) {
  Start({}, CommandOutput::kBodyVelocity);
  PublishMap(true);
  for (int k = 0; k < 4; ++k) Step();
  SendGoal(PoseGoal(11, 10.0, 4.0));
  ASSERT_TRUE(StepUntil([&] { return LastState() == kStateReached; }, 800));
  EXPECT_NEAR(pose_.x_m, 10.0, 0.5);
  ASSERT_FALSE(requests_.empty());
  EXPECT_EQ(static_cast<int64_t>(requests_.size()), node_.counter("commands"));
  EXPECT_EQ(commands_.size(), requests_.size()) << "CMD_VEL went out too";
  for (const auto& r : requests_) {
    EXPECT_EQ(r.robot, "r1");
    EXPECT_EQ(r.frame, "pioneer3at");
    EXPECT_EQ(r.requester, "Twist2BVR");
    EXPECT_EQ(r.goal_id, 0);
    EXPECT_EQ(r.priority, cairn::lcmt_body_velocity_request::PRIORITY_NORMAL + 0);
    EXPECT_FALSE(r.disable_axis[0]);
    EXPECT_TRUE(r.disable_axis[1] && r.disable_axis[2] && r.disable_axis[3] && r.disable_axis[4]);
    EXPECT_FALSE(r.disable_axis[5]);
    EXPECT_EQ(r.twist[1], 0.0);
    EXPECT_EQ(r.twist[2], 0.0);
  }
  EXPECT_GT(std::max_element(requests_.begin(), requests_.end(),
                             [](const auto& a, const auto& b) { return a.twist[0] < b.twist[0]; })
                ->twist[0],
            0.2);
}

// control_clock pose: the poses' stamps pace the loop, a tick (and a command) per 50 ms of them,
// however fast they come in wall time; a stamp that goes back (a restarted simulation) ticks.
TEST_F(NavigatorServiceTest, WithThePoseClockEachFiftyMillisecondsOfPosesIsOneCommand) {
  Start({}, CommandOutput::kVelocity, ControlClock::kPose);
  PublishMap(true);
  for (int k = 0; k < 4; ++k) Step();
  SendGoal(PoseGoal(12, 10.0, 4.0));
  ASSERT_TRUE(StepUntil([&] { return LastState() == kStateDriving; }, 100));
  const size_t before = commands_.size();
  for (int k = 0; k < 20; ++k) {  // 200 ms of poses, 10 ms apart, with no Tick() of the test's
    sim_utime_ += 10'000;
    PublishClock();
    PublishPose();
    Pump();
  }
  EXPECT_EQ(commands_.size() - before, 4u);
  sim_utime_ -= 1'000'000;
  PublishClock();
  PublishPose();
  Pump();
  EXPECT_EQ(commands_.size() - before, 5u);
}

TEST_F(NavigatorServiceTest, AReSentGoalIdDoesNotRestartTheGoal) {
  Start();
  PublishMap(true);
  for (int k = 0; k < 4; ++k) Step();
  SendGoal(PoseGoal(9, 10.0, 4.0));
  ASSERT_TRUE(StepUntil([&] { return !paths_.empty(); }, 100));
  const size_t plans = paths_.size();
  // The same id again (a sender repeating it until the status names it): ignored, counted.
  SendGoal(PoseGoal(9, 10.0, 4.0));
  for (int k = 0; k < 20; ++k) Step();
  EXPECT_EQ(node_.counter("goal_repeats"), 1);
  EXPECT_EQ(paths_.size(), plans) << "the repeated goal was planned again";
  // A new id is a new goal.
  SendGoal(PoseGoal(10, 10.0, 4.0));
  ASSERT_TRUE(StepUntil([&] { return paths_.size() > plans; }, 100));
  EXPECT_EQ(paths_.back().goal_id, 10);
}

TEST_F(NavigatorServiceTest, StaleMapStopsAtOnceWithTheReason) {
  Start();
  PublishMap(true);
  for (int k = 0; k < 4; ++k) Step();
  SendGoal(PoseGoal(1, 10.0, 4.0));
  ASSERT_TRUE(
      StepUntil([&] { return !commands_.empty() && commands_.back().linear_mps > 0.2; }, 200));
  const int64_t last_map = sim_utime_;
  ASSERT_TRUE(StepUntil([&] { return LastState() == kStateStopped; }, 40, true, false));
  EXPECT_EQ(statuses_.back().reason, kReasonStaleMap);
  EXPECT_LE(sim_utime_ - last_map, 500'000 + 2 * 50'000 + 200'000);  // manifests came every 0.2 s
  EXPECT_EQ(commands_.back().linear_mps, 0.0);
  EXPECT_EQ(commands_.back().angular_radps, 0.0);
  EXPECT_GE(node_.counter("safety_stops"), 1);
  EXPECT_EQ(node_.state(), runtime::HealthState::kDegraded);
  // The mapper comes back: driving resumes.
  ASSERT_TRUE(StepUntil([&] { return LastState() == kStateDriving; }, 40));
  EXPECT_EQ(node_.state(), runtime::HealthState::kReady);
}

TEST_F(NavigatorServiceTest, StaleOdometryStops) {
  Start();
  PublishMap(true);
  for (int k = 0; k < 4; ++k) Step();
  SendGoal(PoseGoal(1, 10.0, 4.0));
  ASSERT_TRUE(
      StepUntil([&] { return !commands_.empty() && commands_.back().linear_mps > 0.2; }, 200));
  ASSERT_TRUE(StepUntil([&] { return LastState() == kStateStopped; }, 20, false, true));
  EXPECT_EQ(statuses_.back().reason, kReasonStaleOdom);
  EXPECT_EQ(commands_.back().linear_mps, 0.0);
}

TEST_F(NavigatorServiceTest, BadInputsAreRefusedAndCounted) {
  Start();
  PublishMap(true);
  for (int k = 0; k < 4; ++k) Step();
  // A goal with a NaN coordinate, one for another robot, one of an unknown kind.
  auto nan_goal = PoseGoal(3, NAN, 1.0);
  SendGoal(nan_goal);
  ASSERT_FALSE(statuses_.empty());
  EXPECT_EQ(statuses_.back().goal_id, 3);
  EXPECT_EQ(statuses_.back().state, kStateFailed);
  EXPECT_NE(statuses_.back().message.find("not finite"), std::string::npos);
  auto other = PoseGoal(4, 2.0, 2.0);
  other.robot = "r2";
  SendGoal(other);
  auto weird = PoseGoal(5, 2.0, 2.0);
  weird.kind = 42;
  SendGoal(weird);
  EXPECT_EQ(node_.counter("bad_goals"), 3);
  // A pose with a zero quaternion.
  cairn::lcmt_pose bad_pose{};
  bad_pose.robot = "r1";
  bad_pose.utime = sim_utime_;
  node_.Publish(ch::ForRobot("r1", ch::kPose), bad_pose);
  // A tile whose checksum does not match its data.
  auto batch = runtime::LayerTiler("r1", "live", 50)
                   .Update(map_, layers::CostLayer("pioneer3at"), runtime::TileEncoding::kFloat, 1);
  batch.tiles[0].data[0] = 55.0f;
  node_.Publish(ch::ForRobot("r1", ch::kMapTiles), batch.tiles[0]);
  // Bytes that are no message at all.
  const char junk[] = "not an lcm message";
  node_.lcm().publish(ch::ForRobot("r1", ch::kGoal), junk, sizeof(junk));
  Pump();
  EXPECT_EQ(node_.counter("bad_poses"), 1);
  EXPECT_EQ(node_.counter("bad_map_tiles"), 1);
  EXPECT_GE(node_.decode_errors(), 1);
  const auto health = node_.MakeHealth();
  EXPECT_GE(health.dropped_inputs, 5);
  // Nothing of that disturbed the navigator: it is idle and still works.
  EXPECT_EQ(dut_->navigator().status().state, NavState::kIdle);
  SendGoal(PoseGoal(6, 6.0, 4.0));
  ASSERT_TRUE(StepUntil([&] { return LastState() == kStateDriving; }, 100));
}

TEST_F(NavigatorServiceTest, UnknownPlaceFailsAndAKnownOneResolves) {
  Start({{"dock", {{8.0, 1.0}, {11.0, 1.0}, {11.0, 7.0}, {8.0, 7.0}}}});
  PublishMap(true);
  for (int k = 0; k < 4; ++k) Step();
  cairn::lcmt_goal g{};
  g.robot = "r1";
  g.goal_id = 11;
  g.kind = cairn::lcmt_goal::KIND_PLACE;
  g.place = "garage";
  SendGoal(g);
  ASSERT_TRUE(StepUntil([&] { return LastState() == kStateFailed; }, 10));
  EXPECT_EQ(statuses_.back().reason, kReasonUnknownPlace);
  g.goal_id = 12;
  g.place = "dock";
  SendGoal(g);
  ASSERT_TRUE(StepUntil([&] { return !paths_.empty(); }, 100));
  EXPECT_EQ(paths_.back().goal_id, 12);
  // The dock's cell farthest from the map's edges (off-map counts as a wall): its west side,
  // 4 m from the east edge of the 12 m × 8 m map and from both long edges.
  EXPECT_NEAR(paths_.back().x_m.back(), 8.05, 0.15);
  EXPECT_NEAR(paths_.back().y_m.back(), 4.0, 0.15);
}

TEST_F(NavigatorServiceTest, AsksForMissingTilesAndCancelStops) {
  Start();
  PublishMap(true, /*skip=*/true);
  Step(true, false);
  Step(true, false);
  ASSERT_FALSE(resends_.empty());
  EXPECT_EQ(resends_.back().layer, "cost/pioneer3at");
  EXPECT_EQ(resends_.back().num_tiles, 1);
  EXPECT_EQ(resends_.back().requester, "cairn-navigator");
  PublishMap(true);
  for (int k = 0; k < 4; ++k) Step();
  SendGoal(PoseGoal(2, 10.0, 4.0));
  ASSERT_TRUE(
      StepUntil([&] { return !commands_.empty() && commands_.back().linear_mps > 0.2; }, 200));
  cairn::lcmt_goal cancel{};
  cancel.robot = "r1";
  cancel.goal_id = 2;
  cancel.kind = cairn::lcmt_goal::KIND_CANCEL;
  SendGoal(cancel);
  ASSERT_TRUE(StepUntil([&] { return commands_.back().linear_mps == 0.0; }, 40));
  EXPECT_EQ(LastState(), kStateCancelled);
  EXPECT_EQ(statuses_.back().reason, kReasonCancelled);
}

// Issue 20: layers were assembled and cost maps built on the node's thread, which also runs the
// control loop: while a large layer was built, no command (and no stale-input stop) could go
// out. With the map's own thread (the shipped configuration), while a 4000 x 4000 layer (1600
// tiles, 64 MB) is assembled and built, no turn of the node's loop takes 100 ms (built on the
// node's thread, the turn that took the manifest took the whole build: 0.2 to 0.3 s here), and
// commands keep coming.
TEST_F(NavigatorServiceTest, CommandsKeepTheirRateWhileALargeLayerIsBuilt) {
  Start({}, CommandOutput::kVelocity, ControlClock::kWall, /*map_thread=*/true);
  using Clock = std::chrono::steady_clock;
  std::vector<Clock::time_point> command_times;
  double longest_turn_s = 0.0;
  auto spin_until = [&](const std::function<bool()>& done, double timeout_s) {
    const auto until =
        Clock::now() + std::chrono::microseconds(static_cast<int64_t>(timeout_s * 1e6));
    auto last = Clock::now();
    while (!done() && Clock::now() < until) {
      const auto now = Clock::now();
      sim_utime_ += std::chrono::duration_cast<std::chrono::microseconds>(now - last).count();
      last = now;
      PublishClock();
      PublishPose();
      const size_t before = commands_.size();
      node_.SpinOnce(10);
      longest_turn_s =
          std::max(longest_turn_s, std::chrono::duration<double>(Clock::now() - now).count());
      if (commands_.size() != before) command_times.push_back(Clock::now());
    }
    return done();
  };
  PublishMap(true);
  SendGoal(PoseGoal(31, 10.0, 4.0));
  ASSERT_TRUE(spin_until([&] { return commands_.size() >= 5; }, 20.0)) << "no commands";

  common::GridGeometry g;
  g.resolution_m = 0.1;
  g.size_x = 4000;
  g.size_y = 4000;
  common::GridMap large(g);
  large.AddLayer(layers::CostLayer("pioneer3at"), 0.0f);
  runtime::LayerTiler tiler("r1", "live", 100, /*version_base=*/1'000'000);
  auto batch = tiler.Update(large, layers::CostLayer("pioneer3at"), runtime::TileEncoding::kFloat,
                            sim_utime_, true);
  ASSERT_EQ(batch.tiles.size(), 1600u);
  for (const auto& t : batch.tiles) node_.Publish(ch::ForRobot("r1", ch::kMapTiles), t);
  node_.Publish(ch::ForRobot("r1", ch::kMapManifest), batch.manifest);
  command_times.clear();
  longest_turn_s = 0.0;
  const auto published = Clock::now();
  ASSERT_TRUE(spin_until(
      [&] {
        const auto map = dut_->latest_map();
        return map && map->geometry().size_x == 4000;
      },
      60.0))
      << "the large layer never arrived";
  const auto built = Clock::now();
  EXPECT_LT(longest_turn_s, 0.1) << "a turn of the node's loop took " << longest_turn_s << " s";
  EXPECT_GE(command_times.size(), 2u)
      << "no commands in the " << std::chrono::duration<double>(built - published).count()
      << " s the layer took";
}

}  // namespace
}  // namespace cairn::planner
