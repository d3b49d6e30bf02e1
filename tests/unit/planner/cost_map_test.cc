#include "planner/cost_map.h"

#include <random>

#include <gtest/gtest.h>

#include "planner/global/global_planner.h"
#include "tests/unit/planner/test_maps.h"

namespace cairn::planner {
namespace {

using common::Pose2;
using common::Vector2;
using testing::PioneerFootprint;
using testing::SmallFootprint;
using testing::TestLayer;

TEST(CostMapTest, AsymmetricPatternCatchesTransposedOrFlippedGrids) {
  // A 40 × 20 grid at 0.1 m whose minimum corner is at (1, 2). One lethal cell, (30, 5), at
  // world (4.05, 2.55). A transposed, x-flipped or y-flipped reading would put it elsewhere.
  TestLayer layer(40, 20, 0.1, 0.0f, {1.0, 2.0, 0.0});
  layer.cost(30, 5) = 100.0f;
  const auto map = layer.Build(common::RectangleFootprint(0.05, 0.05));
  EXPECT_EQ(map->CostAt({4.05, 2.55}), 100.0f);
  EXPECT_FALSE(map->IsValid({4.05, 2.55, 0.0}));
  EXPECT_FALSE(map->CheckFootprintExact({4.05, 2.55, 0.0}).valid);
  EXPECT_TRUE(map->IsValid({1.0 + 0.95, 2.55, 0.0}));  // x flipped: cell (9, 5)
  EXPECT_TRUE(map->IsValid({4.05, 2.0 + 1.45, 0.0}));  // y flipped: cell (30, 14)
  EXPECT_TRUE(map->IsValid({1.55, 2.0 + 1.95, 0.0}));  // transposed would be (5, 30): (5, 19)
  // The raw storage is x fastest: data()[ix + iy * size_x].
  EXPECT_EQ(map->cost().data()[30 + 5 * 40], 100.0f);

  // A long thin robot (1.0 m × 0.1 m) 0.35 m to the left of the cell: reaches it lying along
  // x, not when turned along y; 0.35 m below it is the other way round.
  const auto thin = layer.Build(common::RectangleFootprint(1.0, 0.1));
  EXPECT_FALSE(thin->IsValid({4.05 - 0.35, 2.55, 0.0}));
  EXPECT_TRUE(thin->IsValid({4.05 - 0.35, 2.55, M_PI / 2}));
  EXPECT_TRUE(thin->IsValid({4.05, 2.55 - 0.35, 0.0}));
  EXPECT_FALSE(thin->IsValid({4.05, 2.55 - 0.35, M_PI / 2}));
  // The robot's front is +x: an asymmetric footprint reaching 0.5 m forward and 0.1 m back.
  const auto nose = layer.Build({{0.5, 0.03}, {-0.1, 0.03}, {-0.1, -0.03}, {0.5, -0.03}});
  EXPECT_FALSE(nose->IsValid({4.05 - 0.4, 2.55, 0.0}));  // facing the cell
  EXPECT_TRUE(nose->IsValid({4.05 - 0.4, 2.55, M_PI}));  // facing away
}

// footprint_padding_m grows the robot's own footprint for every check: a pose whose footprint
// clears a wall by 0.2 m is invalid with 0.3 m of padding.
TEST(CostMapTest, FootprintPaddingGrowsTheRobotsFootprint) {
  TestLayer layer(100, 100, 0.05);
  layer.Rect(0.0, 3.0, 5.0, 5.0, 100.0f);        // a wall from y = 3
  const Pose2 pose{2.5, 3.0 - 0.25 - 0.2, 0.0};  // the 0.5 m wide footprint 0.2 m below it
  EXPECT_TRUE(layer.Build(PioneerFootprint())->IsValid(pose));
  CostMapParams padded;
  padded.footprint_padding_m = 0.3;
  const auto map = layer.Build(PioneerFootprint(), padded);
  EXPECT_FALSE(map->IsValid(pose));
  EXPECT_NEAR(map->footprint().inscribed_radius_m(), 0.25 + 0.3, 0.02);
}

TEST(CostMapTest, RotatedGridOrigin) {
  // The grid's x axis points along world +y: cell (ix, iy) sits at world (-iy, ix) · res.
  TestLayer layer(30, 10, 0.1, 0.0f, {0.0, 0.0, M_PI / 2});
  layer.cost(25, 2) = 100.0f;
  const auto map = layer.Build(common::RectangleFootprint(0.05, 0.05));
  EXPECT_FALSE(map->IsValid({-0.25, 2.55, 0.0}));
  EXPECT_TRUE(map->IsValid({-0.25, 0.55, 0.0}));   // cell (5, 2)
  EXPECT_FALSE(map->IsValid({-2.55, 0.25, 0.0}));  // transposed: off the grid (unknown)
  EXPECT_TRUE(map->Contains({-0.5, 2.0}));
  EXPECT_FALSE(map->Contains({0.5, 2.0}));
}

TEST(CostMapTest, UnknownAndOffMapCells) {
  TestLayer layer(50, 50, 0.1);
  layer.Rect(2.0, 2.0, 3.0, 3.0, NAN).Rect(3.5, 1.0, 4.0, 1.5, 40.0f);
  CostMapParams strict;
  const auto blocked = layer.Build(SmallFootprint(), strict);
  EXPECT_FALSE(blocked->IsValid({2.5, 2.5, 0.0}));
  EXPECT_FALSE(blocked->IsValid({0.1, 1.0, 0.0}));  // hangs off the map
  CostMapParams lenient;
  lenient.unknown_is_traversable = true;
  lenient.unknown_cost = 60.0f;
  const auto open = layer.Build(SmallFootprint(), lenient);
  const FootprintCost c = open->CheckFootprint({2.5, 2.5, 0.0});
  EXPECT_TRUE(c.valid);
  EXPECT_TRUE(c.touches_unknown);
  EXPECT_FLOAT_EQ(c.max_cost, 60.0f);
  EXPECT_FLOAT_EQ(open->CheckFootprint({3.75, 1.25, 0.0}).max_cost, 40.0f);
  EXPECT_FLOAT_EQ(open->TraversalCostAt({2.5, 2.5}), 60.0f);
  EXPECT_FLOAT_EQ(open->TraversalCostAt({30.0, 2.5}), 60.0f);  // off the map
  CostMapParams bad;
  bad.unknown_cost = 100.0f;
  EXPECT_THROW(layer.Build(SmallFootprint(), bad), std::invalid_argument);
  common::Layer wrong(3, 3);
  EXPECT_THROW(CostMap(layer.geometry, wrong, SmallFootprint()), std::invalid_argument);
}

TEST(CostMapTest, ShortcutsAgreeWithTheExactCheck) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int m = 0; m < 6; ++m) {
    TestLayer layer(120, 90, 0.05 + 0.05 * (m % 3), 0.0f, {-1.0, 0.5, 0.0});
    for (int k = 0; k < 25; ++k) {
      const double x = -1.0 + u(rng) * layer.geometry.length_x_m();
      const double y = 0.5 + u(rng) * layer.geometry.length_y_m();
      const float value = k % 3 == 0 ? 100.0f : (k % 3 == 1 ? NAN : 50.0f);
      layer.Rect(x, y, x + u(rng), y + u(rng), value);
    }
    CostMapParams params;
    params.unknown_is_traversable = m % 2 == 0;
    const auto map = layer.Build(PioneerFootprint(), params);
    for (int t = 0; t < 3000; ++t) {
      const Pose2 p{-1.5 + u(rng) * (layer.geometry.length_x_m() + 1.0),
                    0.0 + u(rng) * (layer.geometry.length_y_m() + 1.0), (u(rng) - 0.5) * 2 * M_PI};
      const FootprintCost fast = map->CheckFootprint(p);
      const FootprintCost exact = map->CheckFootprintExact(p);
      ASSERT_EQ(fast.valid, exact.valid) << "map " << m << " pose " << t;
      ASSERT_EQ(map->IsValid(p), exact.valid);
      if (exact.valid) {
        ASSERT_FLOAT_EQ(fast.max_cost, exact.max_cost);
      }
    }
  }
}

