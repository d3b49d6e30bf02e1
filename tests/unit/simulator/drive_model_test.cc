#include "simulator/drive_model.h"

#include <cmath>

#include <gtest/gtest.h>

#include "simulator/sensors/odometry_sensor.h"
#include "tests/unit/simulator/sim_test_util.h"

namespace cairn::sim {
namespace {

using testing::Drive;
using testing::SimTest;
using testing::TestPaths;

class ThrusterDriveTest : public SimTest {};

// The Sparus II in a shipped underwater world at (0, 0), 2.2 m above the seabed.
Scenario AuvScenario(const std::string& world, double current_y_mps = 0.0) {
  Scenario s = MakeScenario(world, {"auv:sparus2"}, TestPaths());
  s.robots[0].sensors = SensorSet{};
  s.robots[0].sensors.Set<OdometrySensor>();
  s.physics.current_y_mps = current_y_mps;
  return s;
}

void Idle(MujocoSim& sim, double duration_s, SimOutputs* out) {
  const double end = sim.time_s() + duration_s;
  while (sim.time_s() < end) sim.Step(out);
}

TEST_F(ThrusterDriveTest, HoversAtItsDepthLevelWhenIdle) {
  MujocoSim sim(AuvScenario("floor"));
  SimOutputs out;
  const common::Pose3 start = sim.RobotPose("auv");
  EXPECT_NEAR(start.position_m.z(), 2.205, 1e-3);
  Idle(sim, 10.0, &out);
  const common::Pose3 pose = sim.RobotPose("auv");
  // Neither sinking under its weight nor rising on a buoyancy counted twice.
  EXPECT_NEAR(pose.position_m.z(), start.position_m.z(), 0.02);
  EXPECT_NEAR(pose.position_m.x(), 0.0, 0.01);
  EXPECT_NEAR(pose.position_m.y(), 0.0, 0.01);
  EXPECT_LT(std::abs(pose.roll_rad()), 0.01);
  EXPECT_LT(std::abs(pose.pitch_rad()), 0.01);
}

TEST_F(ThrusterDriveTest, SurgesAtTheCommandedSpeedAndKeepsDepthAndHeading) {
  MujocoSim sim(AuvScenario("floor"));
  SimOutputs out;
  Drive(sim, "auv", 0.6, 0.0, 20.0, &out);
  const common::Vector3 velocity = sim.RobotVelocity("auv");
  EXPECT_NEAR(velocity.x(), 0.6, 0.03);
  EXPECT_NEAR(velocity.y(), 0.0, 0.01);
  const common::Pose3 pose = sim.RobotPose("auv");
  EXPECT_NEAR(pose.position_m.z(), 2.205, 0.05);
  EXPECT_NEAR(pose.yaw_rad(), 0.0, 0.01);
  EXPECT_GT(pose.position_m.x(), 9.0);  // ramped at the profile's 0.2 m/s^2, then 0.6 m/s
  // Odometry (surge and yaw rate integrated) follows the truth.
  const auto* odom = sim.FindSensor<OdometrySensor>("auv");
  ASSERT_NE(odom, nullptr);
  EXPECT_NEAR(odom->pose().x_m, pose.position_m.x(), 0.05);
  EXPECT_NEAR(odom->pose().y_m, pose.position_m.y(), 0.05);
}

TEST_F(ThrusterDriveTest, TurnsAtTheCommandedYawRate) {
  MujocoSim sim(AuvScenario("floor"));
  SimOutputs out;
  Drive(sim, "auv", 0.3, 0.2, 10.0, &out);
  const double yaw0 = sim.RobotPose("auv").yaw_rad();
  Drive(sim, "auv", 0.3, 0.2, 2.0, &out);
  const double yaw1 = sim.RobotPose("auv").yaw_rad();
  EXPECT_NEAR(common::WrapAngle(yaw1 - yaw0) / 2.0, 0.2, 0.02);
  EXPECT_NEAR(sim.RobotPose("auv").position_m.z(), 2.205, 0.05);
}

TEST_F(ThrusterDriveTest, OdometryFollowsTheTruthThroughTurnsWithTheHullsSway) {
  // Weaving left and right: the hull slips sideways in every turn (0.7 m over 30 s when only
  // surge and yaw were integrated); a DVL measures the sway, so the odometry stays on the truth.
  MujocoSim sim(AuvScenario("floor"));
  SimOutputs out;
  for (int k = 0; k < 6; ++k) Drive(sim, "auv", 0.5, k % 2 ? 0.2 : -0.2, 5.0, &out);
  const common::Pose3 pose = sim.RobotPose("auv");
  const auto* odom = sim.FindSensor<OdometrySensor>("auv");
  ASSERT_NE(odom, nullptr);
  EXPECT_GT(pose.position_m.x(), 10.0);
  EXPECT_NEAR(odom->pose().x_m, pose.position_m.x(), 0.05);
  EXPECT_NEAR(odom->pose().y_m, pose.position_m.y(), 0.05);
  EXPECT_NEAR(common::WrapAngle(odom->pose().yaw_rad - pose.yaw_rad()), 0.0, 0.01);
}

TEST_F(ThrusterDriveTest, CommandsBeyondTheProfileAreClampedAndReverseIsRefused) {
  MujocoSim sim(AuvScenario("floor"));
  // The sparus2_msis profile: surge 0..1 m/s, yaw rate +-0.3 rad/s.
  EXPECT_EQ(sim.Command("auv", -0.5, 0.0), CommandVerdict::kClamped);
  EXPECT_EQ(sim.drive("auv").target_linear_mps(), 0.0);
  EXPECT_EQ(sim.Command("auv", 2.0, 1.0), CommandVerdict::kClamped);
  EXPECT_EQ(sim.drive("auv").target_linear_mps(), 1.0);
  EXPECT_EQ(sim.drive("auv").target_angular_radps(), 0.3);
}

TEST_F(ThrusterDriveTest, ACurrentCarriesAnIdleHull) {
  MujocoSim sim(AuvScenario("floor", 0.1));
  SimOutputs out;
  Idle(sim, 60.0, &out);
  const common::Vector3 velocity = sim.RobotVelocity("auv");
  // Broadside to the current, the hull is soon carried at the water's speed.
  EXPECT_NEAR(velocity.y(), 0.1, 0.01);
  EXPECT_GT(sim.RobotPose("auv").position_m.y(), 3.0);
  EXPECT_NEAR(sim.RobotPose("auv").position_m.z(), 2.205, 0.05);
}

TEST_F(ThrusterDriveTest, ACurrentNeedsWater) {
  Scenario s = MakeScenario("hall", {"r:p3dx::8,1"}, TestPaths());
  s.physics.current_x_mps = 0.1;
  try {
    MujocoSim sim(s);
    FAIL() << "a current in a dry world was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("needs water"), std::string::npos) << e.what();
  }
}

TEST_F(ThrusterDriveTest, ADryWorldKeepsTheWheeledDriveUnchanged) {
  // The seam picks wheels for a wheeled model: a P3-DX still drives at its command.
  Scenario s = MakeScenario("hall", {"r:p3dx::8,1,90"}, TestPaths());
  s.robots[0].sensors = SensorSet{};
  MujocoSim sim(s);
  SimOutputs out;
  Drive(sim, "r", 0.3, 0.0, 5.0, &out);
  EXPECT_NEAR(sim.RobotVelocity("r").y(), 0.3, 0.03);
}

}  // namespace
}  // namespace cairn::sim
