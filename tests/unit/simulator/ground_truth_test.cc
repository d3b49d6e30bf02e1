#include "simulator/ground_truth.h"

#include <cmath>
#include <stdexcept>

#include <gtest/gtest.h>

#include "tests/unit/simulator/sim_test_util.h"

namespace cairn::sim {
namespace {

// size_x x size_y cells of resolution_m from (x0, y0).
common::GridGeometry Grid(double resolution_m, int size_x, int size_y, double x0, double y0) {
  common::GridGeometry g;
  g.resolution_m = resolution_m;
  g.size_x = size_x;
  g.size_y = size_y;
  g.origin = {x0, y0, 0.0};
  return g;
}

// A 2 x 2 m floor patch at 0.1 m: cell (ix, iy) covers x -1 + 0.1 ix .. , y -1 + 0.1 iy ...
common::GridGeometry Patch() { return Grid(0.1, 20, 20, -1.0, -1.0); }

// A box on the floor (x -0.2..0.2, y -0.3..0.1, 0.5 m high; its bottom is the floor's plane),
// listed before the floor so that mj_ray reports the box's bottom where it ties with the floor;
// a table-like slab at 1.5 m (x 0.5..0.9, y 0.5..0.9) and one at 0.5 m (x -0.9..-0.5,
// y 0.5..0.9); a box whose east edge cuts a cell (x -0.8..-0.56, y -0.8..-0.6, 0.3 m high); a
// box that collides with nothing (not geometry) and a fully transparent one that collides.
std::string InlineWorld() {
  return R"(<mujoco model="truth_test">
  <worldbody>
    <geom name="box" type="box" size="0.2 0.2 0.25" pos="0 -0.1 0.25"/>
    <geom name="floor" type="plane" size="5 5 0.1"/>
    <geom name="high_slab" type="box" size="0.2 0.2 0.02" pos="0.7 0.7 1.5"/>
    <geom name="low_slab" type="box" size="0.2 0.2 0.02" pos="-0.7 0.7 0.5"/>
    <geom name="edge_box" type="box" size="0.12 0.1 0.15" pos="-0.68 -0.7 0.15"/>
    <geom name="ghost" type="box" size="0.1 0.1 0.1" pos="0.7 -0.7 0.3" contype="0" conaffinity="0"/>
    <geom name="glass" type="box" size="0.1 0.1 0.1" pos="0.7 -0.4 0.1" rgba="1 1 1 0"/>
  </worldbody>
</mujoco>)";
}

TEST(TruthRasterParamsTest, ValidateNamesTheField) {
  TruthRasterParams p;
  EXPECT_NO_THROW(p.Validate());
  p.band_high_m = 0.01;
  try {
    p.Validate();
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("band_high_m"), std::string::npos) << e.what();
  }
  p = {};
  p.samples_per_side = 0;
  EXPECT_THROW(p.Validate(), std::invalid_argument);
  p = {};
  p.band_low_m = 0.0;
  EXPECT_THROW(p.Validate(), std::invalid_argument);
  p = {};
  p.threads = 0;
  EXPECT_THROW(p.Validate(), std::invalid_argument);
}

TEST(GroundTruthTest, PeelsABoxStandingOnTheFloor) {
  GroundTruthWorld world = GroundTruthWorld::FromText(InlineWorld(), "/tmp/truth_test.xml", {});
  EXPECT_NEAR(world.ray_start_z_m(), 2.52, 1e-9);  // the high slab's top + 1 m
  const ColumnProfile box = world.Column(0.0, -0.1);
  ASSERT_EQ(box.spans.size(), 2u);
  EXPECT_NEAR(box.spans[0].top_m, 0.5, 1e-9);
  EXPECT_NEAR(box.spans[0].bottom_m, 0.0, 1e-9);
  EXPECT_FALSE(box.spans[0].terrain);
  EXPECT_TRUE(box.spans[1].terrain);
  EXPECT_TRUE(std::isinf(box.spans[1].bottom_m));
  EXPECT_NEAR(box.ground_m, 0.0, 1e-9);
  EXPECT_NEAR(box.top_m, 0.5, 1e-9);
  const ColumnProfile slab = world.Column(0.7, 0.7);
  ASSERT_EQ(slab.spans.size(), 2u);
  EXPECT_NEAR(slab.spans[0].top_m, 1.52, 1e-9);
  EXPECT_NEAR(slab.spans[0].bottom_m, 1.48, 1e-9);
  EXPECT_NEAR(slab.ground_m, 0.0, 1e-9);
  // The non-colliding box is not geometry.
  const ColumnProfile ghost = world.Column(0.7, -0.7);
  ASSERT_EQ(ghost.spans.size(), 1u);
  EXPECT_NEAR(ghost.top_m, 0.0, 1e-9);
  // Outside the floor's size nothing is hit.
  const ColumnProfile outside = world.Column(6.0, 0.0);
  EXPECT_TRUE(outside.spans.empty());
  EXPECT_TRUE(std::isnan(outside.ground_m));
}