// A 0.56 m gap in a wall across x: the pioneer3at (0.63 m x 0.50 m) fits through it facing along
// x, not across; grown by the 0.05 m planning padding on every side it fits at no heading.
TEST(CostMapTest, FitsAtSomeHeadingPerFootprint) {
  TestLayer layer(100, 100, 0.02);
  layer.Rect(0.9, 0.0, 1.1, 0.72, 100.0f).Rect(0.9, 1.28, 1.1, 2.0, 100.0f);
  const auto map = layer.Build(PioneerFootprint());
  const auto& g = map->geometry();
  auto index = [&](double x, double y) {
    const auto c = g.IndexOf({x, y});
    return c->ix + static_cast<int64_t>(c->iy) * g.size_x;
  };
  EXPECT_TRUE(map->IsValid({1.0, 1.0, 0.0}));
  EXPECT_FALSE(map->IsValid({1.0, 1.0, M_PI / 2}));
  for (int repeat = 0; repeat < 2; ++repeat) {  // the second answer comes from the cache
    EXPECT_TRUE(map->FitsAtSomeHeading(index(1.0, 1.0), FootprintKind::kRobot));
    EXPECT_FALSE(map->FitsAtSomeHeading(index(1.0, 1.0), FootprintKind::kPadded));
    EXPECT_TRUE(map->FitsAtSomeHeading(index(0.4, 1.0), FootprintKind::kPadded));
    EXPECT_FALSE(map->FitsAtSomeHeading(index(1.0, 0.5), FootprintKind::kRobot));
  }
}

