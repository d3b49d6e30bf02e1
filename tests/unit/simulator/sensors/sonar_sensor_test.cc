#include "simulator/sensors/sonar_sensor.h"

#include <algorithm>
#include <cmath>

#include <gtest/gtest.h>

#include "simulator/mujoco_sim.h"
#include "tests/unit/simulator/sim_test_util.h"

// The sonar in MuJoCo: a Pioneer 3-DX carrying it on its laser mount (0.3 m over a flat floor)
// in front of a wall; real ray casting into the world.

namespace cairn::sim {
namespace {

using testing::FlatWorld;
using testing::InlineScenario;
using testing::SimTest;

class SonarSensorTest : public SimTest {};

// A wall 4 m high whose face lies 10.5 m ahead of the head (the mount is 0.13 m ahead of the
// robot's centre).
Scenario WallAhead(const std::string& mode, double start_deg) {
  Scenario s = InlineScenario(FlatWorld(R"(<geom type="box" size="0.2 10 2" pos="10.83 0 2"/>)"),
                              "auv", "p3dx");
  SonarParams p;
  p.mode = mode;
  p.mount_site = "laser_mount";
  p.start_deg = start_deg;
  p.intensity_noise_sigma = 0.0;
  s.robots[0].sensors.Set<SonarSensor>(p);
  return s;
}

TEST_F(SonarSensorTest, AWallAheadEchoesInItsBinAndTheFloorStaysUnderDetection) {
  MujocoSim sim(WallAhead("default", 0.0));
  SimOutputs out;
  while (sim.time_s() < 1.0 - 1e-9) sim.Step(&out);
  const auto& pings = out.Readings<SonarSensor>();
  // One round trip to 50 m at 1500 m/s apart: 15 pings a second.
  ASSERT_EQ(pings.size(), 15u);
  const SonarPing& first = pings.front();
  EXPECT_EQ(first.robot, "auv");
  EXPECT_DOUBLE_EQ(first.pan_rad, 0.0);  // the angle it was taken at
  EXPECT_NEAR(pings[1].pan_rad, 0.005, 1e-12);
  ASSERT_EQ(first.bins.size(), 50u);
  const auto peak = std::max_element(first.bins.begin(), first.bins.end());
  EXPECT_EQ(peak - first.bins.begin(), 10);
  EXPECT_GE(*peak, 200);
  for (int k = 0; k < 10; ++k) EXPECT_LE(first.bins[k], 88) << "floor, bin " << k;
  for (int k = 12; k < 50; ++k) EXPECT_EQ(first.bins[k], 0) << "behind the wall, bin " << k;
  // The head looks along the robot's x axis at pan 0, its position the mount's.
  const Eigen::Vector3d ahead = first.sensor_pose.orientation * Eigen::Vector3d::UnitX();
  EXPECT_NEAR(ahead.x(), 1.0, 1e-4);  // the body settles on its wheels
  EXPECT_NEAR(first.sensor_pose.position_m.x(), 0.13, 0.02);
}

// Turned 60 deg to the left the head sees no wall (the wall's end, 10 m to the side at 10.7 m
// ahead, is 43 deg off the axis): the floor only. The faithful mode publishes the angle one step
// on.
TEST_F(SonarSensorTest, PannedAwayFromTheWallItHearsTheFloorOnly) {
  MujocoSim sim(WallAhead("faithful", 60.0));
  SimOutputs out;
  while (sim.time_s() < 0.07) sim.Step(&out);
  const auto& pings = out.Readings<SonarSensor>();
  ASSERT_EQ(pings.size(), 1u);
  // Stepped on past the limit (where the head turns back): 60 deg + 0.005 rad.
  EXPECT_NEAR(pings[0].pan_rad, 60.0 * M_PI / 180.0 + 0.005, 1e-9)
      << "the faithful head publishes its angle after the step";
  const Eigen::Vector3d dir = pings[0].sensor_pose.orientation * Eigen::Vector3d::UnitX();
  EXPECT_NEAR(std::atan2(dir.y(), dir.x()), 60.0 * M_PI / 180.0, 1e-4);
  EXPECT_LE(*std::max_element(pings[0].bins.begin(), pings[0].bins.end()), 87);
}

TEST(SonarParamsTest, BadValuesAreRefusedByName) {
  SonarParams p;
  EXPECT_NO_THROW(p.Validate());
  EXPECT_NEAR(p.PingPeriodS(), 2.0 * 50.0 / 1500.0, 1e-12);
  p.mode = "loud";
  EXPECT_THROW(p.Validate(), std::invalid_argument);
  p = SonarParams();
  p.rays = 1;
  EXPECT_THROW(p.Validate(), std::invalid_argument);
  p = SonarParams();
  p.start_deg = 70.0;
  EXPECT_THROW(p.Validate(), std::invalid_argument);
}

}  // namespace
}  // namespace cairn::sim