TEST(GroundTruthTest, InlineWorldCellsByHand) {
  GroundTruthWorld world = GroundTruthWorld::FromText(InlineWorld(), "/tmp/truth_test.xml", {});
  const common::GridMap truth = world.Rasterise(Patch());
  const common::Layer& occ = truth.at(kTruthOccupiedLayer);
  const common::Layer& ground = truth.at(kTruthGroundLayer);
  const common::Layer& top = truth.at(kTruthTopLayer);
  int occupied = 0;
  for (int iy = 0; iy < 20; ++iy) {
    for (int ix = 0; ix < 20; ++ix) {
      ASSERT_FLOAT_EQ(ground(ix, iy), 0.f) << ix << "," << iy;
      const bool in_box = ix >= 8 && ix < 12 && iy >= 7 && iy < 11;
      const bool in_low_slab = ix >= 1 && ix < 5 && iy >= 15 && iy < 19;
      // The edge box covers x -0.8..-0.56: cells 2, 3 and cell 4 (x -0.6..-0.5) whose first
      // sample column (x -0.5833) falls inside; y -0.8..-0.6: cells 2, 3.
      const bool in_edge_box = ix >= 2 && ix < 5 && iy >= 2 && iy < 4;
      // The fully transparent box (mj_ray does not see it) still collides: x 0.6..0.8,
      // y -0.5..-0.3.
      const bool in_glass = ix >= 16 && ix < 18 && iy >= 5 && iy < 7;
      const bool expected = in_box || in_low_slab || in_edge_box || in_glass;
      EXPECT_EQ(occ(ix, iy), expected ? 1.f : 0.f) << ix << "," << iy;
      occupied += occ(ix, iy) == 1.f;
    }
  }
  EXPECT_EQ(occupied, 16 + 16 + 6 + 4);
  // Tops: the box, the slabs (the high one is not occupied), bare floor.
  EXPECT_FLOAT_EQ(top(9, 8), 0.5f);
  EXPECT_FLOAT_EQ(top(16, 16), 1.52f);
  EXPECT_FLOAT_EQ(occ(16, 16), 0.f);
  EXPECT_FLOAT_EQ(top(2, 16), 0.52f);
  EXPECT_FLOAT_EQ(top(15, 2), 0.f);
  EXPECT_FLOAT_EQ(top(4, 2), 0.3f);  // the edge box's top, seen by part of the cell

  // A band below the low slab: it no longer occupies.
  TruthRasterParams low_band;
  low_band.band_high_m = 0.45;
  const common::GridMap lower =
      GroundTruthWorld::FromText(InlineWorld(), "/tmp/truth_test.xml", low_band).Rasterise(Patch());
  EXPECT_FLOAT_EQ(lower.at(kTruthOccupiedLayer)(2, 16), 0.f);
  EXPECT_FLOAT_EQ(lower.at(kTruthOccupiedLayer)(9, 8), 1.f);
}

