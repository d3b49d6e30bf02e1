#include "simulator/sensors/turret_sensor.h"

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

TEST(TurretLineRotationTest, BeamZeroPointsUpAndNinetyDegreesAlongThePan) {
  for (double pan : {0.0, 30.0 * kDeg, 90.0 * kDeg}) {
    const Eigen::Matrix3d r = TurretLineRotation(pan);
    EXPECT_TRUE(r.col(0).isApprox(Eigen::Vector3d::UnitZ())) << pan;
    EXPECT_TRUE(r.col(1).isApprox(Eigen::Vector3d(std::cos(pan), std::sin(pan), 0.0))) << pan;
    EXPECT_NEAR(r.determinant(), 1.0, 1e-12);
    EXPECT_TRUE((r.transpose() * r).isIdentity(1e-12));
  }
}

class TurretSensorTest : public SimTest {};

TEST_F(TurretSensorTest, TurretSweepsThePanRange) {
  Scenario s = InlineScenario(FlatWorld(R"(<geom type="box" size="0.1 3 2" pos="4 0 2"/>)"), "r",
                              "pioneer3at");
  s.robots[0].sensors = SensorSet{};
  TurretParams turret;
  turret.range_noise_sigma_m = 0.0;
  s.robots[0].sensors.Set<TurretSensor>(turret);
  MujocoSim sim(s);
  SimOutputs out;
  while (sim.time_s() < 7.3) sim.Step(&out);  // 360 lines at 50 Hz
  ASSERT_GE(out.Readings<TurretSensor>().size(), 360u);
  EXPECT_NEAR(out.Readings<TurretSensor>()[0].pan_rad, 0.0, 1e-12);
  EXPECT_NEAR(out.Readings<TurretSensor>()[1].pan_rad, 0.5 * kDeg, 1e-12);
  EXPECT_NEAR(out.Readings<TurretSensor>()[359].pan_rad, 179.5 * kDeg, 1e-9);
  EXPECT_NEAR(out.Readings<TurretSensor>()[360].pan_rad, 0.0, 1e-12);  // next sweep
  // At pan 0 the beam at +90 deg points along the turret's x axis, at the wall 4 m ahead.
  const common::LaserScan& scan = out.Readings<TurretSensor>()[0].scan;
  const int beam =
      static_cast<int>(std::lround((M_PI / 2 - scan.angle_min_rad) / scan.angle_increment_rad));
  const common::Vector3 end = scan.sensor_pose.Transform(
      common::Vector3(std::cos(scan.angle_min_rad + beam * scan.angle_increment_rad),
                      std::sin(scan.angle_min_rad + beam * scan.angle_increment_rad), 0.0) *
      scan.ranges_m[beam]);
  EXPECT_NEAR(end.x(), 3.9, 1e-3);
}

}  // namespace
}  // namespace cairn::sim
