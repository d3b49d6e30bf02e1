// LcmMapClient on occupancy tiles (the dynamic map server's final layer) over memq://, driven
// through its handlers and a real LayerTiler.

#include "planner/lcm/lcm_map_client.h"

#include <cmath>

#include <gtest/gtest.h>

#include "cairn/lcmt_tile_resend_request.hpp"

#include "common/channels.h"
#include "common/layers.h"
#include "services/runtime/tiler.h"
#include "tests/support/memq_node.h"
#include "tests/unit/planner/test_maps.h"

namespace cairn::planner {
namespace {

runtime::NodeOptions Options() { return cairn::testing::MemqNodeOptions("cairn-navigator", "r1"); }

LcmMapClientParams OccupancyParams() {
  LcmMapClientParams p;
  p.robot = "r1";
  p.layer = layers::kFinal;
  p.snapshot.encoding = MapEncoding::kOccupancy;
  p.snapshot.occupancy.occupied_threshold_og = 20.f;
  p.snapshot.occupancy.free_threshold_og = 5.f;
  p.snapshot.incomplete_timeout_s = 0.0;
  return p;
}

// A 60 x 40 final layer at 0.05 m (tiles of 20 cells): free, a wall (100), an object seen a
// few times (OG 12: graded), one seen long enough (OG 40: lethal), and unknown cells.
common::GridMap FinalLayer() {
  common::GridGeometry g;
  g.resolution_m = 0.05;
  g.size_x = 60;
  g.size_y = 40;
  g.origin = {-1.0, -1.0, 0.0};
  common::GridMap map(g);
  common::Layer& og = map.AddLayer(layers::kFinal, 0.f);
  for (int iy = 0; iy < 40; ++iy) og(0, iy) = 100.f;
  og(30, 20) = 12.f;
  og(31, 20) = 40.f;
  og(45, 5) = NAN;
  for (int iy = 0; iy < 20; ++iy) {
    for (int ix = 40; ix < 60; ++ix) og(ix, iy + 20) = NAN;  // a whole unknown tile
  }
  return map;
}

class LcmMapClientTest : public ::testing::Test {
 protected:
  LcmMapClientTest() : node_(Options()), tiler_("r1", "live", 20) {}

  std::unique_ptr<LcmMapClient> Client(LcmMapClientParams params) {
    return std::make_unique<LcmMapClient>(node_, std::move(params),
                                          testing::PioneerProfile().footprint_m);
  }
  runtime::LayerTiler::Batch Tiles(const common::GridMap& map) {
    return tiler_.Update(map, layers::kFinal, runtime::TileEncoding::kOccupancy, ++utime_);
  }

