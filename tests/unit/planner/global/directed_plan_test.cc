// Plans across a one-way step (the directed layer): the OMPL planner and grid A* cross it in
// the direction it allows, route round by a ramp or answer "no path" the other way, and read
// the cost layer alone exactly as before without the directed layer.

#include <gtest/gtest.h>

#include "planner/global/global_planner.h"
#include "planner/global/grid_astar.h"
#include "tests/unit/planner/test_maps.h"

namespace cairn::planner {
namespace {

using common::Pose2;
using common::Vector2;
using testing::OneWayStepCorridor;
using testing::PioneerFootprint;

GlobalPlannerParams Params() {
  GlobalPlannerParams p;
  p.time_budget_s = 60.0;  // far beyond what a plan needs: the tests assert what, not how fast
  p.improvement_time_s = 60.0;
  p.simplify_time_s = 60.0;
  p.seed = 7;
  return p;
}

// Every motion of the path is one the one-way cells allow, and every pose is valid.
void ExpectDrivable(const CostMap& map, const PlanResult& r) {
  ASSERT_GE(r.poses.size(), 2u);
  for (size_t i = 0; i < r.poses.size(); ++i) {
    EXPECT_TRUE(map.IsValid(r.poses[i])) << i;
    if (i > 0) {
      EXPECT_TRUE(map.MotionAllowed(r.poses[i - 1], r.poses[i]))
          << i << ": (" << r.poses[i - 1].x_m << ", " << r.poses[i - 1].y_m << ", "
          << r.poses[i - 1].yaw_rad << ") to (" << r.poses[i].x_m << ", " << r.poses[i].y_m << ", "
          << r.poses[i].yaw_rad << ")";
    }
  }
}

// The y where the path first passes x = 6 (the step line), or NaN.
double CrossingY(const std::vector<Vector2>& points) {
  for (size_t i = 1; i < points.size(); ++i) {
    const Vector2& a = points[i - 1];
    const Vector2& b = points[i];
    if ((a.x() - 6.0) * (b.x() - 6.0) <= 0.0 && a.x() != b.x()) {
      return a.y() + (b.y() - a.y()) * (6.0 - a.x()) / (b.x() - a.x());
    }
  }
  return NAN;
}
std::vector<Vector2> Positions(const std::vector<Pose2>& poses) {
  std::vector<Vector2> out;
  for (const Pose2& p : poses) out.push_back(p.position());
  return out;
}

TEST(DirectedPlanTest, DownTheStepYesUpItNoPath) {
  const auto layer = OneWayStepCorridor();
  const auto map = layer.Build(PioneerFootprint());
  const GlobalPlanner dut(Params());
  const PlanResult down = dut.Plan(*map, {{9.0, 2.0, M_PI}, {3.0, 2.0, 0.0}, false});
  ASSERT_EQ(down.status, PlanStatus::kSuccess) << down.message;
  ExpectDrivable(*map, down);
  const PlanResult up = dut.Plan(*map, {{3.0, 2.0, 0.0}, {9.0, 2.0, 0.0}, false});
  EXPECT_EQ(up.status, PlanStatus::kNoPath) << up.message;
  // The cost layer alone (an old mapper): the step is lethal both ways, as before.
  const auto isotropic = layer.layer.Build(PioneerFootprint());
  EXPECT_EQ(dut.Plan(*isotropic, {{9.0, 2.0, M_PI}, {3.0, 2.0, 0.0}, false}).status,
            PlanStatus::kNoPath);
}

TEST(DirectedPlanTest, UpItRoutesRoundByTheRamp) {
  const auto map = OneWayStepCorridor(3.5).Build(PioneerFootprint());
  const GlobalPlanner dut(Params());
  const PlanResult up = dut.Plan(*map, {{3.0, 1.5, 0.0}, {9.0, 1.5, 0.0}, false});
  ASSERT_EQ(up.status, PlanStatus::kSuccess) << up.message;
  ExpectDrivable(*map, up);
  EXPECT_GT(CrossingY(Positions(up.poses)), 3.5) << "up by the ramp";
  // Shortcut and merged paths that would drive up the step are undone, not the whole
  // refinement (OMPL's shortcutting checks some motions backwards): a refined path, not the
  // planner's detour.
  EXPECT_TRUE(up.simplified);
  EXPECT_LT(up.length_m, 11.0);
  const PlanResult down = dut.Plan(*map, {{9.0, 1.5, M_PI}, {3.0, 1.5, 0.0}, false});
  ASSERT_EQ(down.status, PlanStatus::kSuccess) << down.message;
  ExpectDrivable(*map, down);
  EXPECT_LT(CrossingY(Positions(down.poses)), 3.5) << "straight down the step";
}

TEST(DirectedPlanTest, ReedsSheppCrossesDownTheStepReversingOrNot) {
  GlobalPlannerParams p = Params();
  p.state_space = StateSpaceKind::kReedsShepp;
  p.turning_radius_m = 0.4;
  const auto map = OneWayStepCorridor().Build(PioneerFootprint());
  const GlobalPlanner dut(p);
  // Facing up the step (+x) with the goal below: down it forwards after a turn, or reversing.
  const PlanResult down = dut.Plan(*map, {{8.0, 2.0, 0.0}, {4.0, 2.0, 0.0}, true});
  ASSERT_EQ(down.status, PlanStatus::kSuccess) << down.message;
  ExpectDrivable(*map, down);
  EXPECT_EQ(dut.Plan(*map, {{4.0, 2.0, 0.0}, {8.0, 2.0, 0.0}, true}).status, PlanStatus::kNoPath);
}

TEST(DirectedPlanTest, GridAStarTakesDirectedSteps) {
  const auto closed = OneWayStepCorridor().Build(PioneerFootprint());
  for (const bool any_angle : {false, true}) {
    SCOPED_TRACE(any_angle ? "Theta*" : "A*");
    GridAStarParams params;
    params.any_angle = any_angle;
    const GridPath down = GridAStar(*closed, {9.0, 2.0}, {3.0, 2.0}, params);
    ASSERT_TRUE(down.found);
    EXPECT_FALSE(GridAStar(*closed, {3.0, 2.0}, {9.0, 2.0}, params).found);
    const auto ramp = OneWayStepCorridor(3.5).Build(PioneerFootprint());
    const GridPath up = GridAStar(*ramp, {3.0, 1.5}, {9.0, 1.5}, params);
    ASSERT_TRUE(up.found);
    EXPECT_GT(CrossingY(up.points_m), 3.5);
    const GridPath down_ramp = GridAStar(*ramp, {9.0, 1.5}, {3.0, 1.5}, params);
    ASSERT_TRUE(down_ramp.found);
    EXPECT_LT(CrossingY(down_ramp.points_m), 3.5);
  }
  // Without the directed layer: no way across in either direction.
  const auto isotropic = OneWayStepCorridor().layer.Build(PioneerFootprint());
  EXPECT_FALSE(GridAStar(*isotropic, {9.0, 2.0}, {3.0, 2.0}).found);
}

}  // namespace
}  // namespace cairn::planner
