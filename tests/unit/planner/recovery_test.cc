#include "planner/recovery.h"

#include <gtest/gtest.h>

#include "tests/unit/planner/test_maps.h"

namespace cairn::planner {
namespace {

using common::Pose2;
using testing::PioneerFootprint;
using testing::TestLayer;

class RecoveryTest : public ::testing::Test {
 protected:
  RecoveryTest()
      : limits_(VelocityLimits::FromProfile(testing::PioneerProfile())), gen_(limits_, {}) {}

  // Steps a behaviour with a kinematic robot; returns the number of cycles until done.
  int Run(RecoveryBehaviour* dut, const CostMap* map, Pose2* pose, int max_cycles,
          bool* clear_requested = nullptr, int* clear_count = nullptr) {
    Velocity last;
    double t = 0.0;
    for (int k = 0; k < max_cycles; ++k) {
      t += 0.05;
      const RecoveryStep step = dut->Step(*pose, last, map, t);
      EXPECT_TRUE(limits_.Allows(last, step.command, 0.05, 1e-12)) << "cycle " << k;
      if (step.request_clear_short_term) {
        if (clear_requested) *clear_requested = true;
        if (clear_count) ++*clear_count;
      }
      last = step.command;
      pose->x_m += last.linear_mps * 0.05 * std::cos(pose->yaw_rad);
      pose->y_m += last.linear_mps * 0.05 * std::sin(pose->yaw_rad);
      pose->yaw_rad = common::WrapAngle(pose->yaw_rad + last.angular_radps * 0.05);
      if (step.done) {
        note_ = step.note;
        last_blocked_ = step.blocked;
        EXPECT_EQ(last.linear_mps, 0.0);
        EXPECT_EQ(last.angular_radps, 0.0);
        return k + 1;
      }
    }
    return -1;
  }
  VelocityLimits limits_;
  TrajectoryGenerator gen_;
  std::string note_;
  bool last_blocked_{false};
};

TEST_F(RecoveryTest, RotateTurnsByTheAngleAndStops) {
  TestLayer layer(60, 60, 0.1);
  const auto map = layer.Build(PioneerFootprint());
  RecoveryParams p;
  RecoveryBehaviour dut(gen_, p);
  Pose2 pose{3.0, 3.0, 0.0};
  dut.Start(RecoveryKind::kRotate, pose, 0.0);
  const int cycles = Run(&dut, map.get(), &pose, 400);
  ASSERT_GT(cycles, 0);
  EXPECT_NEAR(pose.yaw_rad, p.rotate_angle_rad, 0.15);
  EXPECT_NEAR(pose.x_m, 3.0, 1e-9);
}

TEST_F(RecoveryTest, BackUpReversesTheDistanceUnlessBlocked) {
  TestLayer layer(60, 60, 0.1);
  const auto map = layer.Build(PioneerFootprint());
  RecoveryBehaviour dut(gen_, {});
  Pose2 pose{3.0, 3.0, M_PI / 2};
  dut.Start(RecoveryKind::kBackUp, pose, 0.0);
  ASSERT_GT(Run(&dut, map.get(), &pose, 400), 0);
  EXPECT_NEAR(pose.x_m, 3.0, 1e-6);
  EXPECT_LT(pose.y_m, 3.0 - 0.29);
  EXPECT_GT(pose.y_m, 3.0 - 0.35);
  // A wall right behind: it does not move back into it.
  TestLayer walled(60, 60, 0.1);
  walled.Rect(0.0, 0.0, 6.0, 2.6, 100.0f);
  const auto wmap = walled.Build(PioneerFootprint());
  Pose2 close{3.0, 3.0, M_PI / 2};
  ASSERT_TRUE(wmap->IsValid(close));
  dut.Start(RecoveryKind::kBackUp, close, 0.0);
  ASSERT_GT(Run(&dut, wmap.get(), &close, 400), 0);
  EXPECT_EQ(note_, "backing up is blocked");
  EXPECT_TRUE(wmap->IsValid(close));
}

TEST_F(RecoveryTest, RotateTurnsClockwiseWhereOnlyThatWayIsClear) {
  // A long robot with something at its front-left and back-right corners: turning
  // counter-clockwise sweeps into both, clockwise into neither.
  TestLayer layer(60, 60, 0.1);
  layer.Rect(3.5, 3.3, 3.9, 3.6, 100.0f).Rect(2.1, 2.4, 2.5, 2.7, 100.0f);
  const auto map = layer.Build(common::RectangleFootprint(1.5, 0.4));
  RecoveryParams p;
  p.rotate_angle_rad = 0.5;
  RecoveryBehaviour dut(gen_, p);
  Pose2 pose{3.0, 3.0, 0.0};
  ASSERT_TRUE(map->IsValid(pose));
  ASSERT_FALSE(MotionClear(map.get(), pose, {0.0, p.rotate_speed_radps}, 0.5));
  ASSERT_TRUE(MotionClear(map.get(), pose, {0.0, -p.rotate_speed_radps}, 0.5));
  dut.Start(RecoveryKind::kRotate, pose, 0.0);
  ASSERT_GT(Run(&dut, map.get(), &pose, 400), 0);
  EXPECT_NEAR(pose.yaw_rad, -0.5, 0.15) << note_;
  EXPECT_TRUE(map->IsValid(pose));
  EXPECT_FALSE(last_blocked_);
}

TEST_F(RecoveryTest, TurnsAndReversesBlockedBeforeTheyMovedSaySo) {
  // A long robot in a corridor just wider than it is, a wall at its tail: it can neither turn
  // nor back up, and both say they were blocked where they stood.
  TestLayer layer(60, 60, 0.1);
  layer.Rect(0.0, 0.0, 6.0, 2.65, 100.0f).Rect(0.0, 3.35, 6.0, 6.0, 100.0f);
  layer.Rect(0.0, 0.0, 2.15, 6.0, 100.0f);
  const auto map = layer.Build(common::RectangleFootprint(1.5, 0.4));
  RecoveryBehaviour dut(gen_, {});
  Pose2 pose{3.0, 3.0, 0.0};
  ASSERT_TRUE(map->IsValid(pose));
  dut.Start(RecoveryKind::kRotate, pose, 0.0);
  ASSERT_GT(Run(&dut, map.get(), &pose, 100), 0);
  EXPECT_EQ(note_, "rotation blocked");
  EXPECT_TRUE(last_blocked_);
  EXPECT_TRUE(map->IsValid(pose));
  dut.Start(RecoveryKind::kBackUp, pose, 0.0);
  ASSERT_GT(Run(&dut, map.get(), &pose, 100), 0);
  EXPECT_EQ(note_, "backing up is blocked");
  EXPECT_TRUE(last_blocked_);
  // The way ahead is clear: drive_forward takes it, its distance and no further.
  dut.Start(RecoveryKind::kDriveForward, pose, 0.0);
  ASSERT_GT(Run(&dut, map.get(), &pose, 400), 0);
  EXPECT_FALSE(last_blocked_) << note_;
  EXPECT_GT(pose.x_m, 3.0 + 0.29);
  EXPECT_LT(pose.x_m, 3.0 + 0.35);
  EXPECT_NEAR(pose.y_m, 3.0, 1e-6);
  EXPECT_TRUE(map->IsValid(pose));
}

TEST_F(RecoveryTest, DriveForwardStopsAtAWallAhead) {
  TestLayer layer(60, 60, 0.1);
  layer.Rect(0.0, 3.4, 6.0, 6.0, 100.0f);
  const auto map = layer.Build(PioneerFootprint());
  RecoveryBehaviour dut(gen_, {});
  // 3.5 cm short of the wall: blocked where it stands.
  Pose2 pose{3.0, 3.05, M_PI / 2};
  ASSERT_TRUE(map->IsValid(pose));
  dut.Start(RecoveryKind::kDriveForward, pose, 0.0);
  ASSERT_GT(Run(&dut, map.get(), &pose, 400), 0);
  EXPECT_EQ(note_, "driving forward is blocked");
  EXPECT_TRUE(last_blocked_);
  EXPECT_TRUE(map->IsValid(pose));
  // 30 cm short: it drives up to the wall, stops there, and has moved (not blocked).
  pose = {3.0, 2.8, M_PI / 2};
  dut.Start(RecoveryKind::kDriveForward, pose, 0.0);
  ASSERT_GT(Run(&dut, map.get(), &pose, 400), 0);
  EXPECT_EQ(note_, "driving forward is blocked");
  EXPECT_FALSE(last_blocked_);
  EXPECT_GT(pose.y_m, 2.9);
  EXPECT_TRUE(map->IsValid(pose));
  EXPECT_EQ(RecoveryKindFromName("drive_forward"), RecoveryKind::kDriveForward);
}

TEST_F(RecoveryTest, WaitAndClearShortTerm) {
  TestLayer layer(60, 60, 0.1);
  const auto map = layer.Build(PioneerFootprint());
  RecoveryParams p;
  p.wait_s = 1.0;
  p.clear_wait_s = 0.5;
  RecoveryBehaviour dut(gen_, p);
  Pose2 pose{3.0, 3.0, 0.0};
  dut.Start(RecoveryKind::kWait, pose, 0.0);
  EXPECT_NEAR(Run(&dut, map.get(), &pose, 400), 20, 1);
  int clears = 0;
  dut.Start(RecoveryKind::kClearShortTerm, pose, 0.0);
  EXPECT_NEAR(Run(&dut, map.get(), &pose, 400, nullptr, &clears), 10, 1);
  EXPECT_EQ(clears, 1);
  EXPECT_EQ(RecoveryKindFromName("back_up"), RecoveryKind::kBackUp);
  EXPECT_THROW(RecoveryKindFromName("spin"), std::invalid_argument);
}

}  // namespace
}  // namespace cairn::planner
