#include "planner/global/ompl_problem.h"

#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "planner/global/coarse_route.h"
#include "planner/global/global_planner.h"
#include "tests/unit/planner/test_maps.h"

namespace cairn::planner::internal {
namespace {

using common::Pose2;
using common::Vector2;
using testing::PioneerFootprint;
using testing::TestLayer;

// A wall across x = 10 with one 0.7 m gap (y 4.0..4.7): the pioneer3at's padded footprint
// (0.73 m x 0.60 m) passes it facing along x, and at no heading more than about 10 deg off.
TestLayer WallWithNarrowGap() {
  TestLayer layer(200, 100, 0.1);
  layer.Rect(9.8, 0.0, 10.2, 3.95, 100.0f).Rect(9.8, 4.75, 10.2, 10.0, 100.0f);
  return layer;
}

GlobalPlannerParams Params() {
  GlobalPlannerParams p;
  p.seed = 7;
  return p;
}

TEST(RepairRouteTest, TurnsTheFootprintThroughAGapTheRouteCrossesAtAnAngle) {
  const auto map = WallWithNarrowGap().Build(PioneerFootprint());
  const Pose2 start{6.0, 2.0, 0.0}, goal{14.0, 7.0, 0.0};
  const OmplProblem problem = SetUpProblem(*map, Params(), start, goal, true, {});
  CoarseRouteParams cp;
  cp.stride_cells = 4;
  const GridPath route = CoarseGridRoute(*map, start.position(), goal.position(), cp);
  ASSERT_TRUE(route.found);
  ob::ScopedState<ob::SE2StateSpace> goal_state(problem.space);
  goal_state->setXY(goal.x_m, goal.y_m);
  goal_state->setYaw(goal.yaw_rad);
  og::PathGeometric path = RouteAsPath(problem, route.points_m, start, goal_state.get());
  EXPECT_FALSE(path.check()) << "the route's own headings fit through the gap";
  ASSERT_TRUE(RepairRoute(problem, &path));
  EXPECT_TRUE(path.check());
  const auto& states = path.getStates();
  EXPECT_LT((ToPose(states.front()).position() - start.position()).norm(), 1e-9);
  EXPECT_LT((ToPose(states.back()).position() - goal.position()).norm(), 1e-9);
}

TEST(RepairRouteTest, FailsWhereNoHeadingFits) {
  // The same gap 0.5 m wide: the inscribed disc passes, the footprint at no heading.
  TestLayer layer(200, 100, 0.1);
  layer.Rect(9.8, 0.0, 10.2, 3.95, 100.0f).Rect(9.8, 4.45, 10.2, 10.0, 100.0f);
  const auto map = layer.Build(PioneerFootprint());
  const Pose2 start{6.0, 4.2, 0.0}, goal{14.0, 4.2, 0.0};
  const OmplProblem problem = SetUpProblem(*map, Params(), start, goal, true, {});
  ob::ScopedState<ob::SE2StateSpace> goal_state(problem.space);
  goal_state->setXY(goal.x_m, goal.y_m);
  goal_state->setYaw(goal.yaw_rad);
  const std::vector<Vector2> points{{6.0, 4.2}, {8.0, 4.2}, {10.0, 4.2}, {12.0, 4.2}, {14.0, 4.2}};
  og::PathGeometric path = RouteAsPath(problem, points, start, goal_state.get());
  EXPECT_FALSE(RepairRoute(problem, &path));
  EXPECT_FALSE(path.check());
}

}  // namespace
}  // namespace cairn::planner::internal
