#include "mapstore/lcm/mapstore_conversions.h"

#include <gtest/gtest.h>

#include "common/crc32.h"
#include "mapstore/lcm/tile_wire.h"
#include "services/runtime/tiler.h"
#include "tests/unit/mapstore/fake_deriver.h"

namespace cairn::mapstore {
namespace {

// A layer as runtime::LayerTiler publishes it.
runtime::LayerTiler::Batch Published(runtime::TileEncoding encoding) {
  common::GridMap map = testing::SampleSnapshot("m", 23, 17).base;
  map.AddLayer("occupancy", 40.f).block(0, 0, 3, 3).setConstant(common::kUnknown);
  runtime::LayerTiler tiler("rover1", "live", 10);
  return tiler.Update(map, encoding == runtime::TileEncoding::kFloat ? "elevation" : "occupancy",
                      encoding, 5, true);
}

TEST(MapstoreConversionsTest, ManifestsRoundTripAndBadArraysAreRefused) {
  const cairn::lcmt_grid_manifest msg = Published(runtime::TileEncoding::kFloat).manifest;
  auto manifest = FromLcm(msg);
  ASSERT_TRUE(manifest.ok());
  EXPECT_EQ(manifest->layer, "elevation");
  EXPECT_EQ(manifest->tile_size, 10);
  EXPECT_EQ(manifest->tiles.size(), static_cast<size_t>(msg.num_tiles));
  const cairn::lcmt_grid_manifest back = ToLcm(*manifest, msg.utime);
  std::vector<uint8_t> a(msg.getEncodedSize()), b(back.getEncodedSize());
  msg.encode(a.data(), 0, static_cast<int>(a.size()));
  back.encode(b.data(), 0, static_cast<int>(b.size()));
  EXPECT_EQ(a, b);
  cairn::lcmt_grid_manifest bad = msg;
  bad.checksum.pop_back();
  EXPECT_EQ(FromLcm(bad).status().code(), common::StatusCode::kInvalidArgument);
}

TEST(MapstoreConversionsTest, FloatTilesAreCheckedAgainstTheirCrc) {
  const auto batch = Published(runtime::TileEncoding::kFloat);
  const cairn::lcmt_grid_tile& msg = batch.tiles.front();
  auto tile = CheckFloatTile(msg);
  ASSERT_TRUE(tile.ok());
  EXPECT_EQ(tile->header.layer, "elevation");
  EXPECT_EQ(tile->header.map_name, "live");
  EXPECT_EQ(tile->header.checksum, static_cast<uint32_t>(msg.checksum));
  EXPECT_EQ(tile->cells, msg.data.data());  // borrowed, not copied
  cairn::lcmt_grid_tile damaged = msg;
  damaged.data[55] += 1.f;  // a known cell (the first rows start unknown)
  EXPECT_EQ(CheckFloatTile(damaged).status().code(), common::StatusCode::kCorrupt);
  cairn::lcmt_grid_tile compressed = msg;
  ASSERT_TRUE(CompressTile(&compressed));
  EXPECT_EQ(CheckFloatTile(compressed).status().code(), common::StatusCode::kInvalidArgument);
  std::vector<float> cells;
  ASSERT_TRUE(DecodeTileCells(compressed, &cells).ok());
  const CheckedTile decoded = DecodedTile(compressed, cells);
  EXPECT_EQ(decoded.num_cells, msg.data.size());
  EXPECT_EQ(decoded.header.checksum, tile->header.checksum);
}

TEST(MapstoreConversionsTest, OccupancyTilesBecomeFloatsWithUnknownForMinusOne) {
  const auto batch = Published(runtime::TileEncoding::kOccupancy);
  const cairn::lcmt_occupancy_tile& msg = batch.occupancy_tiles.front();
  std::vector<float> cells;
  auto tile = CheckOccupancyTile(msg, &cells);
  ASSERT_TRUE(tile.ok());
  EXPECT_TRUE(std::isnan(cells[0]));
  EXPECT_EQ(cells[5], 40.f);
  EXPECT_EQ(tile->header.checksum, common::Crc32(msg.data.data(), msg.data.size()));
  cairn::lcmt_occupancy_tile damaged = msg;
  damaged.data[5] = 41;
  EXPECT_EQ(CheckOccupancyTile(damaged, &cells).status().code(), common::StatusCode::kCorrupt);
}

TEST(MapstoreConversionsTest, ResendRequestsAndOctomapChunksRoundTrip) {
  TileRequest r;
  r.robot = "rover1";
  r.map_name = "12/hall";
  r.layer = "elevation";
  r.layer_version = 4;
  r.tiles = {{1, 2}, {3, 0}};
  const cairn::lcmt_tile_resend_request msg = ToLcm(r, "cairn-mapstore", 99);
  EXPECT_EQ(msg.requester, "cairn-mapstore");
  EXPECT_EQ(msg.num_tiles, 2);
  const TileRequest back = FromLcm(msg);
  EXPECT_EQ(back.tiles, r.tiles);
  EXPECT_EQ(back.layer_version, 4);
  EXPECT_EQ(back.map_name, r.map_name);

  OctomapData tree;
  tree.bytes = std::string(500, 't');
  tree.resolution_m = 0.2;
  const OctomapChunk chunk = SplitOctomap(tree, 300)[1];
  const cairn::lcmt_octomap wire = ToLcm(chunk, "rover1", "12/hall", 7);
  EXPECT_EQ(wire.num_bytes, 200);
  auto read = FromLcm(wire);
  ASSERT_TRUE(read.ok());
  EXPECT_EQ(read->chunk_index, 1);
  EXPECT_EQ(read->chunk_count, 2);
  EXPECT_EQ(read->checksum, chunk.checksum);
  EXPECT_EQ(std::string(read->data, read->size), std::string(200, 't'));
  cairn::lcmt_octomap bad = wire;
  bad.num_bytes = 3;
  EXPECT_EQ(FromLcm(bad).status().code(), common::StatusCode::kInvalidArgument);
}

// A mapper's list of layers (its answer to OP_PUBLISH_ALL) is checked before a save waits for
// any of them.
TEST(MapstoreConversionsTest, AMapperReplysLayersAreCheckedAgainstTheirCountAndNames) {
  cairn::lcmt_map_control_reply m{};
  m.request_id = 5;
  m.status = cairn::lcmt_map_control_reply::STATUS_OK;
  m.layers = {"elevation", "cost/pioneer3at"};
  m.num_layers = 2;
  auto ok = FromLcm(m);
  ASSERT_TRUE(ok.ok()) << ok.status().ToString();
  EXPECT_EQ(ok->request_id, 5);
  EXPECT_TRUE(ok->ok);
  EXPECT_EQ(ok->layers, m.layers);
  m.num_layers = 3;  // disagrees with the list
  EXPECT_EQ(FromLcm(m).status().code(), common::StatusCode::kInvalidArgument);
  m.layers = {"elevation", "../etc"};
  m.num_layers = 2;
  EXPECT_EQ(FromLcm(m).status().code(), common::StatusCode::kInvalidArgument);
  m.layers.assign(cairn::lcmt_map_control_reply::MAX_LAYERS + 1, "elevation");
  m.num_layers = static_cast<int32_t>(m.layers.size());
  EXPECT_EQ(FromLcm(m).status().code(), common::StatusCode::kInvalidArgument);
  m.layers.clear();
  m.num_layers = 0;
  m.status = cairn::lcmt_map_control_reply::STATUS_INVALID;
  EXPECT_FALSE(FromLcm(m).value().ok);
}

TEST(MapstoreConversionsTest, RequestsNameTheirMapWriterAndSave) {
  cairn::lcmt_mapstore_request r{};
  r.request_id = 42;
  r.map_name = "hall";
  r.version = 3;
  r.layers = {"elevation"};
  r.robot = "rover1";
  r.expect_octomap = true;
  EXPECT_EQ(SiteOf(r), kDefaultSite);
  EXPECT_EQ(RefOf(r).version, 3);
  EXPECT_EQ(ContextOf(r).actor, "unknown");
  EXPECT_EQ(ContextOf(r).request_id, 42);
  r.site = "lab";
  r.requester = "navigator";
  EXPECT_EQ(RefOf(r).site, "lab");
  EXPECT_EQ(ContextOf(r).actor, "navigator");
  const SaveRequest save = SaveRequestOf(r);
  EXPECT_EQ(SaveKey(save), "navigator#42");
  EXPECT_EQ(PushName(save), "42/hall");
  EXPECT_EQ(save.robot, "rover1");
  EXPECT_EQ(save.layers, r.layers);
  EXPECT_TRUE(save.expect_octomap);
}

}  // namespace
}  // namespace cairn::mapstore
