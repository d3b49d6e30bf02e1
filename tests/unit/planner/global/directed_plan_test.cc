// Plans across a one-way step (the directed layer): the OMPL planner and grid A* cross it in
// the direction it allows, route round by a ramp or answer "no path" the other way, and read
// the cost layer alone exactly as before without the directed layer.

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

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

// The smallest distance from the path's positions (every 5 cm along it) with x in [x0, x1] to
// a one-way cell's centre.
double ClosestToOneWayCells(const CostMap& map, const std::vector<Pose2>& poses, double x0,
                            double x1) {
  double closest = std::numeric_limits<double>::infinity();
  const common::GridGeometry& g = map.geometry();
  for (size_t i = 1; i < poses.size(); ++i) {
    const Vector2 a = poses[i - 1].position(), b = poses[i].position();
    const int n = std::max(1, static_cast<int>(std::ceil((b - a).norm() / 0.05)));
    for (int k = 0; k <= n; ++k) {
      const Vector2 p = a + (b - a) * (static_cast<double>(k) / n);
      if (p.x() < x0 || p.x() > x1) continue;
      for (int iy = 0; iy < g.size_y; ++iy) {
        for (int ix = 0; ix < g.size_x; ++ix) {
          if (map.OneWayMask({ix, iy}) == 0) continue;
          closest = std::min(closest, (g.CenterOf({ix, iy}) - p).norm());
        }
      }
    }
  }
  return closest;
}

TEST(DirectedPlanTest, PathsUpTheRampKeepOffItsSideEdge) {
  // The straight way up the ramp runs 0.3 m from its side edge, where the floor below refuses
  // the climb: a footprint that strays 5 cm towards the edge touches those cells and may no
  // longer drive on. One-way cells keep paths off like blocking cells (clearance_weight).
  const auto map = OneWayStepCorridor(3.5).Build(PioneerFootprint());
  const GlobalPlanner dut(Params());
  const PlanResult up = dut.Plan(*map, {{1.0, 3.8, 0.0}, {11.0, 3.8, 0.0}, false});
  ASSERT_EQ(up.status, PlanStatus::kSuccess) << up.message;
  ExpectDrivable(*map, up);
  const double inscribed_m = map->footprint().inscribed_radius_m();
  EXPECT_GT(ClosestToOneWayCells(*map, up.poses, 4.0, 6.0), inscribed_m + 0.25);
  // The clearance term does not count one-way cells when it is off.
  GlobalPlannerParams off = Params();
  off.clearance_weight = 0.0;
  const PlanResult hugging =
      GlobalPlanner(off).Plan(*map, {{1.0, 3.8, 0.0}, {11.0, 3.8, 0.0}, false});
  ASSERT_EQ(hugging.status, PlanStatus::kSuccess) << hugging.message;
  EXPECT_LT(ClosestToOneWayCells(*map, hugging.poses, 4.0, 6.0), inscribed_m + 0.2);
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
