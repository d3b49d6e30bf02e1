#include "planner/global/coarse_route.h"

#include <cmath>

#include <gtest/gtest.h>

#include "planner/global/grid_astar.h"
#include "tests/unit/planner/test_maps.h"

namespace cairn::planner {
namespace {

using common::Vector2;
using testing::PioneerFootprint;
using testing::SmallFootprint;
using testing::TestLayer;
using testing::WallWithGap;

// Every segment of the route keeps the inscribed disc clear of blocking cells (the rule of
// passable cells), checked every 0.02 m.
void ExpectRouteClear(const CostMap& map, const GridPath& route) {
  const double inscribed = map.footprint().inscribed_radius_m();
  for (size_t k = 1; k < route.points_m.size(); ++k) {
    const Vector2 a = route.points_m[k - 1], b = route.points_m[k];
    const int n = std::max(1, static_cast<int>(std::ceil((b - a).norm() / 0.02)));
    for (int i = 0; i <= n; ++i) {
      const Vector2 p = a + (b - a) * (static_cast<double>(i) / n);
      EXPECT_GT(map.ClearanceAt(p), inscribed - 0.1) << "segment " << k << " at " << p.transpose();
    }
  }
}

TEST(CoarseRouteTest, ThroughTheGapLikeTheGridAStar) {
  const auto map = WallWithGap().Build(PioneerFootprint());
  const GridPath fine = GridAStar(*map, {2.0, 2.0}, {18.0, 2.0});
  for (const int stride : {1, 4, 6}) {
    CoarseRouteParams p;
    p.stride_cells = stride;
    const GridPath coarse = CoarseGridRoute(*map, {2.0, 2.0}, {18.0, 2.0}, p);
    ASSERT_TRUE(coarse.found) << stride;
    EXPECT_LT((coarse.points_m.front() - Vector2(2.0, 2.0)).norm(), 0.08);
    EXPECT_LT((coarse.points_m.back() - Vector2(18.0, 2.0)).norm(), 0.08);
    EXPECT_LT(coarse.length_m, 1.1 * fine.length_m) << stride;
    ExpectRouteClear(*map, coarse);
    if (stride == 4) {
      EXPECT_LT(coarse.expanded, fine.expanded / 4);
    }
  }
}

TEST(CoarseRouteTest, CostAwareAndNotFoundWhenClosed) {
  TestLayer band(200, 100, 0.1);
  band.Rect(9.0, 0.0, 11.0, 8.0, 90.0f);
  const auto banded = band.Build(SmallFootprint());
  CoarseRouteParams cheap;
  cheap.traversal_cost_weight = 0.0;
  CoarseRouteParams careful;
  careful.traversal_cost_weight = 10.0;
  const GridPath straight = CoarseGridRoute(*banded, {2.0, 2.0}, {18.0, 2.0}, cheap);
  const GridPath around = CoarseGridRoute(*banded, {2.0, 2.0}, {18.0, 2.0}, careful);
  ASSERT_TRUE(straight.found && around.found);
  EXPECT_LT(straight.length_m, 16.5);
  EXPECT_GT(around.length_m, 18.0);

  TestLayer closed = WallWithGap();
  closed.Rect(9.8, 5.9, 10.2, 7.3, 100.0f);
  const auto walled = closed.Build(PioneerFootprint());
  EXPECT_FALSE(CoarseGridRoute(*walled, {2.0, 2.0}, {18.0, 2.0}, {}).found);
  // Ends outside the grid or on blocking cells.
  EXPECT_FALSE(CoarseGridRoute(*walled, {-1.0, 2.0}, {18.0, 2.0}, {}).found);
  EXPECT_FALSE(CoarseGridRoute(*walled, {10.0, 2.0}, {18.0, 2.0}, {}).found);
}

// A 0.5 m gap on the straight line and a 1.2 m gap 5 m aside. The pioneer3at's inscribed disc
// (0.25 m) passes the narrow gap, but its footprint (0.63 m x 0.50 m, 0.05 m more with the
// planning padding) fits there at no heading: the route takes the wide gap.
TEST(CoarseRouteTest, AGapTheDiscPassesButNoHeadingFitsIsNotAWayThrough) {
  TestLayer layer(200, 100, 0.1);
  layer.Rect(9.8, 0.0, 10.2, 2.0, 100.0f)
      .Rect(9.8, 2.5, 10.2, 7.0, 100.0f)
      .Rect(9.8, 8.2, 10.2, 10.0, 100.0f);
  const auto map = layer.Build(PioneerFootprint());
  const Vector2 gap(10.0, 2.25);
  ASSERT_GT(map->ClearanceAt(gap), map->footprint().inscribed_radius_m() - 0.1);
  const auto cell = map->geometry().IndexOf(gap);
  ASSERT_TRUE(cell);
  const int64_t i = cell->ix + static_cast<int64_t>(cell->iy) * map->geometry().size_x;
  EXPECT_FALSE(map->FitsAtSomeHeading(i, FootprintKind::kRobot));
  EXPECT_FALSE(map->FitsAtSomeHeading(i, FootprintKind::kPadded));
  for (const int stride : {1, 4}) {
    CoarseRouteParams p;
    p.stride_cells = stride;
    const GridPath route = CoarseGridRoute(*map, {2.0, 2.25}, {18.0, 2.25}, p);
    ASSERT_TRUE(route.found) << stride;
    EXPECT_GT(route.length_m, 19.0) << stride;  // round by the wide gap (the straight line: 16 m)
    for (size_t k = 1; k < route.points_m.size(); ++k) {
      const Vector2 a = route.points_m[k - 1], b = route.points_m[k];
      if ((a.x() - 10.0) * (b.x() - 10.0) > 0.0) continue;  // not across the wall
      EXPECT_GT(std::min(a.y(), b.y()), 6.9) << "stride " << stride << " crossed at y " << a.y();
    }
  }
}

TEST(CoarseRouteTest, SameBlockAndStopAndBadStride) {
  const auto map = WallWithGap().Build(PioneerFootprint());
  const GridPath near = CoarseGridRoute(*map, {2.0, 2.0}, {2.15, 2.1}, {});
  ASSERT_TRUE(near.found);
  EXPECT_EQ(near.points_m.size(), 2u);
  EXPECT_FALSE(CoarseGridRoute(*map, {2.0, 2.0}, {18.0, 2.0}, {}, [] { return true; }).found);
  CoarseRouteParams bad;
  bad.stride_cells = 0;
  EXPECT_THROW(CoarseGridRoute(*map, {2.0, 2.0}, {18.0, 2.0}, bad), std::invalid_argument);
}

}  // namespace
}  // namespace cairn::planner
