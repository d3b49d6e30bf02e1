#include "common/tile_assembler.h"

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

}  // namespace
}  // namespace cairn::mapstore
