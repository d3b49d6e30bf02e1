// MapSnapshotPolicy without any transport: layers handed over as the map client would.

#include "planner/map_snapshot_policy.h"

#include <cmath>

#include <gtest/gtest.h>

#include "common/layers.h"

#include "tests/unit/planner/test_maps.h"

namespace cairn::planner {
namespace {

using testing::PioneerFootprint;

// A 60 x 40 layer at 0.05 m in tiles of 20 cells (3 x 2 tiles), all free.
AssembledLayer Layer(int64_t version, float fill = 0.0f) {
  AssembledLayer layer;
  layer.version = version;
  layer.geometry.resolution_m = 0.05;
  layer.geometry.size_x = 60;
  layer.geometry.size_y = 40;
  layer.cells.setConstant(60, 40, fill);
  layer.tile_size_cells = 20;
  return layer;
}

MapSnapshotParams Params(double incomplete_timeout_s = 1.0) {
  MapSnapshotParams p;
  p.incomplete_timeout_s = incomplete_timeout_s;
  return p;
}

// Directed tiles not held read as the cost layer alone: free cells stay free (a missing tile of
// the directed layer once blocked the cells around the robot), lethal cells stay lethal, and the
// one-way cells of the tiles held stay one-way.
TEST(MapSnapshotPolicyTest, MissingDirectedTilesReadAsTheCostLayerAlone) {
  MapSnapshotPolicy dut(Params(), PioneerFootprint());
  AssembledLayer layer = Layer(4);
  layer.cells(25, 5) = 100.0f;  // lethal in the missing directed tile (1, 0)
  layer.cells(5, 5) = 100.0f;   // lethal and one-way in the held tile (0, 0)
  layer.directed = common::Layer::Zero(60, 40);
  (*layer.directed)(5, 5) = 4.0f;
  layer.directed_missing_tiles = {{1, 0}};
  const auto map = dut.Build(std::move(layer), 1'000'000);
  ASSERT_TRUE(map.ok()) << map.status().ToString();
  EXPECT_TRUE((*map)->has_directed());
  EXPECT_FALSE((*map)->IsBlockedCell({30, 10}));
  EXPECT_TRUE((*map)->IsBlockedCell({25, 5}));
  EXPECT_EQ((*map)->OneWayMask({5, 5}), 4);
  EXPECT_FALSE((*map)->IsBlockedCell({5, 5}));
  EXPECT_TRUE((*map)->IsValid({1.5, 0.75, 0.0}));  // a pose inside the missing directed tile
}

// A rim marked as an unseen drop blocks the snapshot the robot drives on; with
// look_at_unseen_drops the snapshot carries a planning twin where it is unknown ground (traversable
// here at unknown_cost), and without any such mark no twin is built.
TEST(MapSnapshotPolicyTest, UnseenDropsAreUnknownToPlansOnlyWhenAllowed) {
  MapSnapshotParams params = Params();
  params.cost.unknown_is_traversable = true;
  params.look_at_unseen_drops = true;
  auto layer_with_rim = [] {
    AssembledLayer layer = Layer(4);
    layer.directed = common::Layer::Zero(60, 40);
    for (int iy = 0; iy < 40; ++iy) {
      layer.cells(30, iy) = 100.0f;
      (*layer.directed)(30, iy) = layers::kUnseenDrop;
    }
    return layer;
  };
  MapSnapshotPolicy dut(params, PioneerFootprint());
  const auto map = dut.Build(layer_with_rim(), 1'000'000);
  ASSERT_TRUE(map.ok()) << map.status().ToString();
  EXPECT_EQ((*map)->unseen_drop_cells(), 40);
  EXPECT_TRUE((*map)->IsBlockedCell({30, 10}));
  ASSERT_NE((*map)->planning_map_shared(), nullptr);
  const CostMap& plan = (*map)->planning_map();
  EXPECT_FALSE(plan.IsBlockedCell({30, 10}));
  EXPECT_TRUE(std::isnan(plan.cost()(30, 10)));
  EXPECT_EQ(plan.version(), (*map)->version());
  // A pose astride the rim: invalid to drive, valid to plan through.
  EXPECT_FALSE((*map)->IsValid({1.525, 1.0, 0.0}));
  EXPECT_TRUE(plan.IsValid({1.525, 1.0, 0.0}));

  params.look_at_unseen_drops = false;
  MapSnapshotPolicy strict(params, PioneerFootprint());
  const auto no_twin = strict.Build(layer_with_rim(), 1'000'000);
  ASSERT_TRUE(no_twin.ok());
  EXPECT_EQ((*no_twin)->planning_map_shared(), nullptr);
  EXPECT_EQ(&(*no_twin)->planning_map(), no_twin->get());
  EXPECT_TRUE((*no_twin)->planning_map().IsBlockedCell({30, 10}));

  params.look_at_unseen_drops = true;
  MapSnapshotPolicy plain(params, PioneerFootprint());
  AssembledLayer layer = Layer(5);
  layer.directed = common::Layer::Zero(60, 40);
  const auto without_marks = plain.Build(std::move(layer), 1'000'000);
  ASSERT_TRUE(without_marks.ok());
  EXPECT_EQ((*without_marks)->planning_map_shared(), nullptr);
}

TEST(MapSnapshotPolicyTest, MissingTilesAreLethalNotUnexplored) {
  MapSnapshotParams params = Params();
  params.cost.unknown_is_traversable = true;  // unexplored cells could be crossed ...
  MapSnapshotPolicy dut(params, PioneerFootprint());
  AssembledLayer layer = Layer(3, NAN);
  layer.missing_tiles = {{1, 0}, {2, 1}};
  const auto map = dut.Build(std::move(layer), 7'000'000);
  ASSERT_TRUE(map.ok()) << map.status().ToString();
  const common::Layer& cost = (*map)->cost();
  // ... a missing tile's cells cannot: they are lethal, every one of them, and nothing else is.
  for (int iy = 0; iy < 40; ++iy) {
    for (int ix = 0; ix < 60; ++ix) {
      const bool in_missing = (ix >= 20 && ix < 40 && iy < 20) || (ix >= 40 && iy >= 20);
      if (in_missing) {
        ASSERT_FLOAT_EQ(cost(ix, iy), 100.0f) << ix << ", " << iy;
      } else {
        ASSERT_TRUE(std::isnan(cost(ix, iy))) << ix << ", " << iy;
      }
    }
  }
  EXPECT_TRUE((*map)->IsBlockedCell({25, 5}));
  EXPECT_FALSE((*map)->IsBlockedCell({5, 5}));
  EXPECT_EQ((*map)->missing_tiles(), 2);
  EXPECT_EQ((*map)->version(), 3);
  EXPECT_EQ((*map)->utime(), 7'000'000);
  EXPECT_EQ(dut.built_version(), 3);
  EXPECT_TRUE(dut.built_incomplete());
}

TEST(MapSnapshotPolicyTest, TilesAreClippedToTheLayerAndTheLethalCostIsTheParams) {
  MapSnapshotParams params = Params();
  params.cost.lethal_cost = 90.0f;
  MapSnapshotPolicy dut(params, PioneerFootprint());
  AssembledLayer layer = Layer(1);
  layer.tile_size_cells = 25;  // the last column and row of tiles hang over the layer's edge
  layer.missing_tiles = {{2, 1}, {7, 7}};
  const auto map = dut.Build(std::move(layer), 1);
  ASSERT_TRUE(map.ok());
  EXPECT_FLOAT_EQ((*map)->cost()(59, 39), 90.0f);
  EXPECT_FLOAT_EQ((*map)->cost()(50, 25), 90.0f);
  EXPECT_FLOAT_EQ((*map)->cost()(49, 39), 0.0f);
  EXPECT_FLOAT_EQ((*map)->cost()(59, 24), 0.0f);
}

TEST(MapSnapshotPolicyTest, OccupancyIsConvertedToCost) {
  MapSnapshotParams params = Params();
  params.encoding = MapEncoding::kOccupancy;
  params.occupancy.occupied_threshold_og = 20.0f;
  params.occupancy.free_threshold_og = 5.0f;
  MapSnapshotPolicy dut(params, PioneerFootprint());
  AssembledLayer layer = Layer(1);
  layer.cells(0, 0) = 100.0f;
  layer.cells(1, 0) = 12.0f;
  layer.cells(2, 0) = NAN;
  const auto map = dut.Build(std::move(layer), 1);
  ASSERT_TRUE(map.ok());
  EXPECT_FLOAT_EQ((*map)->cost()(0, 0), 100.0f);
  EXPECT_FLOAT_EQ((*map)->cost()(1, 0), 100.0f * (12.0f - 5.0f) / (20.0f - 5.0f));
  EXPECT_TRUE(std::isnan((*map)->cost()(2, 0)));
  EXPECT_FLOAT_EQ((*map)->cost()(3, 0), 0.0f);
}

TEST(MapSnapshotPolicyTest, AnIncompleteVersionWaitsThenIsTakenThenRebuiltOnce) {
  MapSnapshotPolicy dut(Params(1.0), PioneerFootprint());
  EXPECT_EQ(dut.OnLayerChanged(0, false, 100), SnapshotAction::kWait);  // nothing announced
  // Version 1 is announced at t = 1 s with a tile missing: wait, ask for it.
  EXPECT_EQ(dut.OnLayerChanged(1, false, 1'000'000), SnapshotAction::kWait);
  EXPECT_TRUE(dut.WantsMissingTiles(1, false));
  EXPECT_EQ(dut.OnPoll(1, false, 1'900'000), SnapshotAction::kWait);
  // After the timeout (from when it was first seen) it is taken with its hole.
  EXPECT_EQ(dut.OnPoll(1, false, 2'000'000), SnapshotAction::kBuildIncomplete);
  AssembledLayer holed = Layer(1);
  holed.missing_tiles = {{0, 0}};
  ASSERT_TRUE(dut.Build(std::move(holed), 2'000'000).ok());
  // Never built again with the same hole, but still asked for.
  EXPECT_EQ(dut.OnPoll(1, false, 9'000'000), SnapshotAction::kWait);
  EXPECT_EQ(dut.OnLayerChanged(1, false, 9'000'000), SnapshotAction::kWait);
  EXPECT_TRUE(dut.WantsMissingTiles(1, false));
  // The tile comes: built again, complete, by the handler or by the next poll.
  EXPECT_EQ(dut.OnPoll(1, true, 9'100'000), SnapshotAction::kBuild);
  EXPECT_EQ(dut.OnLayerChanged(1, true, 9'100'000), SnapshotAction::kBuild);
  ASSERT_TRUE(dut.Build(Layer(1), 9'100'000).ok());
  EXPECT_FALSE(dut.built_incomplete());
  // Then nothing more for that version.
  EXPECT_EQ(dut.OnLayerChanged(1, true, 9'200'000), SnapshotAction::kWait);
  EXPECT_EQ(dut.OnPoll(1, true, 9'200'000), SnapshotAction::kWait);
  EXPECT_FALSE(dut.WantsMissingTiles(1, true));
  // A new complete version is taken at once, without a wait.
  EXPECT_EQ(dut.OnLayerChanged(2, true, 9'300'000), SnapshotAction::kBuild);
}

TEST(MapSnapshotPolicyTest, TheTimeoutRunsFromTheFirstSightOfAVersion) {
  MapSnapshotPolicy dut(Params(0.5), PioneerFootprint());
  ASSERT_TRUE(dut.Build(Layer(1), 0).ok());
  EXPECT_EQ(dut.OnLayerChanged(2, false, 1'000'000), SnapshotAction::kWait);
  EXPECT_EQ(dut.OnLayerChanged(2, false, 1'400'000), SnapshotAction::kWait);  // later tiles
  EXPECT_EQ(dut.OnPoll(2, false, 1'499'999), SnapshotAction::kWait);
  EXPECT_EQ(dut.OnPoll(2, false, 1'500'000), SnapshotAction::kBuildIncomplete);
  // With no timeout an incomplete version is taken at the first poll.
  MapSnapshotPolicy eager(Params(0.0), PioneerFootprint());
  EXPECT_EQ(eager.OnLayerChanged(1, false, 5), SnapshotAction::kWait);
  EXPECT_EQ(eager.OnPoll(1, false, 5), SnapshotAction::kBuildIncomplete);
}

TEST(MapSnapshotPolicyTest, ARefusedLayerIsReportedAndNotTriedAgain) {
  MapSnapshotPolicy dut(Params(), PioneerFootprint());
  AssembledLayer bad = Layer(4);
  bad.cells.setConstant(3, 3, 0.0f);  // not the geometry's size
  const auto map = dut.Build(std::move(bad), 1);
  ASSERT_FALSE(map.ok());
  EXPECT_EQ(map.status().code(), common::StatusCode::kInvalidArgument);
  EXPECT_EQ(dut.built_version(), 4);
  EXPECT_EQ(dut.OnLayerChanged(4, true, 2), SnapshotAction::kWait);
  EXPECT_EQ(dut.OnPoll(4, true, 2), SnapshotAction::kWait);
}

TEST(MapSnapshotPolicyTest, RefusesBadParams) {
  MapSnapshotParams p = Params(-1.0);
  EXPECT_THROW(MapSnapshotPolicy(p, PioneerFootprint()), std::invalid_argument);
  p = Params();
  p.encoding = MapEncoding::kOccupancy;
  p.occupancy.free_threshold_og = 80.0f;
  EXPECT_THROW(MapSnapshotPolicy(p, PioneerFootprint()), std::invalid_argument);
  EXPECT_THROW(MapSnapshotPolicy(Params(), {{0.0, 0.0}}), std::invalid_argument);
}

}  // namespace
}  // namespace cairn::planner