TEST(GroundTruthTest, AWideTallBlockIsABuildingAndAWideLowOneIsADeck) {
  // Two 4 x 4 m blocks on a floor: a 3 m tall one (a solid house) and a 0.3 m one (a deck).
  // Both are wider than terrain_min_extent_m; only the low one is terrain, so the house's roof
  // is no ground and its footprint is occupied, while the deck's top is ground.
  const std::string xml = R"(<mujoco model="blocks">
  <worldbody>
    <geom name="floor" type="plane" size="20 20 0.1"/>
    <geom name="house" type="box" size="2 2 1.5" pos="-3 0 1.5"/>
    <geom name="deck" type="box" size="2 2 0.15" pos="3 0 0.15"/>
  </worldbody>
</mujoco>)";
  GroundTruthWorld world = GroundTruthWorld::FromText(xml, "/tmp/truth_blocks.xml", {});
  const ColumnProfile house = world.Column(-3.0, 0.0);
  EXPECT_NEAR(house.ground_m, 0.0, 1e-9);
  EXPECT_NEAR(house.top_m, 3.0, 1e-9);
  const ColumnProfile deck = world.Column(3.0, 0.0);
  EXPECT_NEAR(deck.ground_m, 0.3, 1e-9);
  const common::GridMap truth = world.Rasterise(Grid(0.5, 24, 4, -6.0, -1.0));
  const common::Layer& occ = truth.at(kTruthOccupiedLayer);
  EXPECT_FLOAT_EQ(occ(6, 2), 1.f);   // x -2.75: the house
  EXPECT_FLOAT_EQ(occ(18, 2), 0.f);  // x 3.25: the deck's top
  EXPECT_FLOAT_EQ(occ(0, 2), 0.f);   // x -5.75: the floor
  // A bound above the house makes it terrain again (its roof ground), as before.
  TruthRasterParams tall;
  tall.terrain_max_height_m = 4.0;
  EXPECT_NEAR(
      GroundTruthWorld::FromText(xml, "/tmp/truth_blocks.xml", tall).Column(-3.0, 0.0).ground_m,
      3.0, 1e-9);
  tall.terrain_max_height_m = 0.0;
  EXPECT_THROW(tall.Validate(), std::invalid_argument);
}

TEST(GroundTruthTest, RotatedGridAndThreadsGiveTheSameCells) {
  TruthRasterParams threaded;
  threaded.threads = 2;
  common::GridGeometry g = Patch();
  const common::GridMap one =
      GroundTruthWorld::FromText(InlineWorld(), "/tmp/truth_test.xml", {}).Rasterise(g);
  const common::GridMap two =
      GroundTruthWorld::FromText(InlineWorld(), "/tmp/truth_test.xml", threaded).Rasterise(g);
  EXPECT_TRUE(one == two);
  // A grid turned by 90°: cell (ix, iy) lies at world x = 1 - 0.1 (iy + 0.5), y = -1 + 0.1
  // (ix + 0.5); the box (x -0.2..0.2, y -0.3..0.1) is cells ix 7..10, iy 8..11.
  g.origin = {1.0, -1.0, M_PI / 2};
  const common::GridMap turned =
      GroundTruthWorld::FromText(InlineWorld(), "/tmp/truth_test.xml", {}).Rasterise(g);
  EXPECT_FLOAT_EQ(turned.at(kTruthOccupiedLayer)(7, 8), 1.f);
  EXPECT_FLOAT_EQ(turned.at(kTruthOccupiedLayer)(10, 11), 1.f);
  EXPECT_FLOAT_EQ(turned.at(kTruthOccupiedLayer)(6, 8), 0.f);
  EXPECT_FLOAT_EQ(turned.at(kTruthOccupiedLayer)(7, 12), 0.f);
}

// The arena (simulator/worlds/README.md): 12 x 10 m, walls 1 m high and 0.15 m thick outside
// the area, furniture. Grid: 0.1 m cells from (-0.5, -0.5), 130 x 110.
class ArenaTruthTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    common::GridGeometry g;
    g.resolution_m = 0.1;
    g.size_x = 130;
    g.size_y = 110;
    g.origin = {-0.5, -0.5, 0.0};
    truth_ = new common::GridMap(
        RasteriseGroundTruth(testing::TestPaths().WorldPath("arena"), g, TruthRasterParams{}));
  }
  static void TearDownTestSuite() { delete truth_; }
  // The cell holding world (x, y).
  static float At(const char* layer, double x, double y) {
    const auto cell = truth_->IndexOf({x, y});
    EXPECT_TRUE(cell.has_value());
    return truth_->at(layer)(cell->ix, cell->iy);
  }
  static common::GridMap* truth_;
};
common::GridMap* ArenaTruthTest::truth_ = nullptr;

