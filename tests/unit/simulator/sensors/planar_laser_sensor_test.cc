#include "simulator/sensors/planar_laser_sensor.h"

#include <cmath>

#include <gtest/gtest.h>

#include "simulator/mujoco_sim.h"
#include "tests/unit/simulator/sim_test_util.h"

namespace cairn::sim {
namespace {

using testing::FlatWorld;
using testing::InlineScenario;
using testing::SimTest;

constexpr double kDeg = M_PI / 180.0;

TEST(FanTest, BeamsSpanTheFieldOfViewEdgeToEdge) {
  double angle_min = 0.0, increment = 0.0;
  FanAngles(240.0, 683, &angle_min, &increment);
  EXPECT_DOUBLE_EQ(angle_min, -120.0 * kDeg);
  EXPECT_NEAR(angle_min + 682 * increment, 120.0 * kDeg, 1e-12);
  const RayPattern fan = BuildFanPattern(240.0, 683);
  ASSERT_EQ(fan.directions.size(), 683u);
  EXPECT_NEAR(fan.directions[341].x(), 1.0, 1e-12);  // the centre beam looks ahead
  EXPECT_NEAR(std::atan2(fan.directions[0].y(), fan.directions[0].x()), -120.0 * kDeg, 1e-12);
  for (const auto& d : fan.directions) EXPECT_EQ(d.z(), 0.0);
  // Every beam belongs to exactly one group.
  int covered = 0;
  for (const auto& g : fan.groups) covered += g.end - g.begin;
  EXPECT_EQ(covered, 683);
}

class PlanarLaserSensorTest : public SimTest {};

TEST_F(PlanarLaserSensorTest, ReturnsWithinRangeNoReturnIsInfinityTooCloseIsNan) {
  // A post 2 m ahead (in range), a wall 10 m to the left (beyond 5.6 m), a pillar touching the
  // laser's right side (closer than the minimum range).
  Scenario s = InlineScenario(FlatWorld(R"(
      <geom type="box" size="0.05 0.05 1" pos="2.05 0 1"/>
      <geom type="box" size="20 0.1 1" pos="0 10.1 1"/>)"),
                              "r", "p3dx");
  PlanarLaserParams& p = *s.robots[0].sensors.Find<PlanarLaserSensor>();
  p.range_noise_sigma_m = 0.0;
  p.min_range_m = 0.5;
  p.max_range_m = 5.6;
  MujocoSim sim(s);
  SimOutputs out;
  while (sim.time_s() < 0.1 - 1e-9) sim.Step(&out);
  ASSERT_EQ(out.Readings<PlanarLaserSensor>().size(), 1u);
  const common::LaserScan& scan = out.Readings<PlanarLaserSensor>().front();
  EXPECT_EQ(scan.utime, 100000);
  EXPECT_EQ(scan.robot, "r");
  ASSERT_EQ(scan.ranges_m.size(), 683u);
  ASSERT_EQ(scan.intensities.size(), 683u);
  const double x = scan.sensor_pose.position_m.x();
  EXPECT_NEAR(scan.ranges_m[341], 2.0 - x, 1e-5);
  EXPECT_GT(scan.intensities[341], 0.f);
  // 90 deg left: the wall is 10 m away, out of range.
  const int left =
      static_cast<int>(std::lround((90.0 * kDeg - scan.angle_min_rad) / scan.angle_increment_rad));
  EXPECT_TRUE(std::isinf(scan.ranges_m[left]));
  EXPECT_EQ(scan.intensities[left], 0.f);

  // The same scene with the minimum range beyond the post: it reads NaN.
  Scenario close = s;
  close.robots[0].sensors.Find<PlanarLaserSensor>()->min_range_m = 3.0;
  MujocoSim sim2(close);
  SimOutputs out2;
  while (sim2.time_s() < 0.1 - 1e-9) sim2.Step(&out2);
  EXPECT_TRUE(std::isnan(out2.Readings<PlanarLaserSensor>().front().ranges_m[341]));
}

TEST_F(PlanarLaserSensorTest, NoiseIsSeededPerScanAndBeam) {
  auto centre = [](uint64_t seed) {
    Scenario s = InlineScenario(FlatWorld(R"(<geom type="box" size="0.1 3 1" pos="3.1 0 1"/>)"),
                                "r", "p3dx");
    s.seed = seed;
    s.robots[0].sensors.Find<PlanarLaserSensor>()->range_noise_sigma_m = 0.05;
    MujocoSim sim(s);
    SimOutputs out;
    while (sim.time_s() < 0.2 - 1e-9) sim.Step(&out);
    const auto& scans = out.Readings<PlanarLaserSensor>();
    return std::make_pair(scans[0].ranges_m[341], scans[1].ranges_m[341]);
  };
  const auto a = centre(1), b = centre(1), c = centre(2);
  EXPECT_EQ(a, b);
  EXPECT_NE(a.first, a.second);  // a new draw per scan
  EXPECT_NE(a.first, c.first);
  EXPECT_NEAR(a.first, 3.0, 0.5);  // the wall, seen from the laser near the origin
}

}  // namespace
}  // namespace cairn::sim
