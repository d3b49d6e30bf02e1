#include "simulator/sensors/ground_truth_sensor.h"

#include <gtest/gtest.h>

#include "simulator/mujoco_sim.h"
#include "tests/unit/simulator/sim_test_util.h"

namespace cairn::sim {
namespace {

using testing::Drive;
using testing::FlatWorld;
using testing::InlineScenario;
using testing::SimTest;

class GroundTruthSensorTest : public SimTest {};

TEST_F(GroundTruthSensorTest, IsTheBasePoseAndWorldVelocityAtItsRate) {
  Scenario s = InlineScenario(FlatWorld(), "r", "p3dx", 1.0, 2.0, 0.5);
  s.robots[0].sensors = SensorSet{};
  s.robots[0].sensors.Set<GroundTruthSensor>().rate_hz = 25.0;
  MujocoSim sim(s);
  SimOutputs out;
  Drive(sim, "r", 0.3, 0.2, 2.0, &out);
  const auto& poses = out.Readings<GroundTruthSensor>();
  ASSERT_EQ(poses.size(), 50u);
  const GroundTruthReading& last = poses.back();
  EXPECT_EQ(last.utime, sim.utime());
  EXPECT_EQ(last.robot, "r");
  EXPECT_EQ(last.pose.position_m, sim.RobotPose("r").position_m);
  EXPECT_NEAR(last.pose.orientation.angularDistance(sim.RobotPose("r").orientation), 0.0, 1e-12);
  EXPECT_EQ(last.linear_velocity_mps, sim.RobotVelocity("r"));
  // Turning at about 0.2 rad/s about the world's z axis.
  EXPECT_NEAR(last.angular_velocity_radps.z(), 0.2, 0.02);
  EXPECT_NEAR(last.linear_velocity_mps.norm(), 0.3, 0.02);
}

}  // namespace
}  // namespace cairn::sim