  runtime::Node node_;
  runtime::LayerTiler tiler_;
  int64_t utime_{1'000'000};
};

TEST_F(LcmMapClientTest, BuildsACostMapFromOccupancyTiles) {
  auto dut = Client(OccupancyParams());
  const auto batch = Tiles(FinalLayer());
  ASSERT_FALSE(batch.occupancy_tiles.empty());
  for (const auto& t : batch.occupancy_tiles) dut->OnTile(t);
  EXPECT_EQ(dut->Latest(), nullptr);  // no manifest yet: completeness unknown
  dut->OnManifest(batch.manifest);
  const auto map = dut->Latest();
  ASSERT_NE(map, nullptr);
  EXPECT_EQ(map->version(), batch.manifest.layer_version);
  const common::Layer& cost = map->cost();
  EXPECT_FLOAT_EQ(cost(0, 3), 100.f);    // wall
  EXPECT_FLOAT_EQ(cost(10, 10), 0.f);    // free
  EXPECT_FLOAT_EQ(cost(31, 20), 100.f);  // at or above the occupied threshold
  EXPECT_FLOAT_EQ(cost(30, 20), 100.f * (12.f - 5.f) / (20.f - 5.f));  // graded
  EXPECT_TRUE(std::isnan(cost(45, 5)));                                // -1 stays unknown
  EXPECT_TRUE(std::isnan(cost(50, 30)));  // an absent (all unknown) tile too
  EXPECT_TRUE(map->IsBlockedCell({31, 20}));
  EXPECT_FALSE(map->IsBlockedCell({30, 20}));
  EXPECT_GT(node_.NowUtime(), 0);
  EXPECT_GT(dut->last_heard_utime(), 0);
}

TEST_F(LcmMapClientTest, IgnoresOtherLayersAndTheOtherEncoding) {
  auto dut = Client(OccupancyParams());
  common::GridMap map = FinalLayer();
  // The same layer name as float tiles (a cost-layer client's input) is not read.
  auto floats = tiler_.Update(map, layers::kFinal, runtime::TileEncoding::kFloat, ++utime_);
  for (const auto& t : floats.tiles) dut->OnTile(t);
  // Another occupancy layer (short_term) with its manifest is not read either.
  common::GridMap other = map;
  other.AddLayer(layers::kShortTerm, 100.f);
  auto short_term =
      tiler_.Update(other, layers::kShortTerm, runtime::TileEncoding::kOccupancy, ++utime_);
  for (const auto& t : short_term.occupancy_tiles) dut->OnTile(t);
  dut->OnManifest(short_term.manifest);
  EXPECT_EQ(dut->Latest(), nullptr);
  EXPECT_EQ(dut->last_heard_utime(), 0);
}

TEST_F(LcmMapClientTest, MissingTilesAreLethalAndAskedFor) {
  auto dut = Client(OccupancyParams());
  std::vector<cairn::lcmt_tile_resend_request> resends;
  node_.Subscribe<cairn::lcmt_tile_resend_request>(
      channels::ForRobot("r1", channels::kMapTileResend),
      [&](const cairn::lcmt_tile_resend_request& r) { resends.push_back(r); });
  const auto batch = Tiles(FinalLayer());
  ASSERT_GT(batch.occupancy_tiles.size(), 2u);
  // Tile (1, 0) (cells 20..39 x 0..19) never arrives.
  for (const auto& t : batch.occupancy_tiles) {
    if (!(t.tile_ix == 1 && t.tile_iy == 0)) dut->OnTile(t);
  }
  dut->OnManifest(batch.manifest);
  EXPECT_EQ(dut->Latest(), nullptr);
  dut->Poll();  // asks again, and (timeout 0) builds with the missing tile blocked
  while (node_.lcm().handleTimeout(0) > 0) {
  }
  ASSERT_EQ(resends.size(), 1u);
  EXPECT_EQ(resends[0].layer, layers::kFinal);
  ASSERT_EQ(resends[0].num_tiles, 1);
  EXPECT_EQ(resends[0].tile_ix[0], 1);
  const auto map = dut->Latest();
  ASSERT_NE(map, nullptr);
  EXPECT_FLOAT_EQ(map->cost()(25, 5), 100.f);
  EXPECT_FLOAT_EQ(map->cost()(10, 5), 0.f);
  EXPECT_EQ(map->missing_tiles(), 1);
  // Polling again neither rebuilds the same holes nor forgets to ask for them.
  dut->Poll();
  EXPECT_EQ(dut->Latest(), map);
  // The resent tile of the same version completes it: rebuilt without holes.
  for (const auto& t : batch.occupancy_tiles) {
    if (t.tile_ix == 1 && t.tile_iy == 0) dut->OnTile(t);
  }
  const auto complete = dut->Latest();
  ASSERT_NE(complete, nullptr);
  EXPECT_NE(complete, map);
  EXPECT_EQ(complete->version(), map->version());
  EXPECT_EQ(complete->missing_tiles(), 0);
  EXPECT_FLOAT_EQ(complete->cost()(25, 5), 0.f);
}

// A cost layer and its directed companion for the Pioneer, 60 x 40 cells at 0.05 m (tiles of
// 20): a column of one-way cells (mask 1: not towards +x; cost lethal) at ix = 30.
common::GridMap CostAndDirected() {
  common::GridGeometry g;
  g.resolution_m = 0.05;
  g.size_x = 60;
  g.size_y = 40;
  common::GridMap map(g);
  common::Layer& cost = map.AddLayer(layers::CostLayer("pioneer3at"), 0.f);
  common::Layer& directed = map.AddLayer(layers::DirectedLayer("pioneer3at"), 0.f);
  for (int iy = 0; iy < 40; ++iy) {
    cost(30, iy) = 100.f;
    directed(30, iy) = 1.f;
  }
  return map;
}

LcmMapClientParams DirectedParams() {
  LcmMapClientParams p;
  p.robot = "r1";
  p.layer = layers::CostLayer("pioneer3at");
  p.directed_layer = layers::DirectedLayer("pioneer3at");
  p.snapshot.incomplete_timeout_s = 0.0;
  return p;
}

TEST_F(LcmMapClientTest, ReadsTheDirectedLayerBesideTheCostLayer) {
  auto dut = Client(DirectedParams());
  const common::GridMap map = CostAndDirected();
  const auto cost =
      tiler_.Update(map, layers::CostLayer("pioneer3at"), runtime::TileEncoding::kFloat, ++utime_);
  for (const auto& t : cost.tiles) dut->OnTile(t);
  dut->OnManifest(cost.manifest);
  // No directed tiles yet (an older mapper): the cost layer alone.
  const auto plain = dut->Latest();
  ASSERT_NE(plain, nullptr);
  EXPECT_FALSE(plain->has_directed());
  EXPECT_FLOAT_EQ(plain->cost()(30, 5), 100.f);
  // The directed layer comes: the same cost version again, with its one-way cells.
  const auto directed = tiler_.Update(map, layers::DirectedLayer("pioneer3at"),
                                      runtime::TileEncoding::kFloat, ++utime_);
  for (const auto& t : directed.tiles) dut->OnTile(t);
  EXPECT_EQ(dut->Latest(), plain) << "waits for the directed manifest";
  dut->OnManifest(directed.manifest);
  const auto both = dut->Latest();
  ASSERT_NE(both, plain);
  EXPECT_EQ(both->version(), plain->version());
  EXPECT_TRUE(both->has_directed());
  EXPECT_EQ(both->one_way_cells(), 40);
  EXPECT_LT(both->cost()(30, 5), 100.f);
  EXPECT_FALSE(both->MotionAllowed({1.45, 0.5, 0.0}, {1.6, 0.5, 0.0}));
  EXPECT_TRUE(both->MotionAllowed({1.6, 0.5, M_PI}, {1.45, 0.5, M_PI}));
  // Re-announcing the same versions builds nothing new.
  dut->OnManifest(directed.manifest);
  dut->OnManifest(cost.manifest);
  dut->Poll();
  EXPECT_EQ(dut->Latest(), both);
}

TEST_F(LcmMapClientTest, ACostVersionWaitsForTheDirectedTilesBesideIt) {
  auto dut = Client(DirectedParams());
  std::vector<cairn::lcmt_tile_resend_request> resends;
  node_.Subscribe<cairn::lcmt_tile_resend_request>(
      channels::ForRobot("r1", channels::kMapTileResend),
      [&](const cairn::lcmt_tile_resend_request& r) { resends.push_back(r); });
  // A first pair, whole: in use.
  const common::GridMap first = CostAndDirected();
  const auto cost0 = tiler_.Update(first, layers::CostLayer("pioneer3at"),
                                   runtime::TileEncoding::kFloat, ++utime_);
  const auto directed0 = tiler_.Update(first, layers::DirectedLayer("pioneer3at"),
                                       runtime::TileEncoding::kFloat, ++utime_);
  for (const auto& t : directed0.tiles) dut->OnTile(t);
  dut->OnManifest(directed0.manifest);
  for (const auto& t : cost0.tiles) dut->OnTile(t);
  dut->OnManifest(cost0.manifest);
  const auto in_use = dut->Latest();
  ASSERT_NE(in_use, nullptr);
  ASSERT_EQ(in_use->one_way_cells(), 40);
  // The next pair (the one-way column moved to ix = 35) loses directed tile (1, 0) (cells
  // 20..39) on the way, as a burst of tiles can on a busy bus.
  common::GridMap map = first;
  for (int iy = 0; iy < 40; ++iy) {
    map.at(layers::CostLayer("pioneer3at"))(30, iy) = 0.f;
    map.at(layers::DirectedLayer("pioneer3at"))(30, iy) = 0.f;
    map.at(layers::CostLayer("pioneer3at"))(35, iy) = 100.f;
    map.at(layers::DirectedLayer("pioneer3at"))(35, iy) = 1.f;
  }
  const auto cost =
      tiler_.Update(map, layers::CostLayer("pioneer3at"), runtime::TileEncoding::kFloat, ++utime_);
  const auto directed = tiler_.Update(map, layers::DirectedLayer("pioneer3at"),
                                      runtime::TileEncoding::kFloat, ++utime_);
  for (const auto& t : directed.tiles) {
    if (!(t.tile_ix == 1 && t.tile_iy == 0)) dut->OnTile(t);
  }
  dut->OnManifest(directed.manifest);
  for (const auto& t : cost.tiles) dut->OnTile(t);
  dut->OnManifest(cost.manifest);
  // Its one-way cells would read as lethal walls without their directed tile: the pair in use
  // stays until the tile comes, and the tile is asked for.
  EXPECT_EQ(dut->Latest(), in_use) << "the new cost version waits for its directed tiles";
  dut->Poll();
  while (node_.lcm().handleTimeout(0) > 0) {
  }
  ASSERT_GE(resends.size(), 1u);
  EXPECT_EQ(resends.back().layer, layers::DirectedLayer("pioneer3at"));
  // The resent tile completes the pair: built with it.
  for (const auto& t : directed.tiles) {
    if (t.tile_ix == 1 && t.tile_iy == 0) dut->OnTile(t);
  }
  const auto whole = dut->Latest();
  ASSERT_NE(whole, in_use);
  EXPECT_EQ(whole->one_way_cells(), 40);
  EXPECT_LT(whole->cost()(35, 5), 100.f) << "one-way, not a wall";
  EXPECT_FLOAT_EQ(whole->cost()(30, 5), 0.f);
}

TEST_F(LcmMapClientTest, MissingDirectedTilesBlockEveryHeadingOnceTheWaitIsOver) {
  auto dut = Client(DirectedParams());  // incomplete_timeout_s 0: the wait ends at the next poll
  const common::GridMap map = CostAndDirected();
  const auto cost =
      tiler_.Update(map, layers::CostLayer("pioneer3at"), runtime::TileEncoding::kFloat, ++utime_);
  const auto directed = tiler_.Update(map, layers::DirectedLayer("pioneer3at"),
                                      runtime::TileEncoding::kFloat, ++utime_);
  for (const auto& t : directed.tiles) {
    if (!(t.tile_ix == 1 && t.tile_iy == 0)) dut->OnTile(t);  // tile (1, 0): cells 20..39
  }
  dut->OnManifest(directed.manifest);
  for (const auto& t : cost.tiles) dut->OnTile(t);
  dut->OnManifest(cost.manifest);
  EXPECT_EQ(dut->Latest(), nullptr) << "waits for the directed tile";
  dut->Poll();
  const auto holes = dut->Latest();
  ASSERT_NE(holes, nullptr);
  ASSERT_TRUE(holes->has_directed());
  EXPECT_EQ(holes->missing_tiles(), 0) << "the cost layer is whole";
  EXPECT_FLOAT_EQ(holes->cost()(30, 5), 100.f) << "a missing directed tile blocks";
  EXPECT_LT(holes->cost()(30, 25), 100.f);
  // The resent tile completes the directed layer: rebuilt with it.
  for (const auto& t : directed.tiles) {
    if (t.tile_ix == 1 && t.tile_iy == 0) dut->OnTile(t);
  }
  const auto whole = dut->Latest();
  ASSERT_NE(whole, holes);
  EXPECT_LT(whole->cost()(30, 5), 100.f);
  // A client not asked for the directed layer ignores it.
  LcmMapClientParams params = DirectedParams();
  params.directed_layer.clear();
  auto plain = Client(params);
  for (const auto& t : directed.tiles) plain->OnTile(t);
  plain->OnManifest(directed.manifest);
  for (const auto& t : cost.tiles) plain->OnTile(t);
  plain->OnManifest(cost.manifest);
  ASSERT_NE(plain->Latest(), nullptr);
  EXPECT_FALSE(plain->Latest()->has_directed());
}

TEST_F(LcmMapClientTest, RefusesBadThresholds) {
  LcmMapClientParams p = OccupancyParams();
  p.snapshot.occupancy.free_threshold_og = 50.f;
  EXPECT_THROW(Client(p), std::invalid_argument);
}

}  // namespace
}  // namespace cairn::planner