TEST(CostMapTest, ConnectivityNeverDeniesAPathThePlannerFinds) {
  // Soundness of the "no path" proof: whenever OMPL finds an exact path, the grid says the
  // endpoints may be connected.
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int solved = 0;
  for (int m = 0; m < 12; ++m) {
    TestLayer layer(100, 100, 0.1);
    // Walls with random gaps, some just wider than the robot.
    for (int w = 0; w < 3; ++w) {
      const double x = 2.0 + 3.0 * w;
      const double gap = 2.0 + u(rng) * 6.0;
      const double width = 0.50 + u(rng) * 0.3;
      layer.Rect(x, 0.0, x + 0.2, gap, 100.0f).Rect(x, gap + width, x + 0.2, 10.0, 100.0f);
    }
    const auto map = layer.Build(testing::SmallFootprint());
    GlobalPlannerParams p;
    p.grid_precheck = false;
    // Every map is solvable (gaps of 0.5 m or more, a 0.3 m robot): the budget only bounds a
    // fault, never decides a pass. The first exact path is all the check needs.
    p.time_budget_s = 60.0;
    p.improvement_rounds = 0;
    p.seed = 1 + m;
    const PlanResult r = GlobalPlanner(p).Plan(*map, {{1.0, 5.0, 0.0}, {9.5, 5.0, 0.0}, false});
    if (r.ok()) {
      ++solved;
      EXPECT_TRUE(map->MaybeConnected({1.0, 5.0}, {9.5, 5.0})) << "map " << m;
    }
  }
  EXPECT_EQ(solved, 12);
}

