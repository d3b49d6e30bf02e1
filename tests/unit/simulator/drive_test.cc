#include "simulator/drive.h"

#include <cmath>
#include <limits>

#include <gtest/gtest.h>

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

}  // namespace
}  // namespace cairn::sim
