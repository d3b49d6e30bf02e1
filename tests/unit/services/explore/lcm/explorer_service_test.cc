#include "services/explore/lcm/explorer_service.h"

#include <cmath>
#include <optional>
#include <vector>

#include <gtest/gtest.h>

#include "cairn/lcmt_pose.hpp"
#include "cairn/lcmt_sim_clock.hpp"
#include "cairn/lcmt_sim_control_reply.hpp"
#include "cairn/lcmt_sim_control_request.hpp"
#include "cairn/lcmt_velocity_command.hpp"

#include "common/channels.h"
#include "tests/support/memq_node.h"

namespace cairn::explore {
namespace {

constexpr char kRobot[] = "p3dx";

common::RobotProfile Profile() {
  return common::LoadRobotProfileFile(std::string(CAIRN_SOURCE_DIR) + "/config/profiles/p3dx.yaml");
}

// A 240 deg scan of 684 beams, every range `range_m` except the front sector's `front_m`.
cairn::lcmt_laser_scan Scan(int64_t utime, float range_m, float front_m) {
  cairn::lcmt_laser_scan s{};
  s.utime = utime;
  s.robot = kRobot;
  s.frame = "laser";
  s.sensor_orientation_wxyz[0] = 1.0;
  s.angle_min_rad = static_cast<float>(-120.0 * M_PI / 180.0);
  s.angle_increment_rad = static_cast<float>(240.0 * M_PI / 180.0 / 683.0);
  s.range_min_m = 0.02f;
  s.range_max_m = 5.6f;
  s.scan_time_s = 0.1f;
  s.num_ranges = 684;
  s.ranges_m.assign(684, range_m);
  for (int i = 272; i < 408; ++i) s.ranges_m[i] = front_m;
  return s;
}

struct Rig {
  explicit Rig(ExplorerConfig config)
      : node(cairn::testing::MemqNodeOptions("cairn-explorer", kRobot)),
        service(node, config, Profile()) {
    node.Subscribe<cairn::lcmt_velocity_command>(
        channels::ForRobot(kRobot, channels::kCmdVel),
        [this](const cairn::lcmt_velocity_command& c) { commands.push_back(c); });
  }
  void Send(const cairn::lcmt_laser_scan& scan) {
    node.Publish(channels::ForRobot(kRobot, channels::kScan), scan);
    for (int i = 0; i < 3; ++i) node.SpinOnce(0);
  }
  runtime::Node node;
  ExplorerService service;
  std::vector<cairn::lcmt_velocity_command> commands;
};

TEST(ExplorerServiceTest, AClearScanCruisesAndAnObstacleAheadTurnsInPlace) {
  Rig rig(ExplorerConfig{});
  rig.Send(Scan(1'000'000, 4.0f, 4.0f));
  ASSERT_EQ(rig.commands.size(), 1u);
  EXPECT_DOUBLE_EQ(rig.commands[0].linear_mps, 0.35);
  EXPECT_DOUBLE_EQ(rig.commands[0].angular_radps, 0.0);
  EXPECT_EQ(rig.commands[0].source, "cairn-explorer");
  rig.Send(Scan(1'100'000, 4.0f, 0.6f));
  ASSERT_EQ(rig.commands.size(), 2u);
  EXPECT_DOUBLE_EQ(rig.commands[1].linear_mps, 0.0);
  EXPECT_DOUBLE_EQ(std::abs(rig.commands[1].angular_radps), 0.6);
  EXPECT_EQ(rig.service.status().behaviour, "TURN_IN_PLACE");
  EXPECT_EQ(rig.service.status().state, +cairn::lcmt_explore_status::STATE_EXPLORING);
  EXPECT_FLOAT_EQ(rig.service.status().sector_min_m[2], 0.6f);
}

TEST(ExplorerServiceTest, AMalformedScanIsCountedAndDroppedAndTheNextOneIsServed) {
  Rig rig(ExplorerConfig{});
  cairn::lcmt_laser_scan bad = Scan(1'000'000, 4.0f, 4.0f);
  bad.num_ranges = 700;  // disagrees with the array (handed over directly: it cannot be encoded)
  rig.service.OnScan(bad);
  cairn::lcmt_laser_scan no_pose = Scan(1'000'000, 4.0f, 4.0f);
  no_pose.sensor_orientation_wxyz[0] = 0.0;  // not a rotation
  rig.Send(no_pose);
  cairn::lcmt_laser_scan nan_time = Scan(1'000'000, 4.0f, 4.0f);
  nan_time.angle_increment_rad = NAN;
  rig.Send(nan_time);
  EXPECT_TRUE(rig.commands.empty());
  EXPECT_EQ(rig.node.counter("bad_scans"), 3);
  rig.Send(Scan(1'200'000, 4.0f, 4.0f));
  ASSERT_EQ(rig.commands.size(), 1u);
  EXPECT_DOUBLE_EQ(rig.commands[0].linear_mps, 0.35);
}

TEST(ExplorerServiceTest, TheDurationEndsTheExplorationWithAStop) {
  ExplorerConfig config;
  config.duration_s = 1.0;
  Rig rig(config);
  rig.Send(Scan(10'000'000, 4.0f, 4.0f));
  rig.Send(Scan(10'500'000, 4.0f, 4.0f));
  EXPECT_FALSE(rig.service.done());
  rig.Send(Scan(11'000'000, 4.0f, 4.0f));
  EXPECT_TRUE(rig.service.done());
  ASSERT_EQ(rig.commands.size(), 3u);
  EXPECT_DOUBLE_EQ(rig.commands.back().linear_mps, 0.0);
  EXPECT_DOUBLE_EQ(rig.commands.back().angular_radps, 0.0);
  EXPECT_EQ(rig.service.status().state, +cairn::lcmt_explore_status::STATE_DONE);
  rig.Send(Scan(11'100'000, 4.0f, 4.0f));
  EXPECT_EQ(rig.commands.size(), 3u);
}

TEST(ExplorerServiceTest, FrontierModeWaitsForTheOccupancyLayer) {
  ExplorerConfig config;
  config.mode = ExploreMode::kFrontier;
  Rig rig(config);
  rig.service.Tick();
  EXPECT_EQ(rig.service.status().state, +cairn::lcmt_explore_status::STATE_WAITING);
  EXPECT_NE(rig.service.status().message.find("occupancy"), std::string::npos);
  EXPECT_EQ(rig.service.status().goals_sent, 0);
}

// Next-best-view mode: the scan request, a refused request, a malformed turret line and a scan
// that never comes, over memq:// with the simulator's clock driven by the test.
struct NbvRig {
  static ExplorerConfig Config() {
    ExplorerConfig c;
    c.mode = ExploreMode::kNbv;
    c.nbv.work_area = "-5,-5 5,-5 5,5 -5,5";
    c.nbv.scan_timeout_s = 10.0;
    c.nbv.pan_step_deg = 10.0;
    c.nbv.tilt_step_deg = 45.0;
    return c;
  }
  NbvRig() : node(cairn::testing::MemqNodeOptions("cairn-explorer", kRobot, true)) {
    node.Subscribe<cairn::lcmt_sim_control_request>(
        channels::kSimControl,
        [this](const cairn::lcmt_sim_control_request& r) { requests.push_back(r); });
    service.emplace(node, Config(), Profile());
  }
  void Clock(double t_s) {
    cairn::lcmt_sim_clock c{};
    c.utime = static_cast<int64_t>(t_s * 1e6);
    node.Publish(channels::kSimClock, c);
    cairn::lcmt_pose p{};
    p.utime = c.utime;
    p.robot = kRobot;
    p.orientation_wxyz[0] = 1.0;
    node.Publish(channels::ForRobot(kRobot, channels::kPose), p);
    for (int i = 0; i < 4; ++i) node.SpinOnce(0);
    service->Tick();
    for (int i = 0; i < 4; ++i) node.SpinOnce(0);
  }
  runtime::Node node;
  std::optional<ExplorerService> service;
  std::vector<cairn::lcmt_sim_control_request> requests;
};

TEST(ExplorerServiceTest, NbvModeAsksTheTurretForAScanAndAsksAgainWhenNoneComes) {
  NbvRig rig;
  rig.Clock(1.0);
  ASSERT_EQ(rig.requests.size(), 1u);
  EXPECT_EQ(rig.requests[0].op, +cairn::lcmt_sim_control_request::OP_TRIGGER_SENSOR);
  EXPECT_EQ(rig.requests[0].name, "p3dx/turret");
  EXPECT_EQ(rig.service->status().mode, +cairn::lcmt_explore_status::MODE_NBV);
  EXPECT_EQ(rig.service->status().behaviour, "SCANNING");

  // The simulator refuses it: said, and the explorer keeps waiting for the scan.
  cairn::lcmt_sim_control_reply refused{};
  refused.request_id = rig.requests[0].request_id;
  refused.status = cairn::lcmt_sim_control_reply::STATUS_NOT_FOUND;
  refused.message = "robot 'p3dx' has no sensor 'turret'";
  rig.node.Publish(channels::kSimControlReply, refused);
  rig.Clock(2.0);
  EXPECT_FALSE(rig.service->done());

  // A malformed line (a NaN turret angle) is counted and dropped.
  cairn::lcmt_laser_scan line = Scan(2'000'000, 3.0f, 3.0f);
  line.turret_angle_rad = NAN;
  rig.service->OnTurretLine(line);
  EXPECT_EQ(rig.node.counter("bad_turret_lines"), 1);

  // No line in scan_timeout_s (10 s): asked again, and said why.
  rig.Clock(12.0);
  rig.Clock(13.5);  // settle: the new request goes out a second later
  ASSERT_EQ(rig.requests.size(), 2u);
  EXPECT_NE(rig.service->status().message.find("asking again"), std::string::npos)
      << rig.service->status().message;
  EXPECT_FALSE(rig.service->done());
}

TEST(ExplorerServiceTest, NbvModeRefusesAMissingOrSelfIntersectingWorkArea) {
  ExplorerConfig c = NbvRig::Config();
  c.nbv.work_area = "";
  EXPECT_THROW(c.Validate(), std::invalid_argument);
  c.nbv.work_area = "0,0 4,4 4,0 0,4";  // a bow tie
  try {
    c.Validate();
    ADD_FAILURE() << "a self-intersecting work area was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("cross"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace cairn::explore
