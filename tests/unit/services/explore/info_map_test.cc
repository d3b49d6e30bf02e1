#include "services/explore/info_map.h"

#include <cmath>
#include <stdexcept>

#include <gtest/gtest.h>

#include "tests/unit/services/explore/explore_test_support.h"

namespace cairn::explore {
namespace {

ScoredPoint Point(double x, double y, float f, float b, float d) {
  ScoredPoint p;
  p.position_m = {static_cast<float>(x), static_cast<float>(y), 0.f};
  p.normal = {0.f, 0.f, 1.f};
  p.navigability = f;
  p.obstacle = b;
  p.quality = d;
  return p;
}

InfoMap SmallMap() {
  InfoMapParams params;
  params.margin_m = 0.0;
  return InfoMap(RectangleWorkArea({0.0, 0.0}, {3.0, 3.0}), params);
}

// Seed 002 test 9.
TEST(InfoMapTest, NavigabilityFollowsTheNavigableAndObstaclePointsOfACell) {
  InfoMap map = SmallMap();
  EXPECT_EQ(map.size_x(), 10);
  const int64_t a = map.Linear({1, 1}), b = map.Linear({2, 2}), c = map.Linear({3, 3}),
                d = map.Linear({4, 4});
  EXPECT_FLOAT_EQ(map.Navigability(a), 0.5f);
  EXPECT_FALSE(map.Explored(a));
  map.AddPoints({Point(0.45, 0.45, 1.f, 0.f, 1.f), Point(0.40, 0.50, 1.f, 0.f, 1.f)});
  EXPECT_FLOAT_EQ(map.Navigability(a), 1.0f);
  map.AddPoints({Point(0.75, 0.75, 0.f, 1.f, 1.f)});
  EXPECT_FLOAT_EQ(map.Navigability(b), 0.0f);
  map.AddPoints({Point(1.05, 1.05, 1.f, 0.f, 1.f), Point(1.05, 1.05, 0.f, 1.f, 1.f)});
  EXPECT_FLOAT_EQ(map.Navigability(c), 0.5f);
  // Below both thresholds: explored, navigability unchanged.
  map.AddPoints({Point(1.35, 1.35, 0.65f, 0.83f, 0.3f)});
  EXPECT_FLOAT_EQ(map.Navigability(d), 0.5f);
  EXPECT_TRUE(map.Explored(d));
  map.AddPoints({Point(0.45, 0.45, 0.6f, 0.8f, 1.f)});
  EXPECT_FLOAT_EQ(map.Navigability(a), 1.0f);
}

// Seed 002 test 10.
TEST(InfoMapTest, QualityIsTheMeanOfTheCellsPointsAndPointsLandByFloor) {
  InfoMap map = SmallMap();
  map.AddPoints({Point(0.31, 0.59, 1.f, 0.f, 0.2f), Point(0.599, 0.3, 1.f, 0.f, 0.6f)});
  EXPECT_FLOAT_EQ(map.Quality(map.Linear({1, 1})), 0.4f);
  EXPECT_TRUE(std::isnan(map.Quality(map.Linear({2, 1}))));
  map.AddPoints({Point(0.6, 0.3, 1.f, 0.f, 1.f)});
  EXPECT_FLOAT_EQ(map.Quality(map.Linear({2, 1})), 1.0f);
  EXPECT_FLOAT_EQ(map.Quality(map.Linear({1, 1})), 0.4f);
}

TEST(InfoMapTest, CoverageAndMeanQualityCountOnlyTheWorkArea) {
  InfoMapParams params;
  params.margin_m = 0.6;  // two cells of margin all round
  InfoMap map(RectangleWorkArea({0.0, 0.0}, {3.0, 3.0}), params);
  EXPECT_EQ(map.work_area_cells(), 100);
  map.AddPoints({Point(0.15, 0.15, 1.f, 0.f, 0.8f), Point(-0.45, 0.15, 1.f, 0.f, 0.1f)});
  EXPECT_EQ(map.explored_work_area_cells(), 1);
  EXPECT_DOUBLE_EQ(map.Coverage(), 0.01);
  EXPECT_NEAR(map.MeanQuality(), 0.8, 1e-6);
}

TEST(InfoMapTest, NonFinitePointsAndPointsOffTheGridAreSkipped) {
  InfoMap map = SmallMap();
  EXPECT_EQ(map.AddPoints({Point(NAN, 1.0, 1.f, 0.f, 1.f), Point(50.0, 1.0, 1.f, 0.f, 1.f),
                           Point(1.0, 1.0, NAN, 0.f, 1.f), Point(1.0, 1.0, 1.f, 0.f, 1.f)}),
            1);
}

TEST(InfoMapTest, TheGridMapFormRoundTripsEveryStatistic) {
  InfoMap map = SmallMap();
  map.AddPoints({Point(0.45, 0.45, 1.f, 0.f, 0.7f), Point(1.05, 2.05, 0.f, 1.f, 0.2f)});
  const common::GridMap grid = map.ToGridMap();
  EXPECT_TRUE(std::isnan(grid.at(info_layers::kNavigability)(0, 0)));
  EXPECT_FLOAT_EQ(grid.at(info_layers::kNavigability)(1, 1), 1.f);
  EXPECT_FLOAT_EQ(grid.at(info_layers::kExplored)(3, 6), 1.f);
  const InfoMap back = InfoMap::FromGridMap(grid, map.work_area(), map.params());
  for (int64_t i = 0; i < map.num_cells(); ++i) {
    EXPECT_EQ(back.Explored(i), map.Explored(i));
    EXPECT_FLOAT_EQ(back.Navigability(i), map.Navigability(i));
  }
  EXPECT_EQ(back.explored_work_area_cells(), 2);
  common::GridMap missing = grid;
  missing.RemoveLayer(info_layers::kSumQuality);
  EXPECT_THROW(InfoMap::FromGridMap(missing, map.work_area(), map.params()), std::invalid_argument);
}

TEST(InfoMapTest, SteepPointsSetTheCellsWallExtentAndItRoundTrips) {
  InfoMap map = SmallMap();
  auto at = [](double x, double y, double z, Eigen::Vector3f normal) {
    ScoredPoint p = Point(x, y, 1.f, 0.f, 0.5f);
    p.position_m.z() = static_cast<float>(z);
    p.normal = normal;
    return p;
  };
  const Eigen::Vector3f wall(1.f, 0.f, 0.f), ground(0.f, 0.f, 1.f);
  const Eigen::Vector3f slope45(0.f, 0.6f, 0.8f);  // 37 degrees from the vertical: not steep
  map.AddPoints({at(0.45, 0.45, 0.0, ground), at(0.45, 0.45, 0.2, wall), at(0.45, 0.45, 2.4, wall),
                 at(0.45, 0.45, 3.0, slope45), at(1.05, 1.05, 0.5, slope45)});
  const int64_t wall_cell = map.Linear({1, 1}), other = map.Linear({3, 3});
  EXPECT_FLOAT_EQ(map.SteepLow(wall_cell), 0.2f);
  EXPECT_FLOAT_EQ(map.SteepHigh(wall_cell), 2.4f);
  EXPECT_TRUE(map.Explored(other));
  EXPECT_TRUE(std::isnan(map.SteepLow(other)));  // a gentle slope is not a wall
  EXPECT_TRUE(std::isnan(map.SteepHigh(map.Linear({0, 0}))));
  const common::GridMap grid = map.ToGridMap();
  const InfoMap back = InfoMap::FromGridMap(grid, map.work_area(), map.params());
  EXPECT_FLOAT_EQ(back.SteepLow(wall_cell), 0.2f);
  EXPECT_FLOAT_EQ(back.SteepHigh(wall_cell), 2.4f);
  // A map stored before the wall extents existed still loads, with none.
  common::GridMap older = grid;
  older.RemoveLayer(info_layers::kSteepLowZ);
  older.RemoveLayer(info_layers::kSteepHighZ);
  const InfoMap old = InfoMap::FromGridMap(older, map.work_area(), map.params());
  EXPECT_TRUE(old.Explored(wall_cell));
  EXPECT_TRUE(std::isnan(old.SteepLow(wall_cell)));
}

TEST(InfoMapTest, ACellWithAStepAboveTheRobotsIsNeitherSafeNorBlocking) {
  // Street (z 0) and pavement (z 0.15) are navigable everywhere; the kerb's face, steep points
  // from 0 to 0.15 m, stands in one cell. A robot with an 8 cm step cannot cross it.
  InfoMapParams params;
  params.margin_m = 0.0;
  params.max_step_m = 0.08;
  InfoMap rover(RectangleWorkArea({0.0, 0.0}, {3.0, 3.0}), params);
  params.max_step_m = 0.0;
  InfoMap plain(RectangleWorkArea({0.0, 0.0}, {3.0, 3.0}), params);
  params.max_step_m = 0.2;
  InfoMap climber(RectangleWorkArea({0.0, 0.0}, {3.0, 3.0}), params);
  std::vector<ScoredPoint> points;
  for (double z : {0.0, 0.05, 0.1, 0.15}) {
    ScoredPoint face = Point(1.05, 1.05, 1.f, 0.f, 0.5f);
    face.position_m.z() = static_cast<float>(z);
    face.normal = {-1.f, 0.f, 0.f};
    points.push_back(face);
  }
  points.push_back(Point(1.05, 1.05, 1.f, 0.f, 0.5f));  // the street at its foot
  points.push_back(Point(0.45, 0.45, 1.f, 0.f, 0.5f));  // open street
  for (InfoMap* map : {&rover, &plain, &climber}) map->AddPoints(points);
  const int64_t kerb = rover.Linear({3, 3}), street = rover.Linear({1, 1});
  EXPECT_FLOAT_EQ(plain.Navigability(kerb), 1.f);  // F and B alone: navigable
  EXPECT_FLOAT_EQ(rover.Navigability(kerb), kStepCnc);
  EXPECT_FLOAT_EQ(climber.Navigability(kerb), 1.f);
  EXPECT_FLOAT_EQ(rover.Navigability(street), 1.f);
  // The step never raises C_nc, and it survives a round trip.
  const InfoMap back = InfoMap::FromGridMap(rover.ToGridMap(), rover.work_area(), rover.params());
  EXPECT_FLOAT_EQ(back.Navigability(kerb), kStepCnc);
  params.max_step_m = -0.1;
  EXPECT_THROW(params.Validate(), std::invalid_argument);
}

TEST(InfoMapTest, GroundAStepAboveANeighboursMakesBothCellsUnsafe) {
  // No steep point at all (the face unseen): street at z 0 in column 2, pavement at 0.15 in
  // column 3; beside it a 10 degree slope along x in row 7. Cells are 0.3 m.
  InfoMapParams params;
  params.margin_m = 0.0;
  params.max_step_m = 0.08;
  InfoMap map(RectangleWorkArea({0.0, 0.0}, {3.0, 3.0}), params);
  auto ground = [](double x, double y, double z) {
    ScoredPoint p = Point(x, y, 1.f, 0.f, 0.5f);
    p.position_m.z() = static_cast<float>(z);
    return p;
  };
  map.AddPoints({ground(0.75, 1.05, 0.0), ground(1.05, 1.05, 0.15)});
  EXPECT_FLOAT_EQ(map.Navigability(map.Linear({2, 3})), kStepCnc);
  EXPECT_FLOAT_EQ(map.Navigability(map.Linear({3, 3})), kStepCnc);
  const double rise = 0.3 * std::tan(10.0 * M_PI / 180.0);  // 5.3 cm a cell
  std::vector<ScoredPoint> slope;
  for (int ix = 0; ix < 10; ++ix) slope.push_back(ground(0.15 + 0.3 * ix, 2.25, rise * ix));
  map.AddPoints(slope);
  for (int ix = 0; ix < 10; ++ix) EXPECT_FLOAT_EQ(map.Navigability(map.Linear({ix, 7})), 1.f);
  // A neighbour seen later clears nothing and adds its own step: the pavement cell's other
  // side, at the pavement's height, is safe; the street's other side too.
  map.AddPoints({ground(1.35, 1.05, 0.15), ground(0.45, 1.05, 0.0)});
  EXPECT_FLOAT_EQ(map.Navigability(map.Linear({4, 3})), 1.f);
  EXPECT_FLOAT_EQ(map.Navigability(map.Linear({1, 3})), 1.f);
  EXPECT_FLOAT_EQ(map.Navigability(map.Linear({3, 3})), kStepCnc);
  // Rebuilt from its layers, the map judges the same.
  const InfoMap back = InfoMap::FromGridMap(map.ToGridMap(), map.work_area(), map.params());
  for (int64_t i = 0; i < map.num_cells(); ++i) {
    EXPECT_FLOAT_EQ(back.Navigability(i), map.Navigability(i)) << i;
  }
}

InfoMapParams BridgeParams(double level_gap_m) {
  InfoMapParams params;
  params.margin_m = 0.0;
  params.max_step_m = 0.08;
  params.level_gap_m = level_gap_m;
  return params;
}

TEST(InfoMapTest, TwoLevelsKeepABridgesDeckAndTheFloorUnderItBothNavigable) {
  const InfoMap map = testing::BridgeMap(BridgeParams(1.5));
  ASSERT_EQ(map.num_levels(), 2);
  EXPECT_EQ(map.num_nodes(), 2 * map.num_cells());
  const int64_t n = map.num_cells();
  // Under the deck's middle (3.0, 3.15): the floor below, the deck above, both safe. The deck
  // was seen first; the floor, 3 m lower, took the lower level from it.
  const int64_t under = map.Linear({10, 10});
  EXPECT_NEAR(map.GroundHeight(under), 0.f, 1e-5f);
  EXPECT_GT(map.Navigability(under), 0.7f);
  EXPECT_NEAR(map.GroundHeight(under + n), 3.f, 1e-5f);
  EXPECT_GT(map.Navigability(under + n), 0.7f);
  EXPECT_EQ(map.NodeCell(under + n), under);
  EXPECT_EQ(map.NodeLevel(under + n), 1);
  // The deck's underside (obstacle-like, seen from below) counts for the upper level's points
  // but not for its navigability.
  EXPECT_FLOAT_EQ(map.PointCount(under + n), 8.f);
  EXPECT_TRUE(map.CellExplored(under));
  // Over the canyon's wall (x 1.95): the wall's foot makes the floor there unsafe, the wall's
  // top, seen from below, leaves the deck above it safe.
  const int64_t wall = map.Linear({6, 10});
  EXPECT_LT(map.Navigability(wall), 0.7f);
  EXPECT_GT(map.Navigability(wall + n), 0.7f);
  // The level a robot stands on is the one whose ground is nearest its own.
  EXPECT_EQ(map.NearestLevel(under, 0.2f), under);
  EXPECT_EQ(map.NearestLevel(under, 2.9f), under + n);
  EXPECT_EQ(map.NearestLevel(under + n, std::nanf("")), under);
  const int64_t rim = map.Linear({1, 1});
  EXPECT_EQ(map.NearestLevel(rim, 0.f), rim);  // one level: that one
  EXPECT_FALSE(map.Explored(rim + n));
  // The deck's edge over the canyon (y 2.55) is a drop to the floor beside it: not safe.
  EXPECT_LT(map.Navigability(map.Linear({10, 8}) + n), 0.7f);
  // Coverage counts a cell once.
  EXPECT_EQ(map.explored_work_area_cells(), map.work_area_cells());

  // One level: the deck, its underside and the floor in one cell make neither safe.
  const InfoMap flat = testing::BridgeMap(BridgeParams(0.0));
  EXPECT_EQ(flat.num_levels(), 1);
  EXPECT_LT(flat.Navigability(under), 0.7f);
}

TEST(InfoMapTest, BothLevelsRoundTripAndAMapOfOneLevelStillLoads) {
  const InfoMap map = testing::BridgeMap(BridgeParams(1.5));
  const common::GridMap grid = map.ToGridMap();
  EXPECT_TRUE(grid.HasLayer("explore/upper/navigability"));
  EXPECT_TRUE(grid.HasLayer(info_layers::kFloorZ));
  const InfoMap back = InfoMap::FromGridMap(grid, map.work_area(), map.params());
  for (int64_t i = 0; i < map.num_nodes(); ++i) {
    ASSERT_EQ(back.Explored(i), map.Explored(i)) << i;
    ASSERT_FLOAT_EQ(back.Navigability(i), map.Navigability(i)) << i;
  }
  // A further scan after the round trip places its points as before it: the floor level is
  // stored.
  InfoMap grown = back;
  const int64_t under = map.Linear({10, 10});
  ScoredPoint deck;
  deck.position_m = {3.f, 3.15f, 3.f};
  deck.normal = {0.f, 0.f, 1.f};
  deck.navigability = 1.f;
  grown.AddPoints({deck}, 4.f);
  EXPECT_FLOAT_EQ(grown.PointCount(under + map.num_cells()), 9.f);
  EXPECT_FLOAT_EQ(grown.PointCount(under), 4.f);
  // Loaded with one level, a two-level map keeps its lower level.
  const InfoMap lower = InfoMap::FromGridMap(grid, map.work_area(), BridgeParams(0.0));
  EXPECT_FLOAT_EQ(lower.Navigability(under), map.Navigability(under));
  EXPECT_EQ(lower.num_nodes(), map.num_cells());
  // A map stored with one level loads with two: its upper level empty.
  const InfoMap flat = testing::BridgeMap(BridgeParams(0.0));
  const InfoMap two = InfoMap::FromGridMap(flat.ToGridMap(), flat.work_area(), BridgeParams(1.5));
  EXPECT_FALSE(two.Explored(under + two.num_cells()));
  EXPECT_FLOAT_EQ(two.Navigability(under), flat.Navigability(under));
  InfoMapParams bad = BridgeParams(-1.0);
  EXPECT_THROW(bad.Validate(), std::invalid_argument);
}

TEST(InfoMapTest, BadParamsAndHugeAreasAreRefused) {
  InfoMapParams params;
  params.cell_size_m = 0.0;
  EXPECT_THROW(InfoMap(RectangleWorkArea({0, 0}, {3, 3}), params), std::invalid_argument);
  EXPECT_THROW(InfoMap(RectangleWorkArea({0, 0}, {1e5, 1e5})), std::invalid_argument);
  EXPECT_THROW(InfoMap(WorkArea{}), std::invalid_argument);
}

TEST(InfoMapTest, TheSurfaceBetweenFarPointsExploresTheCellsUnderItsTriangles) {
  // A 3 x 3 m map of 0.3 m cells; four points at the corners of a 2.4 m square (two triangles,
  // as far ground rings leave them), F rising from west to east.
  InfoMap map = SmallMap();
  std::vector<ScoredPoint> points = {
      Point(0.25, 0.25, 0.6f, 0.f, 0.2f), Point(2.65, 0.25, 1.0f, 0.f, 0.4f),
      Point(0.25, 2.65, 0.6f, 0.f, 0.2f), Point(2.65, 2.65, 1.0f, 0.f, 0.4f)};
  std::vector<uint8_t> valid(points.size(), 1);
  const std::vector<Eigen::Vector3i> triangles = {{0, 1, 3}, {0, 3, 2}};
  const std::vector<ScoredPoint> filled = FillSurfaceCells(map, points, valid, triangles);
  // Cell centres inside the square: 0.45 .. 2.55 on both axes, 8 x 8, less the one of them a
  // point falls in (2.65, 2.65 is in the cell centred at 2.55, 2.55); the other three points'
  // cells are centred at 0.15, outside the square.
  EXPECT_EQ(filled.size(), 64u - 1u);
  for (const ScoredPoint& p : filled) {
    EXPECT_GT(p.position_m.x(), 0.25f - 1e-4f);
    EXPECT_LT(p.position_m.x(), 2.65f + 1e-4f);
    // Interpolated: F from 0.6 in the west to 1.0 in the east.
    const float expect_f = 0.6f + 0.4f * (p.position_m.x() - 0.25f) / 2.4f;
    EXPECT_NEAR(p.navigability, expect_f, 1e-4f);
    EXPECT_NEAR(p.normal.z(), 1.f, 1e-5f);
  }
  map.AddPoints(points);
  map.AddPoints(filled);
  EXPECT_EQ(map.explored_work_area_cells(), 64 + 3);
  // Cells the map has explored already are left alone; so is a cell a point falls in.
  EXPECT_TRUE(FillSurfaceCells(map, points, valid, triangles).empty());
  // A vertical triangle (a wall) fills nothing; a triangle with an invalid corner is skipped.
  InfoMap fresh = SmallMap();
  std::vector<ScoredPoint> wall = {Point(1.0, 1.0, 0.f, 1.f, 0.5f), Point(2.0, 1.0, 0.f, 1.f, 0.5f),
                                   Point(2.0, 1.0, 0.f, 1.f, 0.5f)};
  wall[2].position_m.z() = 2.f;
  EXPECT_TRUE(FillSurfaceCells(fresh, wall, {1, 1, 1}, {{0, 1, 2}}).empty());
  // Without the south-east corner only the north-west triangle fills: the 36 centres with
  // x <= y, less the point's cell.
  valid[1] = 0;
  EXPECT_EQ(FillSurfaceCells(fresh, points, valid, triangles).size(), 35u);
  EXPECT_THROW(FillSurfaceCells(fresh, points, {1}, triangles), std::invalid_argument);
  // Indices out of range are skipped, not read.
  EXPECT_TRUE(FillSurfaceCells(fresh, points, {1, 1, 1, 1}, {{0, 1, 7}, {-1, 0, 1}}).empty());
}

}  // namespace
}  // namespace cairn::explore
