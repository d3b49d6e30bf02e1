#include "services/mission/lcm/demo_mission.h"

#include <atomic>
#include <chrono>
#include <string>
#include <thread>

#include <gtest/gtest.h>

#include "cairn/lcmt_health.hpp"
#include "cairn/lcmt_pose.hpp"

#include "common/channels.h"
#include "tests/support/memq_node.h"

namespace cairn::mission {
namespace {

runtime::NodeOptions MemqOptions() {
  return cairn::testing::MemqNodeOptions("cairn-mission", "p3at", /*follow_sim_clock=*/true);
}

// `ready_timeout_s`: how long the mission waits for the graph (it waits that long whenever a
// part is missing).
MissionParams QuickParams(double ready_timeout_s = 0.3) {
  MissionParams params;
  params.robot = "p3at";
  params.ready_timeout_s = ready_timeout_s;
  params.timeout_s = 1.0;
  return params;
}

TEST(DemoMissionTest, AGraphThatIsNotRunningIsReportedWithWhatIsMissing) {
  runtime::Node node(MemqOptions());
  const MissionReport report = DemoMission(&node, QuickParams()).Run();
  EXPECT_FALSE(report.ok());
  EXPECT_FALSE(report.reached);
  EXPECT_NE(report.error.find("no pose from p3at"), std::string::npos) << report.error;
  EXPECT_NE(report.error.find("no ready cairn-navigator"), std::string::npos) << report.error;
  EXPECT_NE(report.error.find("no ready cairn-mapstore"), std::string::npos) << report.error;
}

TEST(DemoMissionTest, OnlyWhatIsMissingIsNamed) {
  runtime::Node node(MemqOptions());
  // A pose and a ready navigator for the robot are on the bus while the mission waits for the
  // graph; the map store is not.
  cairn::lcmt_pose pose{};
  pose.robot = "p3at";
  pose.orientation_wxyz[0] = 1.0;
  cairn::lcmt_health health{};
  health.process = "cairn-navigator";
  health.robot = "p3at";
  health.state = cairn::lcmt_health::STATE_READY;
  std::atomic<bool> done{false};
  std::thread peers([&] {
    while (!done) {
      node.lcm().publish(channels::ForRobot("p3at", channels::kPose), &pose);
      node.lcm().publish(channels::kHealth, &health);
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  });
  // Long enough for the peers' messages to arrive on a loaded machine.
  const MissionReport report = DemoMission(&node, QuickParams(3.0)).Run();
  done = true;
  peers.join();
  EXPECT_FALSE(report.ok());
  EXPECT_EQ(report.error.find("no pose"), std::string::npos) << report.error;
  EXPECT_EQ(report.error.find("cairn-navigator"), std::string::npos) << report.error;
  EXPECT_NE(report.error.find("no ready cairn-mapstore"), std::string::npos) << report.error;
}

TEST(FormatReportTest, SaysSuccessOnlyWhenTheGoalWasReachedWithoutAnError) {
  MissionParams params = QuickParams();
  MissionReport report;
  report.reached = true;
  report.nav_outcome = "reached";
  report.distance_m = 12.34;
  report.map_version = 3;
  report.obstacle_lines = {"#1 ramp"};
  const std::string ok = FormatReport(params, report);
  EXPECT_NE(ok.find("SUCCESS (navigation reached)"), std::string::npos) << ok;
  EXPECT_NE(ok.find("distance       12.3 m"), std::string::npos) << ok;
  EXPECT_NE(ok.find("tunnel/demo version 3, shared with rover"), std::string::npos) << ok;
  EXPECT_NE(ok.find("obstacles (1):\n  #1 ramp"), std::string::npos) << ok;
  report.error = "saving the map failed: disk full";
  const std::string failed = FormatReport(params, report);
  EXPECT_NE(failed.find("FAILED"), std::string::npos) << failed;
  EXPECT_NE(failed.find("error          saving the map failed: disk full"), std::string::npos);
}

}  // namespace
}  // namespace cairn::mission
