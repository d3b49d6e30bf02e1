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

TEST(InfoMapTest, BadParamsAndHugeAreasAreRefused) {
  InfoMapParams params;
  params.cell_size_m = 0.0;
  EXPECT_THROW(InfoMap(RectangleWorkArea({0, 0}, {3, 3}), params), std::invalid_argument);
  EXPECT_THROW(InfoMap(RectangleWorkArea({0, 0}, {1e5, 1e5})), std::invalid_argument);
  EXPECT_THROW(InfoMap(WorkArea{}), std::invalid_argument);
}

}  // namespace
}  // namespace cairn::explore
