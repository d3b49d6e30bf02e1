#include "mapstore/lcm/tile_wire.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "common/crc32.h"
#include "services/runtime/layer_assembler.h"
#include "services/runtime/tiler.h"

namespace cairn::mapstore {
namespace {

// A 250 x 130 layer in tiles of 100: a cost-like layer (byte codes) and a terrain-like one.
common::GridMap TwoLayers() {
  common::GridGeometry g;
  g.resolution_m = 0.2;
  g.size_x = 250;
  g.size_y = 130;
  g.origin = {-3.0, 5.0, 0.0};
  common::GridMap map(g);
  common::Layer& cost = map.AddLayer("cost/rover");
  common::Layer& elevation = map.AddLayer("elevation");
  for (int x = 0; x < g.size_x; ++x) {
    for (int y = 0; y < g.size_y; ++y) {
      cost(x, y) = (x + y) % 11 == 0 ? common::kUnknown : static_cast<float>((x * 3 + y) % 255);
      elevation(x, y) = 0.01f * x - 0.02f * y;
    }
  }
  return map;
}

std::vector<cairn::lcmt_grid_tile> CompressedTiles(const common::GridMap& map,
                                                   const std::string& layer,
                                                   runtime::LayerAssembler* assembler) {
  runtime::LayerTiler tiler("r1", "7/site");
  auto batch = tiler.Update(map, layer, runtime::TileEncoding::kFloat, 1, true);
  assembler->OnManifest(batch.manifest);
  for (auto& t : batch.tiles) EXPECT_TRUE(CompressTile(&t));
  return batch.tiles;
}

// A batch decodes straight into the layers: every tile of both codecs is held and the layers
// come out bit for bit; a damaged tile, a tile of another map and a second copy of a tile in
// the same batch are handled, and a float tile goes through as it is.
TEST(TileWireTest, ABatchAssemblesStraightIntoItsLayers) {
  const common::GridMap map = TwoLayers();
  for (const int threads : {1, 2}) {
    runtime::LayerAssembler assembler;
    std::vector<cairn::lcmt_grid_tile> batch = CompressedTiles(map, "cost/rover", &assembler);
    ASSERT_EQ(batch.size(), 6u);
    EXPECT_EQ(batch[0].encoding, +cairn::lcmt_grid_tile::ENCODING_ZSTD_BYTES);
    const auto elevation = CompressedTiles(map, "elevation", &assembler);
    EXPECT_EQ(elevation[0].encoding, +cairn::lcmt_grid_tile::ENCODING_ZSTD_SHUFFLE4);
    batch.insert(batch.end(), elevation.begin(), elevation.end());
    cairn::lcmt_grid_tile damaged = batch[2];
    damaged.bytes[damaged.bytes.size() / 2] ^= 0x21;
    batch[2] = damaged;
    cairn::lcmt_grid_tile foreign = batch[3];
    foreign.map_name = "8/site";
    batch.push_back(foreign);
    batch.push_back(batch[7]);  // the same tile twice
    cairn::lcmt_grid_tile floats = elevation[5];
    ASSERT_TRUE(DecompressTile(&floats).ok());
    batch[11] = floats;

    EXPECT_EQ(AssembleTiles(batch, "7/site", threads, &assembler), 12) << threads;
    EXPECT_TRUE(assembler.Complete("elevation"));
    EXPECT_FALSE(assembler.Complete("cost/rover"));
    const auto missing = assembler.Missing("cost/rover");
    ASSERT_EQ(missing.size(), 1u);
    EXPECT_EQ(missing[0], std::make_pair(damaged.tile_ix, damaged.tile_iy));
    // The damaged tile is asked for again and arrives.
    cairn::lcmt_grid_tile resent = CompressedTiles(map, "cost/rover", &assembler)[2];
    EXPECT_TRUE(AssembleTile(resent, "7/site", &assembler));
    ASSERT_TRUE(assembler.Complete("cost/rover"));
    for (const std::string layer : {"cost/rover", "elevation"}) {
      const auto got = assembler.TakeLayer(layer);
      ASSERT_TRUE(got.has_value());
      const common::Layer& want = map.at(layer);
      const common::Layer& have = got->at(layer);
      ASSERT_EQ(have.size(), want.size());
      EXPECT_EQ(std::memcmp(have.data(), want.data(), sizeof(float) * want.size()), 0) << layer;
    }
  }
}

// Issue 20: a batch of small compressed tiles each claiming 4096 x 4096 cells zero-filled 64 MB
// per tile in the map store, and kept the buffers between batches. A batch decodes at most
// kMaxBatchDecodedCells, and large buffers are released before the next batch.
TEST(TileWireTest, ABatchOfTilesClaimingHugeGridsDecodesWithinItsBudget) {
  cairn::lcmt_grid_tile tile{};
  tile.map_name = "7/site";
  tile.layer = "elevation";
  tile.cells_x = 4096;
  tile.cells_y = 4096;
  tile.tile_size = 4096;
  tile.encoding = cairn::lcmt_grid_tile::ENCODING_FLOAT32;
  tile.data.assign(size_t{4096} * 4096, 0.f);
  tile.num_cells = static_cast<int32_t>(tile.data.size());
  tile.checksum = static_cast<int32_t>(
      common::Crc32(tile.data.data(), tile.data.size() * sizeof(float)));
  ASSERT_TRUE(CompressTile(&tile));
  EXPECT_LT(tile.bytes.size(), 100'000u);  // a few KB claim 64 MB
  const std::vector<cairn::lcmt_grid_tile> batch(8, tile);
  std::vector<std::vector<float>> cells;
  std::vector<char> ok;
  DecodeTiles(batch, "7/site", 2, &cells, &ok);
  EXPECT_EQ(std::count(ok.begin(), ok.end(), 1), 1);  // one 4096² tile fills the budget
  size_t held = 0;
  for (const auto& b : cells) held += b.capacity();
  EXPECT_LE(static_cast<int64_t>(held), kMaxBatchDecodedCells);
  // The next batch starts without the large buffer.
  DecodeTiles({}, "7/site", 2, &cells, &ok);
  held = 0;
  for (const auto& b : cells) held += b.capacity();
  EXPECT_LE(held, cells.size() * kKeptBufferCells);
}

}  // namespace
}  // namespace cairn::mapstore