TEST_F(ArenaTruthTest, GroundIsTheFloorEverywhere) {
  const common::Layer& ground = truth_->at(kTruthGroundLayer);
  for (Eigen::Index i = 0; i < ground.size(); ++i) ASSERT_FLOAT_EQ(ground.data()[i], 0.f) << i;
}

TEST_F(ArenaTruthTest, WallsAndFurnitureByHand) {
  // The start is free floor.
  EXPECT_FLOAT_EQ(At(kTruthOccupiedLayer, 6.05, 3.05), 0.f);
  EXPECT_FLOAT_EQ(At(kTruthTopLayer, 6.05, 3.05), 0.f);
  // The south wall (y -0.15..0) is 1 m high.
  EXPECT_FLOAT_EQ(At(kTruthOccupiedLayer, 6.05, -0.05), 1.f);
  EXPECT_FLOAT_EQ(At(kTruthTopLayer, 6.05, -0.05), 1.f);
  // The armchair's seat (top 0.45) and back (top 0.9).
  EXPECT_FLOAT_EQ(At(kTruthOccupiedLayer, 3.75, 0.75), 1.f);
  EXPECT_FLOAT_EQ(At(kTruthTopLayer, 3.75, 0.75), 0.45f);
  EXPECT_FLOAT_EQ(At(kTruthTopLayer, 3.75, 0.25), 0.9f);
  // A ball on the floor at (1.5, 2.5), the table top (0.72..0.76, inside the 1 m band), the
  // chair's seat; the doorway at x 2.5..3.5 in the y = 6 wall.
  EXPECT_FLOAT_EQ(At(kTruthOccupiedLayer, 1.55, 2.55), 1.f);
  EXPECT_GT(At(kTruthTopLayer, 1.55, 2.55), 0.2f);
  EXPECT_FLOAT_EQ(At(kTruthOccupiedLayer, 9.55, 8.55), 1.f);
  EXPECT_FLOAT_EQ(At(kTruthTopLayer, 9.55, 8.55), 0.76f);
  EXPECT_FLOAT_EQ(At(kTruthOccupiedLayer, 3.05, 8.55), 1.f);
  EXPECT_FLOAT_EQ(At(kTruthOccupiedLayer, 3.05, 6.05), 0.f);
  EXPECT_FLOAT_EQ(At(kTruthOccupiedLayer, 2.05, 6.05), 1.f);

  // The row y 2.0..2.1 crosses only the west wall (cells x -0.2..0), the alcove wall
  // (x 8.0..8.15: two cells) and the east wall (x 12.0..12.15: two cells).
  const common::Layer& occ = truth_->at(kTruthOccupiedLayer);
  std::vector<int> row;
  for (int ix = 0; ix < 130; ++ix) {
    if (occ(ix, 25) == 1.f) row.push_back(ix);
  }
  EXPECT_EQ(row, (std::vector<int>{3, 4, 85, 86, 125, 126}));

  // With a band ending below the table top, only its legs remain. The grid puts each leg's
  // centre on a cell centre; a leg (r 0.03) is met only by that cell's middle sample (the others
  // lie 0.033 m or more away).
  TruthRasterParams low;
  low.band_high_m = 0.7;
  common::GridGeometry g;
  g.resolution_m = 0.1;
  g.size_x = 20;
  g.size_y = 12;
  g.origin = {8.55, 7.95, 0.0};
  const common::GridMap table =
      RasteriseGroundTruth(testing::TestPaths().WorldPath("arena"), g, low);
  const common::Layer& legs = table.at(kTruthOccupiedLayer);
  for (int iy = 0; iy < 12; ++iy) {
    for (int ix = 0; ix < 20; ++ix) {
      const bool leg = (ix == 2 || ix == 16) && (iy == 1 || iy == 9);
      EXPECT_EQ(legs(ix, iy), leg ? 1.f : 0.f) << ix << "," << iy;
    }
  }
}

