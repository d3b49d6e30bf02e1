#include "planner/global/grid_astar.h"

#include <cmath>

#include <gtest/gtest.h>

#include "tests/unit/planner/test_maps.h"

namespace cairn::planner {
namespace {

using common::Vector2;
using testing::PioneerFootprint;
using testing::SmallFootprint;
using testing::TestLayer;
using testing::WallWithGap;

TEST(GridAStarTest, ShortestAroundTheWallAndCostAware) {
  const auto map = WallWithGap().Build(PioneerFootprint());
  const GridPath p = GridAStar(*map, {2.0, 2.0}, {18.0, 2.0});
  ASSERT_TRUE(p.found);
  EXPECT_GT(p.length_m, 16.0);
  EXPECT_LT(p.length_m, 2.0 * std::hypot(8.0, 4.8) * 1.09);  // octile path through the gap
  // A graded band across an open map: a high weight makes the path go around it.
  TestLayer band(200, 100, 0.1);
  band.Rect(9.0, 0.0, 11.0, 8.0, 90.0f);
  const auto banded = band.Build(SmallFootprint());
  GridAStarParams cheap;
  cheap.traversal_cost_weight = 0.0;
  GridAStarParams careful;
  careful.traversal_cost_weight = 10.0;
  const GridPath straight = GridAStar(*banded, {2.0, 2.0}, {18.0, 2.0}, cheap);
  const GridPath around = GridAStar(*banded, {2.0, 2.0}, {18.0, 2.0}, careful);
  ASSERT_TRUE(straight.found && around.found);
  EXPECT_NEAR(straight.length_m, 16.0, 0.05);
  EXPECT_GT(around.length_m, 18.0);
  for (const Vector2& q : around.points_m) EXPECT_FALSE(q.x() > 9.0 && q.x() < 11.0 && q.y() < 8.0);
  // Not found across a closed wall.
  TestLayer closed = WallWithGap();
  closed.Rect(9.8, 5.9, 10.2, 7.3, 100.0f);
  EXPECT_FALSE(GridAStar(*closed.Build(PioneerFootprint()), {2.0, 2.0}, {18.0, 2.0}).found);
}

TEST(GridAStarTest, AnyAngleSearchIsNearlyTautAndStaysPassable) {
  // Open floor: the any-angle path is the straight line between the two cell centres, where the
  // 8-connected one is 7.8 % longer (11 straight and 5 diagonal steps per (16, 5)).
  TestLayer open(200, 100, 0.1);
  const auto free_map = open.Build(SmallFootprint());
  GridAStarParams any;
  any.any_angle = true;
  const Vector2 a{2.05, 2.05}, b{18.05, 7.05};
  const GridPath straight = GridAStar(*free_map, a, b, any);
  const GridPath octile = GridAStar(*free_map, a, b);
  ASSERT_TRUE(straight.found && octile.found);
  EXPECT_NEAR(straight.length_m, (b - a).norm(), 1e-6);
  EXPECT_EQ(straight.points_m.size(), 2u);
  EXPECT_GT(octile.length_m, 1.07 * (b - a).norm());
  // Through the gap: shorter than the 8-connected path, never shorter than the taut string
  // through the gap's corner, and every point of it keeps the inscribed disc off the wall.
  const auto map = WallWithGap().Build(PioneerFootprint());
  const GridPath through = GridAStar(*map, {2.0, 2.0}, {18.0, 2.0}, any);
  const GridPath grid = GridAStar(*map, {2.0, 2.0}, {18.0, 2.0});
  ASSERT_TRUE(through.found && grid.found);
  EXPECT_LT(through.length_m, grid.length_m - 0.3);
  EXPECT_GT(through.length_m, 2.0 * std::hypot(8.0, 4.0));  // taut over the gap's lower edge
  const double inscribed = map->footprint().inscribed_radius_m();
  for (size_t k = 1; k < through.points_m.size(); ++k) {
    const Vector2 p = through.points_m[k - 1], q = through.points_m[k];
    for (double t = 0.0; t <= 1.0; t += 0.01) {
      ASSERT_GT(map->ClearanceAt(p + t * (q - p)), inscribed - 0.15) << k << " " << t;
    }
  }
  // Cost-aware like the 8-connected search: a heavy weight goes around a graded band.
  TestLayer band(200, 100, 0.1);
  band.Rect(9.0, 0.0, 11.0, 8.0, 90.0f);
  const auto banded = band.Build(SmallFootprint());
  any.traversal_cost_weight = 10.0;
  const GridPath around = GridAStar(*banded, {2.0, 2.0}, {18.0, 2.0}, any);
  ASSERT_TRUE(around.found);
  for (const Vector2& q : around.points_m) EXPECT_FALSE(q.x() > 9.0 && q.x() < 11.0 && q.y() < 8.0);
  any.traversal_cost_weight = 0.0;
  EXPECT_NEAR(GridAStar(*banded, {2.0, 2.0}, {18.0, 2.0}, any).length_m, 16.0, 1e-6);
  // Not found across a closed wall.
  TestLayer closed = WallWithGap();
  closed.Rect(9.8, 5.9, 10.2, 7.3, 100.0f);
  EXPECT_FALSE(GridAStar(*closed.Build(PioneerFootprint()), {2.0, 2.0}, {18.0, 2.0}, any).found);
}

}  // namespace
}  // namespace cairn::planner
