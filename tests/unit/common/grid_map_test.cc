#include "common/grid_map.h"

#include <cmath>

#include <gtest/gtest.h>

namespace cairn::common {
namespace {

GridGeometry Geometry(double res, int nx, int ny, Pose2 origin = {}) {
  GridGeometry g;
  g.resolution_m = res;
  g.size_x = nx;
  g.size_y = ny;
  g.origin = origin;
  return g;
}

TEST(GridGeometryTest, FloorNotTruncation) {
  const GridGeometry g = Geometry(0.05, 800, 800, {-20.0, -20.0, 0.0});
  // Seed 003 test 10: (0,0) -> (400,400); (1.0,-2.0) -> col 420 row 360; (-0.03, 0) -> col 399.
  EXPECT_EQ(g.IndexOf({0.0, 0.0}), (CellIndex{400, 400}));
  EXPECT_EQ(g.IndexOf({1.0, -2.0}), (CellIndex{420, 360}));
  EXPECT_EQ(g.IndexOf({-0.03, 0.0})->ix, 399);
  EXPECT_FALSE(g.IndexOf({-20.01, 0.0}).has_value());
  EXPECT_FALSE(g.IndexOf({20.0, 0.0}).has_value());  // max edge is exclusive
  EXPECT_TRUE(g.IndexOf({19.999, 19.999}).has_value());
  EXPECT_FALSE(g.IndexOf({NAN, 0.0}).has_value());
}

TEST(GridGeometryTest, CenterRoundTripsWithYaw) {
  const GridGeometry g = Geometry(0.2, 7, 3, {1.0, 2.0, 0.7});
  for (int ix = 0; ix < 7; ++ix) {
    for (int iy = 0; iy < 3; ++iy) {
      const Vector2 c = g.CenterOf({ix, iy});
      EXPECT_EQ(g.IndexOf(c), (CellIndex{ix, iy}));
    }
  }
  // The first cell's centre is half a cell along the rotated axes from the origin.
  const Vector2 c0 = g.CenterOf({0, 0});
  EXPECT_NEAR(c0.x(), 1.0 + 0.1 * std::cos(0.7) - 0.1 * std::sin(0.7), 1e-12);
  EXPECT_NEAR(c0.y(), 2.0 + 0.1 * std::sin(0.7) + 0.1 * std::cos(0.7), 1e-12);
}

TEST(GridMapTest, ALayerOfCellsIsMovedInWhenItFits) {
  GridMap map(Geometry(0.5, 4, 3, {0.0, 0.0, 0.0}));
  Layer cells(4, 3);
  cells.setConstant(2.f);
  cells(3, 2) = 5.f;
  const float* data = cells.data();
  Layer& added = map.AddLayer("cost/test", std::move(cells));
  EXPECT_EQ(added.data(), data);  // moved, not copied
  EXPECT_EQ(map.at("cost/test")(3, 2), 5.f);
  EXPECT_THROW(map.AddLayer("wrong", Layer(3, 4)), std::invalid_argument);
  EXPECT_FALSE(map.HasLayer("wrong"));
}

TEST(GridMapTest, AsymmetricPatternStorageIsXFastest) {
  // An L-shaped pattern catches transposition and flips: cells (0..3, 0) and (0, 1).
  GridMap map(Geometry(0.5, 4, 3, {10.0, 20.0, 0.0}));
  Layer& layer = map.AddLayer("elevation", 0.f);
  for (int ix = 0; ix < 4; ++ix) layer(ix, 0) = 1.f;
  layer(0, 1) = 2.f;
  // Memory order: x fastest from the minimum corner.
  const float* d = layer.data();
  EXPECT_EQ(d[0], 1.f);
  EXPECT_EQ(d[3], 1.f);
  EXPECT_EQ(d[4], 2.f);  // (0, 1)
  EXPECT_EQ(d[5], 0.f);
  // World lookup: x = 10 + 1.75 is cell ix 3 in row 0; y = 20 + 0.75 is row 1.
  EXPECT_EQ(*map.ValueAt("elevation", {11.75, 20.25}), 1.f);
  EXPECT_EQ(*map.ValueAt("elevation", {10.25, 20.75}), 2.f);
  EXPECT_EQ(*map.ValueAt("elevation", {10.75, 20.75}), 0.f);
  EXPECT_EQ(map.geometry().LinearIndex({0, 1}), 4);
}

TEST(GridMapTest, UnknownIsNanAndMissingLayerThrows) {
  GridMap map(Geometry(1.0, 2, 2));
  map.AddLayer("a");
  EXPECT_FALSE(map.ValueAt("a", {0.5, 0.5}).has_value());
  EXPECT_THROW(map.at("nope"), std::out_of_range);
  EXPECT_TRUE(map.HasLayer("a"));
  EXPECT_EQ(map.layer_names(), std::vector<std::string>{"a"});
}

TEST(GridMapTest, EqualityTreatsNanAsEqual) {
  GridMap a(Geometry(1.0, 3, 2));
  a.AddLayer("x");
  GridMap b = a;
  EXPECT_TRUE(a == b);
  b.at("x")(1, 1) = 3.f;
  EXPECT_FALSE(a == b);
}

TEST(GridGeometryTest, RejectsBadResolution) {
  EXPECT_THROW(GridMap(Geometry(0.0, 2, 2)), std::invalid_argument);
  EXPECT_THROW(GridMap(Geometry(NAN, 2, 2)), std::invalid_argument);
}

}  // namespace
}  // namespace cairn::common