// The tunnel (simulator/worlds/README.md): decks on a ground plane, ramps sunk into them, a
// trench down to the plane, a 1 m cube (an object) and a 20 cm block 14 m long (terrain).
TEST(GroundTruthTest, TunnelDecksRampsAndTrench) {
  const TruthRasterParams params;
  GroundTruthWorld world =
      GroundTruthWorld::FromFile(testing::TestPaths().WorldPath("tunnel"), TruthRasterParams{});
  const double band_low = params.band_low_m;
  const auto occupied = [&](const ColumnProfile& c) {
    for (const SolidSpan& s : c.spans) {
      if (s.top_m >= c.ground_m + band_low && s.bottom_m <= c.ground_m + 1.0) return true;
    }
    return false;
  };
  const ColumnProfile deck = world.Column(4.0, 2.0);
  EXPECT_NEAR(deck.ground_m, 0.0, 1e-9);
  EXPECT_FALSE(occupied(deck));
  const ColumnProfile trench = world.Column(10.3, 30.0);
  EXPECT_NEAR(trench.ground_m, -0.3, 1e-9);
  const ColumnProfile cube = world.Column(9.5, 2.0);
  EXPECT_NEAR(cube.ground_m, 0.0, 1e-9);
  EXPECT_NEAR(cube.top_m, 1.0, 1e-9);
  EXPECT_TRUE(occupied(cube));
  const ColumnProfile block = world.Column(15.0, 22.0);
  EXPECT_NEAR(block.ground_m, 0.2, 1e-9);
  EXPECT_FALSE(occupied(block));
  // Halfway up the 5 degree ramp (x 8.0..11.429, 0 -> 0.3 m).
  const ColumnProfile ramp = world.Column(9.7145, 6.0);
  EXPECT_NEAR(ramp.ground_m, 0.15, 0.005);
  EXPECT_FALSE(occupied(ramp));
  // The lane wall at y = 4 (1.5 m high above the deck).
  const ColumnProfile wall = world.Column(12.0, 4.0);
  EXPECT_NEAR(wall.top_m, 1.5, 1e-9);
  EXPECT_TRUE(occupied(wall));
}

// The outdoor height field: ground follows the terrain, the shed stands on it.
TEST(GroundTruthTest, OutdoorHeightField) {
  GroundTruthWorld world =
      GroundTruthWorld::FromFile(testing::TestPaths().WorldPath("outdoor"), TruthRasterParams{});
  const ColumnProfile start = world.Column(0.0, 0.0);
  EXPECT_GT(start.ground_m, 0.1);
  EXPECT_LT(start.ground_m, 0.2);
  EXPECT_DOUBLE_EQ(start.top_m, start.ground_m);
  const ColumnProfile shed = world.Column(7.0, 5.0);
  EXPECT_NEAR(shed.top_m, 2.485335, 1e-6);
  EXPECT_GT(shed.ground_m, 0.3);
  EXPECT_LT(shed.ground_m, 1.0);

  const common::GridMap truth = world.Rasterise(Grid(0.5, 40, 40, -10.0, -10.0));
  const auto shed_cell = truth.IndexOf({7.25, 5.25});
  const auto start_cell = truth.IndexOf({0.25, 0.25});
  EXPECT_FLOAT_EQ(truth.at(kTruthOccupiedLayer)(shed_cell->ix, shed_cell->iy), 1.f);
  EXPECT_FLOAT_EQ(truth.at(kTruthOccupiedLayer)(start_cell->ix, start_cell->iy), 0.f);
  // Outside the height field (x > 30) there is no ground.
  const common::GridMap outside = world.Rasterise(Grid(0.5, 2, 2, 31.0, 0.0));
  EXPECT_TRUE(std::isnan(outside.at(kTruthGroundLayer)(0, 0)));
  EXPECT_TRUE(std::isnan(outside.at(kTruthOccupiedLayer)(0, 0)));
}

}  // namespace
}  // namespace cairn::sim
