#include "common/body_velocity.h"

#include <gtest/gtest.h>

namespace cairn::common {
namespace {

// Seed 004 test 11: a Twist (vx 0.3, wz 0.1) becomes a body-velocity request with the twist
// copied, the disable mask (F, T, T, T, T, F), priority NORMAL, requester "Twist2BVR", id 0,
// frame "sparus2".
TEST(BodyVelocityTest, Seed004Test11TheBridgeCommandsSurgeAndYawOnly) {
  const BodyVelocityRequest r = BridgeVelocity({0.3, 0.1}, "sparus2");
  EXPECT_EQ(r.twist, (std::array<double, 6>{0.3, 0.0, 0.0, 0.0, 0.0, 0.1}));
  EXPECT_EQ(r.disable_axis, (std::array<bool, 6>{false, true, true, true, true, false}));
  EXPECT_EQ(r.priority, kPriorityNormal);
  EXPECT_EQ(r.requester, "Twist2BVR");
  EXPECT_EQ(r.goal_id, 0);
  EXPECT_EQ(r.frame, "sparus2");
  // And back: the vehicle takes exactly the command.
  const SurgeYaw taken = SurgeYawOf(r);
  EXPECT_EQ(taken.command, (Velocity{0.3, 0.1}));
  EXPECT_FALSE(taken.ignored_axes);
}

TEST(BodyVelocityTest, DisabledAxesReadAsZeroAndUnfollowableAxesAreReported) {
  BodyVelocityRequest r = BridgeVelocity({0.5, -0.2}, "sparus2");
  r.disable_axis[kYaw] = true;
  EXPECT_EQ(SurgeYawOf(r).command, (Velocity{0.5, 0.0}));
  r.disable_axis[kSurge] = true;
  r.twist[kHeave] = 0.4;  // disabled: not a request
  EXPECT_EQ(SurgeYawOf(r).command, (Velocity{0.0, 0.0}));
  EXPECT_FALSE(SurgeYawOf(r).ignored_axes);
  r.disable_axis[kHeave] = false;  // enabled: a depth change it cannot make
  EXPECT_TRUE(SurgeYawOf(r).ignored_axes);
}

}  // namespace
}  // namespace cairn::common