TEST(CostMapTest, RidgeCellsRunDownTheMiddleOfCorridors) {
  // A 1.2 m corridor along x between two walls: the ridge of the distance field is its centre
  // line (y = 5.0), which is where narrow-passage samples go.
  TestLayer layer(100, 100, 0.1);
  layer.Rect(0.0, 0.0, 10.0, 4.4, 100.0f).Rect(0.0, 5.6, 10.0, 10.0, 100.0f);
  const auto map = layer.Build(PioneerFootprint());
  const auto& ridges = map->RidgeCells();
  ASSERT_FALSE(ridges.empty());
  int in_corridor = 0;
  for (const int32_t i : ridges) {
    const Vector2 c = map->geometry().CenterOf({i % 100, i / 100});
    EXPECT_GT(c.y(), 4.4);
    EXPECT_LT(c.y(), 5.6);
    if (c.x() > 1.0 && c.x() < 9.0) {
      EXPECT_NEAR(c.y(), 5.0, 0.11);
      ++in_corridor;
    }
  }
  EXPECT_GE(in_corridor, 70);
  // The smooth clearance is continuous and matches the cell-centre one at cell centres.
  EXPECT_NEAR(map->SmoothClearanceAt({5.05, 5.05}), map->ClearanceAt({5.05, 5.05}), 1e-6);
  EXPECT_LT(std::abs(map->SmoothClearanceAt({5.0, 5.0}) - map->SmoothClearanceAt({5.0, 5.01})),
            0.011);
}

TEST(CostMapTest, BlockingCellsUnderTheRobotAndCheckingAroundThem) {
  TestLayer layer(60, 60, 0.1);
  layer.Rect(3.25, 0.0, 3.6, 6.0, 100.0f);
  const auto map = layer.Build(PioneerFootprint());
  const Pose2 touching{3.0, 3.0, 0.0};  // front at 3.315: cells of x 3.2..3.4 are under it
  ASSERT_FALSE(map->IsValid(touching));
  const auto cells = map->BlockingCellsUnder(touching);
  ASSERT_FALSE(cells.empty());
  EXPECT_TRUE(std::is_sorted(cells.begin(), cells.end()));
  for (const int64_t i : cells)
    EXPECT_TRUE(map->IsBlockedCell({static_cast<int>(i % 60), static_cast<int>(i / 60)}));
  EXPECT_TRUE(map->CheckFootprintIgnoring(touching, cells).valid);
  EXPECT_TRUE(map->CheckFootprintIgnoring({2.9, 3.0, 0.0}, cells).valid);
  EXPECT_FALSE(map->CheckFootprintIgnoring({3.2, 3.0, 0.0}, cells).valid);  // deeper: new cells
  EXPECT_TRUE(map->BlockingCellsUnder({2.0, 3.0, 0.0}).empty());
  // The known-cell bounding box.
  TestLayer partial(40, 30, 0.1, NAN);
  partial.Rect(1.0, 0.5, 2.0, 1.5, 0.0f);
  const auto known = partial.Build(PioneerFootprint())->known_cells();
  ASSERT_TRUE(known.has_value());
  EXPECT_EQ(known->first, (common::CellIndex{10, 5}));
  EXPECT_EQ(known->second, (common::CellIndex{19, 14}));
  EXPECT_FALSE(TestLayer(5, 5, 0.1, NAN).Build(PioneerFootprint())->known_cells().has_value());
}

TEST(CostMapTest, ConnectivitySeparatesWalledOffRegions) {
  TestLayer layer(100, 50, 0.1);
  layer.Rect(4.9, 0.0, 5.1, 5.0, 100.0f);
  const auto map = layer.Build(PioneerFootprint());
  EXPECT_FALSE(map->MaybeConnected({2.0, 2.5}, {8.0, 2.5}));
  EXPECT_TRUE(map->MaybeConnected({2.0, 2.5}, {2.0, 4.0}));
  EXPECT_EQ(map->ComponentOf({5.0, 2.5}), -1);
  EXPECT_EQ(map->ComponentOf({50.0, 2.5}), -1);
  EXPECT_NEAR(map->ClearanceAt({4.0, 2.5}), 0.9, 1e-6);
}

}  // namespace
}  // namespace cairn::planner
