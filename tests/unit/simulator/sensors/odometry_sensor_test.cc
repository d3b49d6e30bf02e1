#include "simulator/sensors/odometry_sensor.h"

#include <cmath>

#include <gtest/gtest.h>

#include "simulator/mujoco_sim.h"
#include "tests/unit/simulator/sim_test_util.h"

namespace cairn::sim {
namespace {

using testing::Drive;
using testing::FlatWorld;
using testing::InlineScenario;
using testing::SimTest;

constexpr double kDeg = M_PI / 180.0;

TEST(WheelOdometryTest, NoiseFreeIntegrationOfAnArcIsExact) {
  const double radius_m = 0.1, track_m = 0.4;
  WheelOdometry odom(OdometryParams{}, radius_m, track_m, NoiseSource(1, 2));
  odom.Reset({1.0, 2.0, 0.3});
  // A circle of radius R at speed v: wheels at R -/+ track/2.
  const double big_r = 2.0, v = 0.5, dt = 0.002;
  const double w = v / big_r;
  const int steps = 5000;  // 10 s: 2.5 rad around the circle
  for (int i = 0; i < steps; ++i) {
    const double left = (v - w * track_m / 2) * dt / radius_m;
    const double right = (v + w * track_m / 2) * dt / radius_m;
    odom.Integrate(left, right, dt);
  }
  const double theta = w * steps * dt;
  const double x = 1.0 + big_r * (std::sin(0.3 + theta) - std::sin(0.3));
  const double y = 2.0 - big_r * (std::cos(0.3 + theta) - std::cos(0.3));
  EXPECT_NEAR(odom.pose().x_m, x, 1e-9);
  EXPECT_NEAR(odom.pose().y_m, y, 1e-9);
  EXPECT_NEAR(odom.pose().yaw_rad, common::WrapAngle(0.3 + theta), 1e-9);
  EXPECT_NEAR(odom.linear_mps(), v, 1e-9);
  EXPECT_NEAR(odom.angular_radps(), w, 1e-9);
}

TEST(WheelOdometryTest, SlipNoiseDriftsRepeatablyPerSeed) {
  OdometryParams noisy;
  noisy.slip_noise_ratio = 0.05;
  auto run = [&](uint64_t seed) {
    WheelOdometry odom(noisy, 0.1, 0.4, NoiseSource(seed, 9));
    odom.Reset({0, 0, 0});
    for (int i = 0; i < 5000; ++i) odom.Integrate(0.01, 0.01, 0.002);  // straight, 5 m
    return odom.pose();
  };
  const common::Pose2 a = run(1), b = run(1), c = run(2);
  EXPECT_EQ(a, b);
  EXPECT_FALSE(a == c);
  // It drifted off the straight line.
  EXPECT_GT(std::abs(a.y_m) + std::abs(a.yaw_rad), 1e-4);
  EXPECT_NEAR(a.x_m, 5.0, 0.1);
}

class OdometryTest : public SimTest {};

TEST_F(OdometryTest, DriftIsZeroWithNoiseOff) {
  // Differential drives roll without slipping: with no slip noise, odometry follows the true
  // path of a 3 m S-curve to within a centimetre and a degree.
  for (const char* model : {"p3dx", "kobuki"}) {
    Scenario s = InlineScenario(FlatWorld(), "r", model, 1.0, -2.0, 0.5);
    ASSERT_TRUE(s.robots[0].sensors.Has(OdometrySensor::kName));
    ASSERT_EQ(s.robots[0].sensors.Find<OdometrySensor>()->slip_noise_ratio, 0.0);
    MujocoSim sim(s);
    SimOutputs out;
    Drive(sim, "r", 0.3, 0.3, 5.0, &out);
    Drive(sim, "r", 0.3, -0.3, 5.0, &out);
    const common::Pose3 truth = sim.RobotPose("r");
    const common::Pose2 odom = sim.FindSensor<OdometrySensor>("r")->pose();
    EXPECT_NEAR(odom.x_m, truth.position_m.x(), 0.01) << model;
    EXPECT_NEAR(odom.y_m, truth.position_m.y(), 0.01) << model;
    EXPECT_NEAR(common::WrapAngle(odom.yaw_rad - truth.yaw_rad()), 0.0, 1.0 * kDeg) << model;
    // The published readings carry the same estimate.
    ASSERT_FALSE(out.Readings<OdometrySensor>().empty());
    EXPECT_NEAR(out.Readings<OdometrySensor>().back().pose.position_m.x(), odom.x_m, 0.01);
  }
}

TEST_F(OdometryTest, SlipNoiseMakesItDrift) {
  Scenario s = InlineScenario(FlatWorld(), "r", "p3dx");
  s.robots[0].sensors.Find<OdometrySensor>()->slip_noise_ratio = 0.2;
  MujocoSim sim(s);
  SimOutputs out;
  Drive(sim, "r", 0.3, 0.0, 10.0, &out);
  const common::Pose3 truth = sim.RobotPose("r");
  const common::Pose2 odom = sim.FindSensor<OdometrySensor>("r")->pose();
  const double error =
      std::hypot(odom.x_m - truth.position_m.x(), odom.y_m - truth.position_m.y()) +
      std::abs(common::WrapAngle(odom.yaw_rad - truth.yaw_rad()));
  EXPECT_GT(error, 0.02);
}

}  // namespace
}  // namespace cairn::sim
