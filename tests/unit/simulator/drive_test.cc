#include "simulator/drive.h"

#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "simulator/sensors.h"

namespace cairn::sim {
namespace {

common::VelocityLimits Limits() {
  common::VelocityLimits l;
  l.max_vel_x_mps = 0.5;
  l.min_vel_x_mps = -0.2;
  l.max_vel_theta_radps = 1.0;
  l.acc_lim_x_mps2 = 1.0;
  l.acc_lim_theta_radps2 = 2.0;
  return l;
}

TEST(DriveControllerTest, NonFiniteCommandsAreDroppedAndKeepThePreviousOne) {
  DriveController drive(Limits(), 0.1, 0.4);
  EXPECT_EQ(drive.SetCommand(0.3, 0.1, 0.0), CommandVerdict::kAccepted);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_EQ(drive.SetCommand(nan, 0.0, 0.1), CommandVerdict::kDropped);
  EXPECT_EQ(drive.SetCommand(0.1, inf, 0.1), CommandVerdict::kDropped);
  EXPECT_EQ(drive.SetCommand(-inf, nan, 0.1), CommandVerdict::kDropped);
  EXPECT_EQ(drive.target_linear_mps(), 0.3);
  EXPECT_EQ(drive.target_angular_radps(), 0.1);
  // A dropped command does not feed the watchdog.
  drive.Update(0.6, 0.01);
  EXPECT_TRUE(drive.watchdog_active());
}

TEST(DriveControllerTest, CommandsBeyondTheLimitsAreClamped) {
  DriveController drive(Limits(), 0.1, 0.4);
  EXPECT_EQ(drive.SetCommand(2.0, 0.0, 0.0), CommandVerdict::kClamped);
  EXPECT_EQ(drive.target_linear_mps(), 0.5);
  EXPECT_EQ(drive.SetCommand(-1.0, -5.0, 0.0), CommandVerdict::kClamped);
  EXPECT_EQ(drive.target_linear_mps(), -0.2);
  EXPECT_EQ(drive.target_angular_radps(), -1.0);
  EXPECT_EQ(drive.SetCommand(0.5, 1.0, 0.0), CommandVerdict::kAccepted);
}

TEST(DriveControllerTest, RampsWithinAccelerationLimitsAndMixesWheels) {
  DriveController drive(Limits(), 0.1, 0.4);
  drive.SetCommand(0.5, 1.0, 0.0);
  drive.Update(0.0, 0.1);
  EXPECT_NEAR(drive.linear_mps(), 0.1, 1e-12);     // 1.0 m/s^2 * 0.1 s
  EXPECT_NEAR(drive.angular_radps(), 0.2, 1e-12);  // 2.0 rad/s^2 * 0.1 s
  for (int i = 1; i <= 10; ++i) {
    drive.SetCommand(0.5, 1.0, 0.1 * i);  // keep the watchdog fed
    drive.Update(0.1 * i, 0.1);
  }
  EXPECT_NEAR(drive.linear_mps(), 0.5, 1e-12);
  EXPECT_NEAR(drive.angular_radps(), 1.0, 1e-12);
  // v -/+ w * track / 2 over the radius.
  EXPECT_NEAR(drive.left_wheel_radps(), (0.5 - 0.2) / 0.1, 1e-12);
  EXPECT_NEAR(drive.right_wheel_radps(), (0.5 + 0.2) / 0.1, 1e-12);
}

TEST(DriveControllerTest, WatchdogStopsAfterHalfASecondWithoutCommands) {
  DriveController drive(Limits(), 0.1, 0.4);
  drive.SetCommand(0.4, 0.0, 1.0);
  double t = 1.0;
  bool fired = false;
  for (; t < 1.49; t += 0.01) fired |= drive.Update(t, 0.01);
  EXPECT_FALSE(fired);
  EXPECT_FALSE(drive.watchdog_active());
  EXPECT_EQ(drive.target_linear_mps(), 0.4);
  for (; t < 1.52; t += 0.01) fired |= drive.Update(t, 0.01);
  EXPECT_TRUE(fired);
  EXPECT_TRUE(drive.watchdog_active());
  EXPECT_EQ(drive.target_linear_mps(), 0.0);
  for (; t < 3.0; t += 0.01) EXPECT_FALSE(drive.Update(t, 0.01));  // fires once
  EXPECT_EQ(drive.linear_mps(), 0.0);
  EXPECT_EQ(drive.left_wheel_radps(), 0.0);
}

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

TEST(NoiseSourceTest, GaussianHasUnitVarianceAndDependsOnlyOnIndex) {
  NoiseSource noise(42, 7);
  double sum = 0.0, sum2 = 0.0;
  const int n = 200000;
  for (int i = 0; i < n; ++i) {
    const double x = noise.Gaussian(i);
    sum += x;
    sum2 += x * x;
  }
  EXPECT_NEAR(sum / n, 0.0, 0.01);
  EXPECT_NEAR(sum2 / n, 1.0, 0.02);
  EXPECT_EQ(noise.Gaussian(12345), NoiseSource(42, 7).Gaussian(12345));
  EXPECT_NE(noise.Gaussian(12345), NoiseSource(43, 7).Gaussian(12345));
  EXPECT_NE(noise.Gaussian(12345), NoiseSource(42, 8).Gaussian(12345));
}

}  // namespace
}  // namespace cairn::sim
