#include "mapstore/blob_codec.h"

#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>

#include <gtest/gtest.h>

#include "mapstore/names.h"
#include "tests/support/sample_obstacles.h"

namespace cairn::mapstore {
namespace {

using common::StatusCode;

std::vector<float> SmoothTerrain(int n) {
  std::vector<float> v(n);
  for (int i = 0; i < n; ++i) v[i] = 1.5f + 0.3f * std::sin(i * 0.01f);
  return v;
}

TEST(BlobCodecTest, EveryCodecRoundTripsAndKeysByContent) {
  const std::vector<float> cells = SmoothTerrain(10000);
  for (Codec codec : {Codec::kRaw, Codec::kZstd, Codec::kZstdShuffle4}) {
    const EncodedBlob blob = EncodeBlob(cells.data(), cells.size() * 4, codec);
    auto back = DecodeBlob(codec, blob.data, blob.raw_size, blob.raw_crc32);
    ASSERT_TRUE(back.ok()) << back.status().ToString();
    ASSERT_EQ(back->size(), cells.size() * 4);
    EXPECT_EQ(std::memcmp(back->data(), cells.data(), back->size()), 0);
    EXPECT_EQ(EncodeBlob(cells.data(), cells.size() * 4, codec).key, blob.key);
  }
  std::vector<float> other = cells;
  other[5000] += 1.f;
  EXPECT_NE(EncodeBlob(other.data(), other.size() * 4, Codec::kZstd).key,
            EncodeBlob(cells.data(), cells.size() * 4, Codec::kZstd).key);
}

TEST(BlobCodecTest, ShufflingHelpsSmoothFloats) {
  const std::vector<float> cells = SmoothTerrain(10000);
  const size_t plain = EncodeBlob(cells.data(), cells.size() * 4, Codec::kZstd).data.size();
  const size_t shuffled =
      EncodeBlob(cells.data(), cells.size() * 4, Codec::kZstdShuffle4).data.size();
  EXPECT_LT(shuffled, plain);
  EXPECT_LT(shuffled, cells.size() * 4 * 6 / 10);
}

// A cost layer's tile: whole numbers 0..100, lethal cells, unknown cells.
std::vector<float> CostCells(int n) {
  std::vector<float> v(n);
  for (int i = 0; i < n; ++i) {
    v[i] = i % 13 == 0 ? std::numeric_limits<float>::quiet_NaN()
                       : static_cast<float>(i % 7 == 0 ? 100 : (i * 31) % 60);
  }
  return v;
}

TEST(BlobCodecTest, WholeNumbersTravelAsOneBytePerCellBitForBit) {
  const std::vector<float> cells = CostCells(10000);
  ASSERT_EQ(FloatCodec(cells.data(), cells.size()), Codec::kZstdBytes);
  const EncodedBlob blob = EncodeBlob(cells.data(), cells.size() * 4, Codec::kZstdBytes);
  const EncodedBlob shuffled = EncodeBlob(cells.data(), cells.size() * 4, Codec::kZstdShuffle4);
  EXPECT_LT(blob.data.size(), shuffled.data.size());
  EXPECT_EQ(blob.raw_crc32, shuffled.raw_crc32);  // the CRC is the floats', whatever the codec
  auto back = DecodeBlob(Codec::kZstdBytes, blob.data, blob.raw_size, blob.raw_crc32,
                         /*verify_crc=*/true);
  ASSERT_TRUE(back.ok()) << back.status().ToString();
  EXPECT_EQ(std::memcmp(back->data(), cells.data(), back->size()), 0);
  // 0 and 254 are the ends of the range.
  const std::vector<float> ends = {0.f, 254.f, 1.f};
  EXPECT_EQ(FloatCodec(ends.data(), ends.size()), Codec::kZstdBytes);
}

// Every byte code (0..254 and the product's NaN) decodes to its float bit for bit, whatever the
// length (whole 16-code steps and the rest).
TEST(BlobCodecTest, EveryByteCodeDecodesToItsFloatAtAnyLength) {
  for (const int n : {1, 15, 16, 17, 256, 771}) {
    std::vector<float> cells(n);
    for (int i = 0; i < n; ++i) {
      const int code = (i * 7) % 256;
      cells[i] = code == 255 ? std::numeric_limits<float>::quiet_NaN() : static_cast<float>(code);
    }
    ASSERT_EQ(FloatCodec(cells.data(), cells.size()), Codec::kZstdBytes) << n;
    const EncodedBlob blob = EncodeBlob(cells.data(), cells.size() * 4, Codec::kZstdBytes);
    auto back = DecodeBlob(Codec::kZstdBytes, blob.data, blob.raw_size, blob.raw_crc32,
                           /*verify_crc=*/true);
    ASSERT_TRUE(back.ok()) << n << ": " << back.status().ToString();
    EXPECT_EQ(std::memcmp(back->data(), cells.data(), back->size()), 0) << n;
  }
}

// A tile's blob decodes straight into its place in a wider layer, clipped to the layer's edge;
// the cells around it are left alone, and a damaged blob or rows beyond the blob are refused.
TEST(BlobCodecTest, FloatRowsDecodeATileIntoItsPlaceInALayer) {
  constexpr int kTileX = 21, kTileY = 9, kStride = 50;
  std::vector<float> terrain = SmoothTerrain(kTileX * kTileY);
  const std::vector<float> cost = CostCells(kTileX * kTileY);
  for (const auto& [codec, cells] :
       {std::make_pair(Codec::kZstdBytes, cost), std::make_pair(Codec::kZstdShuffle4, terrain),
        std::make_pair(Codec::kZstd, terrain)}) {
    const EncodedBlob blob = EncodeBlob(cells.data(), cells.size() * 4, codec);
    for (const bool verify : {false, true}) {
      std::vector<float> layer(kStride * 12, -7.f);
      FloatRows rows;
      rows.first = &layer[2 * kStride + 3];
      rows.row_stride = kStride;
      rows.cells_per_row = 17;  // clipped at the layer's edge
      rows.rows = 8;
      ASSERT_TRUE(DecodeFloatBlobRows(codec, blob.data.data(), blob.data.size(), kTileX, kTileY,
                                      blob.raw_crc32, rows, verify)
                      .ok());
      for (int y = 0; y < 12; ++y) {
        for (int x = 0; x < kStride; ++x) {
          const float got = layer[y * kStride + x];
          const bool inside = y >= 2 && y < 10 && x >= 3 && x < 20;
          if (!inside) {
            ASSERT_EQ(got, -7.f) << "outside the tile at " << x << ", " << y;
            continue;
          }
          const float want = cells[(y - 2) * kTileX + (x - 3)];
          ASSERT_EQ(std::memcmp(&got, &want, 4), 0) << static_cast<int>(codec) << " at " << x;
        }
      }
      std::string damaged = blob.data;
      damaged[damaged.size() / 2] ^= 0x10;
      EXPECT_EQ(DecodeFloatBlobRows(codec, damaged.data(), damaged.size(), kTileX, kTileY,
                                    blob.raw_crc32, rows, verify)
                    .code(),
                common::StatusCode::kCorrupt);
      FloatRows too_wide = rows;
      too_wide.cells_per_row = kTileX + 1;
      EXPECT_EQ(DecodeFloatBlobRows(codec, blob.data.data(), blob.data.size(), kTileX, kTileY,
                                    blob.raw_crc32, too_wide, verify)
                    .code(),
                common::StatusCode::kInvalidArgument);
    }
  }
}

TEST(BlobCodecTest, ValuesWithoutAByteCodeKeepTheFloatCodec) {
  const float kOther = std::nanf("7");  // a NaN with another payload: its bits would change
  for (float odd :
       {0.5f, -0.f, -1.f, 255.f, 1e9f, kOther, std::numeric_limits<float>::infinity()}) {
    std::vector<float> cells = CostCells(100);
    cells[42] = odd;
    EXPECT_EQ(FloatCodec(cells.data(), cells.size()), Codec::kZstdShuffle4) << odd;
    EXPECT_THROW(EncodeBlob(cells.data(), cells.size() * 4, Codec::kZstdBytes),
                 std::invalid_argument)
        << odd;
  }
  const std::vector<float> terrain = SmoothTerrain(100);
  EXPECT_EQ(FloatCodec(terrain.data(), terrain.size()), Codec::kZstdShuffle4);
}

TEST(BlobCodecTest, ADamagedByteBlobIsRefused) {
  const std::vector<float> cells = CostCells(10000);
  const EncodedBlob blob = EncodeBlob(cells.data(), cells.size() * 4, Codec::kZstdBytes);
  std::string damaged = blob.data;
  damaged[damaged.size() / 2] ^= 0x01;
  EXPECT_EQ(DecodeBlob(Codec::kZstdBytes, damaged, blob.raw_size, blob.raw_crc32).status().code(),
            StatusCode::kCorrupt);
  // A frame of another size is no tile of these cells.
  EXPECT_EQ(
      DecodeBlob(Codec::kZstdBytes, blob.data, blob.raw_size * 2, blob.raw_crc32).status().code(),
      StatusCode::kCorrupt);
  // Without a stored checksum the frame is decompressed and its cells compared...
  StoredTile tile{
      0, 0, 100, 100, static_cast<int>(Codec::kZstdBytes), blob.raw_crc32, blob.data, std::nullopt};
  EXPECT_TRUE(CheckStoredTile(tile).ok());
  tile.data = damaged;
  EXPECT_EQ(CheckStoredTile(tile).code(), StatusCode::kCorrupt);
  // ...with one, the stored bytes and header are compared to it without decompressing.
  tile.data = blob.data;
  tile.stored_crc32 = blob.stored_crc32;
  EXPECT_EQ(blob.stored_crc32, StoredBlobCrc32(static_cast<int>(blob.codec), blob.raw_size,
                                               blob.raw_crc32, blob.data.data(), blob.data.size()));
  EXPECT_TRUE(CheckStoredTile(tile).ok());
  tile.data = damaged;
  EXPECT_EQ(CheckStoredTile(tile).code(), StatusCode::kCorrupt);
  tile.data = blob.data;
  tile.raw_crc32 ^= 1u;  // the header is covered too
  EXPECT_EQ(CheckStoredTile(tile).code(), StatusCode::kCorrupt);
}

TEST(BlobCodecTest, DamageIsDetected) {
  const std::vector<float> cells = SmoothTerrain(1000);
  const EncodedBlob blob = EncodeBlob(cells.data(), cells.size() * 4, Codec::kZstdShuffle4);
  std::string flipped = blob.data;
  flipped[flipped.size() / 2] ^= 0x5a;
  auto bad = DecodeBlob(Codec::kZstdShuffle4, flipped, blob.raw_size, blob.raw_crc32);
  EXPECT_EQ(bad.status().code(), StatusCode::kCorrupt);
  auto truncated =
      DecodeBlob(Codec::kZstdShuffle4, blob.data.substr(0, 10), blob.raw_size, blob.raw_crc32);
  EXPECT_EQ(truncated.status().code(), StatusCode::kCorrupt);
  // Loads trust zstd's own content checksum; a full check also compares the stored CRC-32.
  EXPECT_TRUE(DecodeBlob(Codec::kZstdShuffle4, blob.data, blob.raw_size, blob.raw_crc32 ^ 1).ok());
  auto wrong_crc = DecodeBlob(Codec::kZstdShuffle4, blob.data, blob.raw_size, blob.raw_crc32 ^ 1,
                              /*verify_crc=*/true);
  EXPECT_EQ(wrong_crc.status().code(), StatusCode::kCorrupt);
  EXPECT_NE(wrong_crc.status().message().find("checksum"), std::string::npos);
  // A flipped byte anywhere in the frame is caught without the CRC pass.
  for (size_t at = 6; at < blob.data.size(); at += blob.data.size() / 7) {
    std::string damaged = blob.data;
    damaged[at] ^= 0x01;
    EXPECT_EQ(
        DecodeBlob(Codec::kZstdShuffle4, damaged, blob.raw_size, blob.raw_crc32).status().code(),
        StatusCode::kCorrupt)
        << "byte " << at;
  }
  auto raw_crc = DecodeBlob(Codec::kRaw, std::string(12, 'a'), 12, 0);
  EXPECT_EQ(raw_crc.status().code(), StatusCode::kCorrupt);  // raw blobs always check the CRC
  auto raw = DecodeBlob(Codec::kRaw, std::string(8, 'a'), 12, 0);
  EXPECT_EQ(raw.status().code(), StatusCode::kCorrupt);
  auto codec = DecodeBlob(static_cast<Codec>(17), blob.data, blob.raw_size, blob.raw_crc32);
  EXPECT_EQ(codec.status().code(), StatusCode::kCorrupt);
}

TEST(BlobCodecTest, TilesCoverTheGridOnceAndPasteBack) {
  common::GridGeometry g;
  g.size_x = 25;
  g.size_y = 12;
  const auto tiles = TilesOf(g, 10);
  ASSERT_EQ(tiles.size(), 6u);
  EXPECT_EQ(tiles[2].cells_x, 5);
  EXPECT_EQ(tiles[5].cells_y, 2);
  common::Layer layer(25, 12);
  for (int iy = 0; iy < 12; ++iy) {
    for (int ix = 0; ix < 25; ++ix) layer(ix, iy) = ix * 100.f + iy;
  }
  common::Layer copy = common::Layer::Constant(25, 12, NAN);
  for (const TileSpec& t : tiles) {
    const std::vector<float> cells = ExtractTile(layer, t);
    EXPECT_EQ(cells[0], layer(t.x0, t.y0));
    PasteTile(t, cells.data(), 0, 0, &copy);
  }
  EXPECT_TRUE(copy == layer);
  // A region touches only the tiles it overlaps, and pastes into a cropped layer.
  const auto some = TilesOf(g, 10, CellBox{12, 3, 18, 11});
  ASSERT_EQ(some.size(), 2u);
  common::Layer crop = common::Layer::Constant(6, 8, NAN);
  for (const TileSpec& t : some) PasteTile(t, ExtractTile(layer, t).data(), 12, 3, &crop);
  EXPECT_EQ(crop(0, 0), layer(12, 3));
  EXPECT_EQ(crop(5, 7), layer(17, 10));
  EXPECT_TRUE(TilesOf(g, 10, CellBox{30, 0, 40, 5}).empty());
}

// A terrace keeps its parts with their headings and verdicts; a part count over the limit is
// refused before anything is allocated.
TEST(BlobCodecTest, ATerraceRoundTripsWithItsParts) {
  common::ObstacleRegistry r;
  r.obstacles = {cairn::testing::SampleTerrace()};
  auto back = ParseRegistry(SerializeRegistry(r));
  ASSERT_TRUE(back.ok()) << back.status().ToString();
  ASSERT_EQ(back->obstacles.size(), 1u);
  const common::Obstacle& t = back->obstacles[0];
  EXPECT_EQ(t.kind, common::ObstacleKind::kTerrace);
  ASSERT_EQ(t.parts.size(), 2u);
  EXPECT_EQ(t.parts[1].kind, common::ObstacleKind::kStepUp);
  EXPECT_EQ(t.parts[1].heading_in_rad, 3.14159);
  EXPECT_EQ(t.parts[0].outline_m, r.obstacles[0].parts[0].outline_m);
  EXPECT_EQ(t.parts[1].verdicts, r.obstacles[0].parts[1].verdicts);
  std::string many(4, '\0');
  const uint32_t count = common::kMaxObstacleParts + 1;
  std::memcpy(&many[0], &count, 4);
  EXPECT_EQ(ParseParts(many).status().code(), StatusCode::kCorrupt);
  EXPECT_NE(ParseParts(many).status().message().find("parts"), std::string::npos);
}

TEST(BlobCodecTest, RegistryRoundTripsAndRefusesGarbage) {
  common::ObstacleRegistry r;
  r.map_version = 4;
  common::Obstacle o;
  o.id = 12;
  o.kind = common::ObstacleKind::kDitch;
  o.centroid_m = {1.25, -3.5};
  o.outline_m = {{0, 0}, {1, 0}, {1, 1}};
  o.depth_m = NAN;
  o.downhill_heading_rad = 0.5;
  o.verdicts = {{"rover", "h", false, "ditch 0.4 m > 0.3 m"}, {"tank", "k", true, ""}};
  r.obstacles = {o, o};
  r.obstacles[1].id = 13;
  const std::string bytes = SerializeRegistry(r);
  auto back = ParseRegistry(bytes);
  ASSERT_TRUE(back.ok()) << back.status().ToString();
  ASSERT_EQ(back->obstacles.size(), 2u);
  EXPECT_EQ(back->map_version, 4);
  EXPECT_EQ(back->obstacles[1].id, 13);
  EXPECT_EQ(back->obstacles[0].outline_m, o.outline_m);
  EXPECT_TRUE(std::isnan(back->obstacles[0].depth_m));
  EXPECT_EQ(back->obstacles[0].downhill_heading_rad, 0.5);
  EXPECT_EQ(back->obstacles[0].verdicts, o.verdicts);
  for (size_t cut : {size_t{0}, size_t{3}, bytes.size() / 2, bytes.size() - 1}) {
    EXPECT_EQ(ParseRegistry(bytes.substr(0, cut)).status().code(), StatusCode::kCorrupt) << cut;
  }
  EXPECT_EQ(ParseRegistry(bytes + "x").status().code(), StatusCode::kCorrupt);
}

TEST(NamesTest, RulesForNames) {
  for (const char* good : {"corridor", "lab-2", "map_1.v2", "A", "0"}) {
    EXPECT_TRUE(ValidateName("map name", good).ok()) << good;
  }
  for (const std::string& bad : std::vector<std::string>{"", ".", "..", "a..b", "_x", "a/b", "a b",
                                                         "é", "a\nb", std::string(65, 'x')}) {
    const common::Status s = ValidateName("map name", bad);
    EXPECT_EQ(s.code(), StatusCode::kInvalidArgument) << bad;
    EXPECT_NE(s.message().find("map name"), std::string::npos);
  }
  EXPECT_TRUE(ValidateLayerName("cost/pioneer3at").ok());
  EXPECT_TRUE(ValidateLayerName("elevation").ok());
  EXPECT_FALSE(ValidateLayerName("cost/").ok());
  EXPECT_FALSE(ValidateLayerName("/etc").ok());
  EXPECT_FALSE(ValidateLayerName("cost/../x").ok());
  EXPECT_TRUE(ValidatePlaceName("living room").ok());
  EXPECT_FALSE(ValidatePlaceName(" room").ok());
  EXPECT_FALSE(ValidatePlaceName("room;drop").ok());
}

// Issue 20 (found by fuzz_codecs under UBSan): an empty raw blob was copied with memcpy from and
// to null pointers (undefined behaviour even for 0 bytes). It decodes to nothing.
TEST(BlobCodecTest, AnEmptyRawBlobDecodesToNothing) {
  EXPECT_TRUE(DecodeBlobTo(Codec::kRaw, nullptr, 0, 0, 0, nullptr).ok());
  FloatRows rows;  // no place at all
  EXPECT_TRUE(DecodeFloatBlobRows(Codec::kRaw, nullptr, 0, 0, 0, 0, rows).ok());
  // Rows of no cells, of a blob of no cells (zstd, decoded whole into an empty buffer).
  const EncodedBlob empty = EncodeBlob(nullptr, 0, Codec::kZstd);
  float place = 1.f;
  rows.first = &place;
  rows.rows = 1;
  rows.cells_per_row = 0;
  EXPECT_TRUE(DecodeFloatBlobRows(Codec::kZstd, empty.data.data(), empty.data.size(), 0, 1,
                                  empty.raw_crc32, rows)
                  .ok());
  EXPECT_EQ(place, 1.f);
}

}  // namespace
}  // namespace cairn::mapstore
