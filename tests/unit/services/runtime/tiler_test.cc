#include "services/runtime/layer_assembler.h"
#include "services/runtime/tiler.h"

#include <cmath>
#include <optional>

#include <gtest/gtest.h>

namespace cairn::runtime {
namespace {

common::GridMap MakeMap(int nx, int ny) {
  common::GridGeometry g;
  g.resolution_m = 0.2;
  g.size_x = nx;
  g.size_y = ny;
  g.origin = {-3.0, 5.0, 0.0};
  common::GridMap map(g);
  common::Layer& l = map.AddLayer("elevation");
  for (int x = 0; x < nx; ++x) {
    for (int y = 0; y < ny; ++y) l(x, y) = 0.01f * x + 0.1f * y;  // asymmetric
  }
  return map;
}

TEST(LayerTilerTest, FirstUpdateSendsAllTilesThenOnlyChanged) {
  common::GridMap map = MakeMap(250, 130);  // 3 x 2 tiles of 100, edges smaller
  LayerTiler tiler("r1", "live");
  auto first = tiler.Update(map, "elevation", TileEncoding::kFloat, 1);
  EXPECT_TRUE(first.changed);
  EXPECT_EQ(first.tiles.size(), 6u);
  EXPECT_EQ(first.manifest.num_tiles, 6);
  EXPECT_EQ(first.manifest.layer_version, 1);
  for (const auto& t : first.tiles) {
    EXPECT_LT(t.getEncodedSize(), static_cast<int>(kMaxMessageBytes));
    EXPECT_EQ(t.num_cells, t.cells_x * t.cells_y);
  }
  // No change: nothing sent, version unchanged.
  auto same = tiler.Update(map, "elevation", TileEncoding::kFloat, 2);
  EXPECT_FALSE(same.changed);
  EXPECT_TRUE(same.tiles.empty());
  EXPECT_EQ(same.manifest.layer_version, 1);
  // One cell in tile (2, 1) changes.
  map.at("elevation")(240, 120) = 42.f;
  auto one = tiler.Update(map, "elevation", TileEncoding::kFloat, 3);
  ASSERT_EQ(one.tiles.size(), 1u);
  EXPECT_EQ(one.tiles[0].tile_ix, 2);
  EXPECT_EQ(one.tiles[0].tile_iy, 1);
  EXPECT_EQ(one.manifest.layer_version, 2);
}

TEST(LayerTilerTest, ARestartedPublisherWithAVersionBaseSupersedesItsPredecessor) {
  // The assembler ignores manifests older than the one it holds: a publisher restarted from
  // version 1 would be ignored; one starting from a later wall-clock base is taken at once.
  common::GridMap before = MakeMap(120, 50);
  common::GridMap after = before;
  after.at("elevation")(5, 5) = 42.f;
  LayerTiler old_publisher("r1", "live", kDefaultTileSize, 1000);
  LayerAssembler receiver;
  for (int k = 0; k < 3; ++k) {
    before.at("elevation")(0, 0) = static_cast<float>(k);
    auto b = old_publisher.Update(before, "elevation", TileEncoding::kFloat, k);
    for (const auto& t : b.tiles) receiver.OnTile(t);
    receiver.OnManifest(b.manifest);
  }
  EXPECT_EQ(receiver.version("elevation"), 1003);
  LayerTiler restarted_from_zero("r1", "live");
  auto stale = restarted_from_zero.Update(after, "elevation", TileEncoding::kFloat, 10);
  LayerAssembler copy = receiver;
  for (const auto& t : stale.tiles) copy.OnTile(t);
  copy.OnManifest(stale.manifest);
  EXPECT_EQ(copy.version("elevation"), 1003);  // ignored
  LayerTiler restarted("r1", "live", kDefaultTileSize, 2000);
  auto fresh = restarted.Update(after, "elevation", TileEncoding::kFloat, 10);
  EXPECT_EQ(fresh.manifest.layer_version, 2001);
  for (const auto& t : fresh.tiles) receiver.OnTile(t);
  receiver.OnManifest(fresh.manifest);
  EXPECT_EQ(receiver.version("elevation"), 2001);
  ASSERT_TRUE(receiver.Complete("elevation"));
  EXPECT_FLOAT_EQ(receiver.Layer("elevation")->at("elevation")(5, 5), 42.f);
  EXPECT_GT(LayerTiler::StartVersionBase(), 1'600'000'000'000);  // ms since the epoch
  EXPECT_THROW(LayerTiler("r1", "live", kDefaultTileSize, -1), std::invalid_argument);
}

TEST(LayerAssemblerTest, RebuildsExactlyAndDetectsMissingTiles) {
  common::GridMap map = MakeMap(250, 130);
  LayerTiler tiler("r1", "live");
  auto batch = tiler.Update(map, "elevation", TileEncoding::kFloat, 1);
  LayerAssembler assembler;
  assembler.OnManifest(batch.manifest);
  // Lose tile (1, 0).
  for (const auto& t : batch.tiles) {
    if (!(t.tile_ix == 1 && t.tile_iy == 0)) {
      EXPECT_TRUE(assembler.OnTile(t));
    }
  }
  EXPECT_FALSE(assembler.Complete("elevation"));
  auto missing = assembler.Missing("elevation");
  ASSERT_EQ(missing.size(), 1u);
  EXPECT_EQ(missing[0], std::make_pair(1, 0));
  auto request = assembler.MakeResendRequest("elevation", "test", 5);
  ASSERT_TRUE(request.has_value());
  EXPECT_EQ(request->num_tiles, 1);
  // The publisher answers the request; the layer is then complete and identical.
  auto resend = tiler.Resend(*request);
  ASSERT_EQ(resend.tiles.size(), 1u);
  EXPECT_TRUE(assembler.OnTile(resend.tiles[0]));
  EXPECT_TRUE(assembler.Complete("elevation"));
  auto rebuilt = assembler.Layer("elevation");
  ASSERT_TRUE(rebuilt.has_value());
  EXPECT_EQ(rebuilt->geometry(), map.geometry());
  EXPECT_TRUE(*rebuilt == map);
}

// A receiver that decoded a compressed tile hands its cells over; its declared checksum stands
// for them. Cells that do not fit the tile are refused. A layer some tiles never reached has
// unknown cells there, one all tiles reached has none.
TEST(LayerAssemblerTest, DecodedTilesRebuildTheLayerAndGapsStayUnknown) {
  common::GridMap map = MakeMap(250, 130);
  LayerTiler tiler("r1", "live");
  auto batch = tiler.Update(map, "elevation", TileEncoding::kFloat, 1);
  LayerAssembler assembler;
  assembler.OnManifest(batch.manifest);
  cairn::lcmt_grid_tile header = batch.tiles[0];
  header.data.clear();
  header.num_cells = 0;
  EXPECT_FALSE(assembler.OnDecodedTile(header, std::vector<float>(7, 1.f)));
  EXPECT_EQ(assembler.checksum_errors(), 1);
  for (size_t i = 1; i < batch.tiles.size(); ++i) {
    cairn::lcmt_grid_tile h = batch.tiles[i];
    std::vector<float> cells = std::move(h.data);
    h.data.clear();
    h.num_cells = 0;
    EXPECT_TRUE(assembler.OnDecodedTile(h, std::move(cells)));
  }
  EXPECT_FALSE(assembler.Complete("elevation"));
  auto partial = assembler.Layer("elevation");
  ASSERT_TRUE(partial.has_value());
  EXPECT_TRUE(std::isnan(partial->at("elevation")(0, 0)));  // tile (0, 0) never arrived
  EXPECT_EQ(partial->at("elevation")(249, 129), map.at("elevation")(249, 129));
  EXPECT_TRUE(assembler.OnDecodedTile(header, batch.tiles[0].data));
  EXPECT_TRUE(assembler.Complete("elevation"));
  EXPECT_TRUE(*assembler.Layer("elevation") == map);
}

// Tiles are pasted into the layer as they arrive: a tile a newer manifest no longer lists
// becomes unknown again, HeldChecksum names what is held, and TakeLayer hands the layer over
// without a copy and forgets it.
TEST(LayerAssemblerTest, HeldTilesAreTheLayerUntilTakenAndDroppedOnesBecomeUnknown) {
  common::GridMap map = MakeMap(250, 130);
  LayerTiler tiler("r1", "live");
  auto batch = tiler.Update(map, "elevation", TileEncoding::kFloat, 1);
  LayerAssembler assembler;
  assembler.OnManifest(batch.manifest);
  for (const auto& t : batch.tiles) ASSERT_TRUE(assembler.OnTile(t));
  EXPECT_EQ(assembler.HeldChecksum("elevation", 1, 0),
            std::optional<uint32_t>(static_cast<uint32_t>(batch.tiles[1].checksum)));
  EXPECT_FALSE(assembler.HeldChecksum("elevation", 9, 9).has_value());
  EXPECT_FALSE(assembler.HeldChecksum("variance", 0, 0).has_value());
  EXPECT_EQ(assembler.Geometry("elevation"), map.geometry());

  // The next version of the layer has tile (1, 0) all unknown: its manifest leaves it out.
  common::GridMap next = map;
  for (int x = 100; x < 200; ++x) {
    for (int y = 0; y < 100; ++y) next.at("elevation")(x, y) = common::kUnknown;
  }
  auto update = tiler.Update(next, "elevation", TileEncoding::kFloat, 2);
  assembler.OnManifest(update.manifest);
  EXPECT_FALSE(assembler.HeldChecksum("elevation", 1, 0).has_value());
  EXPECT_TRUE(assembler.Complete("elevation"));
  EXPECT_TRUE(*assembler.Layer("elevation") == next);

  auto taken = assembler.TakeLayer("elevation");
  ASSERT_TRUE(taken.has_value());
  EXPECT_TRUE(*taken == next);
  EXPECT_FALSE(assembler.Layer("elevation").has_value());
  EXPECT_FALSE(assembler.TakeLayer("elevation").has_value());
}

// A receiver decoding tiles straight into the layer: BeginTile names the tile's place (edge
// tiles clipped), EndTile holds the tile or, when it did not decode, leaves its place unknown;
// a tile older than the one held has nothing to write.
TEST(LayerAssemblerTest, TilesWrittenInPlaceAreHeldAndFailedOnesStayUnknown) {
  common::GridMap map = MakeMap(250, 130);
  LayerTiler tiler("r1", "live");
  auto batch = tiler.Update(map, "elevation", TileEncoding::kFloat, 1);
  LayerAssembler assembler;
  assembler.OnManifest(batch.manifest);
  auto write = [&](const cairn::lcmt_grid_tile& tile, const LayerAssembler::TileSlot& slot) {
    for (int y = 0; y < slot.cells_y; ++y) {
      for (int x = 0; x < slot.cells_x; ++x) {
        slot.first[y * slot.row_stride + x] = tile.data[y * tile.cells_x + x];
      }
    }
  };
  for (const auto& t : batch.tiles) {
    const auto slot = assembler.BeginTile(t);
    ASSERT_TRUE(slot.has_value());
    ASSERT_NE(slot->first, nullptr);
    EXPECT_EQ(slot->row_stride, 250);
    EXPECT_EQ(slot->cells_x, t.cells_x);
    EXPECT_EQ(slot->cells_y, t.cells_y);
    const bool fail = t.tile_ix == 1 && t.tile_iy == 1;
    if (!fail) write(t, *slot);
    assembler.EndTile(t, !fail);
  }
  EXPECT_FALSE(assembler.Complete("elevation"));
  EXPECT_EQ(assembler.Missing("elevation"), (std::vector<std::pair<int, int>>{{1, 1}}));
  auto partial = assembler.Layer("elevation");
  ASSERT_TRUE(partial.has_value());
  EXPECT_TRUE(std::isnan(partial->at("elevation")(150, 110)));  // in tile (1, 1)
  EXPECT_EQ(partial->at("elevation")(249, 129), map.at("elevation")(249, 129));
  EXPECT_EQ(partial->at("elevation")(0, 0), map.at("elevation")(0, 0));

  // The resent tile arrives; a copy of an older version of it has nothing to write.
  const auto& resent = batch.tiles[4];
  ASSERT_EQ(std::make_pair(resent.tile_ix, resent.tile_iy), std::make_pair(1, 1));
  const auto slot = assembler.BeginTile(resent);
  ASSERT_TRUE(slot.has_value() && slot->first != nullptr);
  write(resent, *slot);
  assembler.EndTile(resent, true);
  cairn::lcmt_grid_tile older = resent;
  older.tile_version = 0;
  const auto none = assembler.BeginTile(older);
  ASSERT_TRUE(none.has_value());
  EXPECT_EQ(none->first, nullptr);
  EXPECT_TRUE(assembler.Complete("elevation"));
  // A tile beyond the layer's edge has nothing to write and counts as held.
  cairn::lcmt_grid_tile beyond = resent;
  beyond.tile_ix = 7;
  const auto outside = assembler.BeginTile(beyond);
  ASSERT_TRUE(outside.has_value());
  EXPECT_EQ(outside->first, nullptr);
  EXPECT_EQ(assembler.HeldChecksum("elevation", 7, 1),
            std::optional<uint32_t>(static_cast<uint32_t>(beyond.checksum)));
  EXPECT_TRUE(*assembler.TakeLayer("elevation") == map);

  // A tile that does not fit a layer gets no place.
  cairn::lcmt_grid_tile huge = batch.tiles[0];
  huge.layer_size_x = 100000;
  huge.layer_size_y = 100000;
  EXPECT_FALSE(assembler.BeginTile(huge).has_value());
  EXPECT_EQ(assembler.checksum_errors(), 1);
}

// A tile declaring a layer too large to hold is refused.
TEST(LayerAssemblerTest, ATileOfAnImpossiblyLargeLayerIsRefused) {
  common::GridMap map = MakeMap(250, 130);
  LayerTiler tiler("r1", "live");
  auto batch = tiler.Update(map, "elevation", TileEncoding::kFloat, 1);
  cairn::lcmt_grid_tile tile = batch.tiles[0];
  tile.layer_size_x = 100000;
  tile.layer_size_y = 100000;
  LayerAssembler assembler;
  EXPECT_FALSE(assembler.OnTile(tile));
  EXPECT_EQ(assembler.checksum_errors(), 1);
  EXPECT_FALSE(assembler.Layer("elevation").has_value());
}

// A map store sends its stored tiles as they are: adopted tiles go out and come back on a
// resend byte for byte, with the manifest of what Update would have listed.
TEST(LayerTilerTest, AdoptedTilesAreSentAndResentAsTheyAre) {
  common::GridMap map = MakeMap(250, 130);
  LayerTiler reference("r1", "stored");
  const auto expected = reference.Update(map, "elevation", TileEncoding::kFloat, 1);
  std::vector<LayerTiler::EncodedTile> encoded;
  for (const auto& t : expected.tiles) {
    LayerTiler::EncodedTile e;
    e.tile_ix = t.tile_ix;
    e.tile_iy = t.tile_iy;
    e.cells_x = t.cells_x;
    e.cells_y = t.cells_y;
    e.checksum = static_cast<uint32_t>(t.checksum);
    if (t.tile_ix == 1) {
      // Stands for a compressed tile: opaque bytes the tiler must not touch.
      e.encoding = cairn::lcmt_grid_tile::ENCODING_ZSTD_SHUFFLE4;
      e.bytes = {1, 2, 3, static_cast<uint8_t>(t.tile_iy)};
    } else {
      e.data = t.data;
    }
    encoded.push_back(std::move(e));
  }
  LayerTiler tiler("r1", "stored");
  const auto batch = tiler.Adopt("elevation", map.geometry(), encoded, 7);
  ASSERT_EQ(batch.tiles.size(), 6u);
  EXPECT_EQ(batch.manifest.num_tiles, 6);
  EXPECT_EQ(batch.manifest.checksum, expected.manifest.checksum);
  EXPECT_EQ(batch.manifest.tile_ix, expected.manifest.tile_ix);
  LayerAssembler assembler;
  assembler.OnManifest(batch.manifest);
  for (const auto& t : batch.tiles) {
    if (t.tile_ix == 1) {
      EXPECT_EQ(t.encoding, +cairn::lcmt_grid_tile::ENCODING_ZSTD_SHUFFLE4);
      EXPECT_EQ(t.num_cells, 0);
      EXPECT_EQ(t.bytes, (std::vector<uint8_t>{1, 2, 3, static_cast<uint8_t>(t.tile_iy)}));
      EXPECT_FALSE(assembler.OnTile(t));  // the assembler knows no codec
    } else {
      EXPECT_TRUE(assembler.OnTile(t));
    }
  }
  EXPECT_EQ(assembler.Missing("elevation"), (std::vector<std::pair<int, int>>{{1, 0}, {1, 1}}));
  // The resend of a compressed tile is the same bytes.
  auto request = assembler.MakeResendRequest("elevation", "test", 8);
  ASSERT_TRUE(request.has_value());
  const auto resent = tiler.Resend(*request);
  ASSERT_EQ(resent.tiles.size(), 2u);
  for (const auto& t : resent.tiles) {
    EXPECT_EQ(t.bytes, (std::vector<uint8_t>{1, 2, 3, static_cast<uint8_t>(t.tile_iy)}));
    EXPECT_EQ(t.num_bytes, 4);
  }
  // Adopting again bumps the version; a tile that does not fit the grid is refused.
  EXPECT_EQ(tiler.Adopt("elevation", map.geometry(), encoded, 9).manifest.layer_version,
            batch.manifest.layer_version + 1);
  auto wrong = encoded;
  wrong[0].cells_x -= 1;
  EXPECT_THROW(tiler.Adopt("elevation", map.geometry(), wrong, 10), std::invalid_argument);
  auto outside = encoded;
  outside[0].tile_ix = 3;
  EXPECT_THROW(tiler.Adopt("elevation", map.geometry(), outside, 11), std::invalid_argument);
}

// A receiver may ask for tiles of a layer this publisher has not tiled yet (it restarted and a
// receiver still holds its predecessor's layer): the answer is empty and its manifest, though
// not sent, is all zeros and encodes (it once held garbage counts, and encoding read past the
// end of its vectors).
TEST(LayerTilerTest, AResendForALayerNotTiledYetIsEmptyAndItsManifestEncodes) {
  LayerTiler tiler("r1", "live");
  cairn::lcmt_tile_resend_request request{};
  request.robot = "r1";
  request.map_name = "live";
  request.layer = "cost/pioneer3at";
  request.num_tiles = 2;
  request.tile_ix = {3, 4};
  request.tile_iy = {1, 1};
  const auto batch = tiler.Resend(request);
  EXPECT_TRUE(batch.tiles.empty());
  EXPECT_TRUE(batch.occupancy_tiles.empty());
  EXPECT_FALSE(batch.changed);
  EXPECT_EQ(batch.manifest.num_tiles, 0);
  EXPECT_EQ(batch.manifest.layer_version, 0);
  std::vector<uint8_t> buffer(static_cast<size_t>(batch.manifest.getEncodedSize()));
  EXPECT_EQ(batch.manifest.encode(buffer.data(), 0, static_cast<int>(buffer.size())),
            static_cast<int>(buffer.size()));
}

TEST(LayerAssemblerTest, CorruptTileIsRefusedAndStaleTileIsMissing) {
  common::GridMap map = MakeMap(120, 50);
  LayerTiler tiler("r1", "live");
  auto v1 = tiler.Update(map, "elevation", TileEncoding::kFloat, 1);
  LayerAssembler assembler;
  auto corrupt = v1.tiles[0];
  corrupt.data[3] += 1.f;
  EXPECT_FALSE(assembler.OnTile(corrupt));
  EXPECT_EQ(assembler.checksum_errors(), 1);
  for (const auto& t : v1.tiles) assembler.OnTile(t);
  assembler.OnManifest(v1.manifest);
  EXPECT_TRUE(assembler.Complete("elevation"));
  // Version 2 changes tile (0,0); its manifest arrives but the tile is lost.
  map.at("elevation")(5, 5) = -1.f;
  auto v2 = tiler.Update(map, "elevation", TileEncoding::kFloat, 2);
  assembler.OnManifest(v2.manifest);
  EXPECT_FALSE(assembler.Complete("elevation"));
  EXPECT_EQ(assembler.Missing("elevation"), (std::vector<std::pair<int, int>>{{0, 0}}));
  EXPECT_EQ(assembler.version("elevation"), 2);
}

TEST(LayerTilerTest, UnknownTilesAreAbsentAndOccupancyEncodes) {
  common::GridGeometry g;
  g.resolution_m = 0.05;
  g.size_x = 300;
  g.size_y = 100;
  common::GridMap map(g);
  common::Layer& occ = map.AddLayer("occupancy");  // all NaN
  occ(250, 10) = 100.f;
  occ(251, 10) = 0.f;
  occ(252, 10) = 49.6f;
  LayerTiler tiler("r1", "live");
  auto batch = tiler.Update(map, "occupancy", TileEncoding::kOccupancy, 1);
  ASSERT_EQ(batch.occupancy_tiles.size(), 1u);  // only tile (2, 0) holds anything
  EXPECT_EQ(batch.manifest.num_tiles, 1);
  const auto& t = batch.occupancy_tiles[0];
  EXPECT_EQ(t.data[10 * t.cells_x + 50], 100);
  EXPECT_EQ(t.data[10 * t.cells_x + 52], 50);
  EXPECT_EQ(t.data[0], -1);
  LayerAssembler assembler;
  assembler.OnManifest(batch.manifest);
  assembler.OnTile(t);
  ASSERT_TRUE(assembler.Complete("occupancy"));
  auto back = assembler.Layer("occupancy");
  EXPECT_EQ(back->at("occupancy")(250, 10), 100.f);
  EXPECT_TRUE(std::isnan(back->at("occupancy")(0, 0)));
}

}  // namespace
}  // namespace cairn::runtime
