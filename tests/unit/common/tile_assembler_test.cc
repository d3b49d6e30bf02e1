#include "common/tile_assembler.h"

#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include <gtest/gtest.h>

#include "tests/unit/mapstore/core_tiles.h"
#include "tests/unit/mapstore/fake_deriver.h"

namespace cairn::mapstore {
namespace {

using testing::CutLayer;
using testing::SameLayer;

class TileAssemblerTest : public ::testing::Test {
 protected:
  TileAssemblerTest()
      : map_(testing::SampleSnapshot("m", 37, 23).base),
        cut_(CutLayer(map_, layers::kElevation, 10, "7/m")) {}

  common::GridMap map_;
  testing::TiledLayer cut_;
  TileAssembler dut_;
};

TEST_F(TileAssemblerTest, RebuildsALayerExactlyFromItsTilesAndManifest) {
  dut_.OnManifest(cut_.manifest);
  EXPECT_FALSE(dut_.Complete(layers::kElevation));
  for (const auto& t : cut_.tiles) EXPECT_TRUE(dut_.OnTile(t.As()));
  EXPECT_TRUE(dut_.Complete(layers::kElevation));
  EXPECT_EQ(dut_.version(layers::kElevation), 1);
  EXPECT_EQ(dut_.Geometry(layers::kElevation), map_.geometry());
  auto copy = dut_.Layer(layers::kElevation);
  ASSERT_TRUE(copy.has_value());
  EXPECT_TRUE(SameLayer(copy->at(layers::kElevation), map_.at(layers::kElevation)));
  auto taken = dut_.TakeLayer(layers::kElevation);
  ASSERT_TRUE(taken.has_value());
  EXPECT_TRUE(SameLayer(taken->at(layers::kElevation), map_.at(layers::kElevation)));
  EXPECT_FALSE(dut_.Geometry(layers::kElevation).has_value());  // taken: forgotten
}

TEST_F(TileAssemblerTest, NamesTheMissingTilesAndLeavesTheirCellsUnknown) {
  dut_.OnManifest(cut_.manifest);
  for (size_t i = 1; i < cut_.tiles.size(); ++i) dut_.OnTile(cut_.tiles[i].As());
  const auto& first = cut_.tiles.front().header;
  const auto missing = dut_.Missing(layers::kElevation);
  ASSERT_EQ(missing.size(), 1u);
  EXPECT_EQ(missing[0], std::make_pair(first.tile_ix, first.tile_iy));
  auto request = dut_.MissingRequest(layers::kElevation);
  ASSERT_TRUE(request.has_value());
  EXPECT_EQ(request->map_name, "7/m");
  EXPECT_EQ(request->robot, "rover1");
  EXPECT_EQ(request->layer_version, 1);
  EXPECT_EQ(request->tiles, missing);
  auto layer = dut_.Layer(layers::kElevation);
  const int x0 = first.tile_ix * 10, y0 = first.tile_iy * 10;
  EXPECT_TRUE(std::isnan(layer->at(layers::kElevation)(x0 + 5, y0 + 5)));
  EXPECT_FALSE(dut_.HeldChecksum(layers::kElevation, first.tile_ix, first.tile_iy).has_value());
  EXPECT_EQ(dut_.HeldChecksum(layers::kElevation, cut_.tiles[1].header.tile_ix,
                              cut_.tiles[1].header.tile_iy),
            cut_.tiles[1].header.checksum);
}

TEST_F(TileAssemblerTest, AnOlderTileIsIgnoredAndATileOfTheWrongSizeRefused) {
  testing::OwnedTile newer = cut_.tiles[0];
  newer.header.tile_version = 5;
  for (float& c : newer.cells) c = 9.f;
  EXPECT_TRUE(dut_.OnTile(newer.As()));
  EXPECT_TRUE(dut_.OnTile(cut_.tiles[0].As()));  // version 1 < 5: ignored, not refused
  EXPECT_EQ(dut_.Layer(layers::kElevation)->at(layers::kElevation)(1, 1), 9.f);

  testing::OwnedTile bad = cut_.tiles[1];
  bad.cells.pop_back();
  EXPECT_FALSE(dut_.OnTile(bad.As()));
  bad = cut_.tiles[1];
  bad.header.geometry.resolution_m = 0.0;
  EXPECT_FALSE(dut_.OnTile(bad.As()));
  EXPECT_EQ(dut_.refused_tiles(), 2);
}

TEST_F(TileAssemblerTest, ANewerManifestDropsTilesItNoLongerListsAndAnOlderOneIsIgnored) {
  dut_.OnManifest(cut_.manifest);
  for (const auto& t : cut_.tiles) dut_.OnTile(t.As());
  TileManifest smaller = cut_.manifest;
  smaller.layer_version = 2;
  smaller.tiles.pop_back();
  dut_.OnManifest(smaller);
  EXPECT_TRUE(dut_.Complete(layers::kElevation));
  const auto& last = cut_.tiles.back().header;
  EXPECT_FALSE(dut_.HeldChecksum(layers::kElevation, last.tile_ix, last.tile_iy).has_value());
  dut_.OnManifest(cut_.manifest);  // version 1 < 2: ignored
  EXPECT_EQ(dut_.version(layers::kElevation), 2);
  EXPECT_TRUE(dut_.Complete(layers::kElevation));
}

// Issue 20: a manifest's grid was never capped (the cell cap applied to tiles only), and any
// manifest of another grid restarted its layer, erasing what was held. A manifest no sender
// could have made is refused, counted, and changes nothing.
TEST_F(TileAssemblerTest, AManifestNoSenderCouldHaveMadeIsRefusedAndChangesNothing) {
  ASSERT_TRUE(dut_.OnManifest(cut_.manifest));
  for (const auto& t : cut_.tiles) ASSERT_TRUE(dut_.OnTile(t.As()));
  ASSERT_TRUE(dut_.Complete(layers::kElevation));
  std::vector<TileManifest> bad;
  TileManifest m = cut_.manifest;
  m.layer_version = 5;
  m.geometry.size_x = 100000;  // 10^10 cells
  m.geometry.size_y = 100000;
  bad.push_back(m);
  m = cut_.manifest;
  m.layer_version = 5;
  m.geometry.resolution_m = std::nan("");
  bad.push_back(m);
  m = cut_.manifest;
  m.layer_version = 5;
  m.tile_size = 0;
  bad.push_back(m);
  m = cut_.manifest;
  m.layer_version = 5;
  m.tile_size = 100000;
  bad.push_back(m);
  m = cut_.manifest;
  m.layer_version = -1;
  bad.push_back(m);
  m = cut_.manifest;
  m.layer_version = 5;
  m.tiles.push_back(m.tiles.front());  // listed twice
  bad.push_back(m);
  m = cut_.manifest;
  m.layer_version = 5;
  m.tiles.back().tile_ix = 4;  // 37 cells in tiles of 10: ix 0..3
  bad.push_back(m);
  for (const TileManifest& b : bad) EXPECT_FALSE(dut_.OnManifest(b));
  EXPECT_EQ(dut_.refused_manifests(), static_cast<int64_t>(bad.size()));
  EXPECT_EQ(dut_.version(layers::kElevation), 1);
  EXPECT_TRUE(dut_.Complete(layers::kElevation));
  auto copy = dut_.Layer(layers::kElevation);
  ASSERT_TRUE(copy.has_value());
  EXPECT_TRUE(SameLayer(copy->at(layers::kElevation), map_.at(layers::kElevation)));
}

TEST_F(TileAssemblerTest, ATileOfAnotherGridRestartsItsLayer) {
  dut_.OnManifest(cut_.manifest);
  for (const auto& t : cut_.tiles) dut_.OnTile(t.As());
  common::GridMap other = testing::SampleSnapshot("m", 20, 20).base;
  const auto moved = CutLayer(other, layers::kElevation, 10, "7/m");
  EXPECT_TRUE(dut_.OnTile(moved.tiles[0].As()));
  EXPECT_EQ(dut_.Geometry(layers::kElevation), other.geometry());
  EXPECT_FALSE(dut_.Complete(layers::kElevation));  // no manifest of the new grid yet
  EXPECT_EQ(dut_.layers(), std::vector<std::string>{layers::kElevation});
}

TEST_F(TileAssemblerTest, TilesWrittenInPlaceAreHeldAndFailedOnesStayUnknown) {
  dut_.OnManifest(cut_.manifest);
  for (const auto& t : cut_.tiles) {
    auto slot = dut_.BeginTile(t.header);
    ASSERT_TRUE(slot.has_value());
    ASSERT_NE(slot->first, nullptr);
    for (int y = 0; y < slot->cells_y; ++y) {
      for (int x = 0; x < slot->cells_x; ++x) {
        slot->first[y * slot->row_stride + x] =
            t.cells[static_cast<size_t>(y) * t.header.cells_x + x];
      }
    }
    dut_.EndTile(t.header, /*decoded=*/&t != &cut_.tiles.front());
  }
  const auto& first = cut_.tiles.front().header;
  EXPECT_EQ(dut_.Missing(layers::kElevation),
            (std::vector<std::pair<int, int>>{{first.tile_ix, first.tile_iy}}));
  auto layer = dut_.Layer(layers::kElevation);
  ASSERT_TRUE(layer.has_value());
  EXPECT_TRUE(std::isnan(layer->at(layers::kElevation)(first.tile_ix * 10, first.tile_iy * 10)));
  // The failed tile comes again, whole: the layer is the map's.
  dut_.OnTile(cut_.tiles.front().As());
  EXPECT_TRUE(dut_.Complete(layers::kElevation));
  EXPECT_TRUE(SameLayer(dut_.Layer(layers::kElevation)->at(layers::kElevation),
                        map_.at(layers::kElevation)));
  // A header that fits no grid is refused and counted.
  TileHeader bad = first;
  bad.cells_x = bad.tile_size + 1;
  EXPECT_FALSE(dut_.BeginTile(bad).has_value());
  EXPECT_EQ(dut_.refused_tiles(), 1);
}

// Issue 20: a manifest with no tiles numbered INT64_MAX erased the layer and froze it at all
// unknown (every later manifest was "older"); a tile numbered so stuck at its place. Versions
// beyond the receiver's clock plus the lead are refused, and change nothing.
TEST_F(TileAssemblerTest, AVersionBeyondTheClockIsRefusedAndChangesNothing) {
  const int64_t now_ms = 1'800'000'000'000;
  TileAssembler dut([&] { return now_ms; });
  ASSERT_TRUE(dut.OnManifest(cut_.manifest));
  for (const auto& t : cut_.tiles) ASSERT_TRUE(dut.OnTile(t.As()));
  ASSERT_TRUE(dut.Complete(layers::kElevation));

  for (int64_t version : {std::numeric_limits<int64_t>::max(),
                          now_ms + TileAssembler::kVersionLeadMs + 1}) {
    TileManifest erase = cut_.manifest;
    erase.layer_version = version;
    erase.tiles.clear();
    EXPECT_FALSE(dut.OnManifest(erase)) << version;
    TileManifest sticky = cut_.manifest;
    sticky.layer_version = 2;
    sticky.tiles.front().tile_version = version;
    EXPECT_FALSE(dut.OnManifest(sticky)) << version;
    testing::OwnedTile tile = cut_.tiles.front();
    tile.header.tile_version = version;
    for (float& c : tile.cells) c = 9.f;
    EXPECT_FALSE(dut.OnTile(tile.As())) << version;
    EXPECT_FALSE(dut.BeginTile(tile.header).has_value()) << version;
  }
  EXPECT_EQ(dut.refused_manifests(), 4);
  EXPECT_EQ(dut.refused_tiles(), 4);
  EXPECT_EQ(dut.version(layers::kElevation), 1);
  EXPECT_TRUE(dut.Complete(layers::kElevation));
  EXPECT_TRUE(SameLayer(dut.Layer(layers::kElevation)->at(layers::kElevation),
                        map_.at(layers::kElevation)));
}

// A version within the lead (a host whose clock runs ahead, or a forgery) is taken, but outranks
// nothing: the sender's next manifest and tiles, however numbered, replace it.
TEST_F(TileAssemblerTest, AVersionAheadOfTheClockOutranksNothing) {
  int64_t now_ms = 1'800'000'000'000;
  TileAssembler dut([&] { return now_ms; });
  ASSERT_TRUE(dut.OnManifest(cut_.manifest));
  for (const auto& t : cut_.tiles) ASSERT_TRUE(dut.OnTile(t.As()));

  TileManifest erase = cut_.manifest;
  erase.layer_version = now_ms + TileAssembler::kVersionLeadMs;
  erase.tiles.clear();
  ASSERT_TRUE(dut.OnManifest(erase));
  EXPECT_TRUE(std::isnan(dut.Layer(layers::kElevation)->at(layers::kElevation)(0, 0)));
  testing::OwnedTile ahead = cut_.tiles.front();
  ahead.header.tile_version = now_ms + 1000;
  for (float& c : ahead.cells) c = 9.f;
  ASSERT_TRUE(dut.OnTile(ahead.As()));

  now_ms += 10;  // the honest sender's next manifest, numbered far below
  TileManifest next = cut_.manifest;
  next.layer_version = 2;
  ASSERT_TRUE(dut.OnManifest(next));
  EXPECT_EQ(dut.version(layers::kElevation), 2);
  for (const auto& t : cut_.tiles) ASSERT_TRUE(dut.OnTile(t.As()));
  EXPECT_TRUE(dut.Complete(layers::kElevation));
  EXPECT_TRUE(SameLayer(dut.Layer(layers::kElevation)->at(layers::kElevation),
                        map_.at(layers::kElevation)));
  // Once the layer's newest is behind the clock, an older manifest is ignored again.
  EXPECT_TRUE(dut.OnManifest(cut_.manifest));
  EXPECT_EQ(dut.version(layers::kElevation), 2);
}

}  // namespace
}  // namespace cairn::mapstore
