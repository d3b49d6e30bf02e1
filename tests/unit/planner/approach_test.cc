#include "planner/approach.h"

#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "tests/unit/planner/test_maps.h"

namespace cairn::planner {
namespace {

using common::Pose2;
using common::Vector2;
using testing::PioneerFootprint;
using testing::TestLayer;

constexpr float kUnknown = std::numeric_limits<float>::quiet_NaN();

// 20 x 10 m at 0.1 m, unknown but for a known free corridor x 0..12, y 0..4.
TestLayer KnownCorridor() {
  TestLayer layer(200, 100, 0.1, kUnknown);
  layer.Rect(0.0, 0.0, 12.0, 4.0, 0.0f);
  return layer;
}

TEST(ApproachPoseTest, TheKnownPoseNearestTheGoalWhereTheRobotCanTurn) {
  const auto map = KnownCorridor().Build(PioneerFootprint());
  const auto pose = ApproachPose(*map, {2.0, 2.0, 0.0}, {18.0, 2.0});
  ASSERT_TRUE(pose.has_value());
  // As far along as the robot's circumscribed circle (0.40 m) and the padding keep it off the
  // unknown end at x = 12, facing the goal.
  const double circle_m = map->footprint().circumscribed_radius_m() + 0.05;
  EXPECT_NEAR(pose->x_m, 12.0 - circle_m, 0.2);
  EXPECT_NEAR(pose->y_m, 2.0, 0.2);
  EXPECT_NEAR(pose->yaw_rad, 0.0, 0.1);
  EXPECT_TRUE(map->IsValid(*pose));
  EXPECT_GE(map->ClearanceAt(pose->position()), circle_m - 0.1);
}

TEST(ApproachPoseTest, ALethalWallIsNotCrossedAndAnEnclosedStartGoesNowhere) {
  // A wall across the corridor at x = 6: the search stops there.
  TestLayer walled = KnownCorridor();
  walled.Rect(5.9, 0.0, 6.1, 4.0, 100.0f);
  const auto pose = ApproachPose(*walled.Build(PioneerFootprint()), {2.0, 2.0, 0.0}, {18.0, 2.0});
  ASSERT_TRUE(pose.has_value());
  EXPECT_LT(pose->x_m, 6.0);
  // Only the start's own cells known: nothing with room to turn is reached.
  TestLayer tiny(200, 100, 0.1, kUnknown);
  tiny.Rect(1.6, 1.6, 2.4, 2.4, 0.0f);
  EXPECT_FALSE(ApproachPose(*tiny.Build(PioneerFootprint()), {2.0, 2.0, 0.0}, {18.0, 2.0}));
  // A start outside the map.
  EXPECT_FALSE(
      ApproachPose(*KnownCorridor().Build(PioneerFootprint()), {-5.0, 2.0, 0.0}, {18.0, 2.0}));
}

}  // namespace
}  // namespace cairn::planner
