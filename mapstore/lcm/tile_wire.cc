#include "mapstore/lcm/tile_wire.h"

#include <algorithm>
#include <chrono>
#include <cstring>
#include <exception>
#include <map>
#include <set>
#include <thread>
#include <tuple>

#include <sys/prctl.h>

#include "mapstore/blob_codec.h"

namespace cairn::mapstore {
namespace {

// The message without its cells; its encoding ends with num_cells, which is patched.
cairn::lcmt_grid_tile Header(const cairn::lcmt_grid_tile& t) {
  cairn::lcmt_grid_tile h{};
  h.utime = t.utime;
  h.robot = t.robot;
  h.map_name = t.map_name;
  h.layer = t.layer;
  h.layer_version = t.layer_version;
  h.tile_version = t.tile_version;
  h.resolution_m = t.resolution_m;
  h.origin_x_m = t.origin_x_m;
  h.origin_y_m = t.origin_y_m;
  h.origin_yaw_rad = t.origin_yaw_rad;
  h.layer_size_x = t.layer_size_x;
  h.layer_size_y = t.layer_size_y;
  h.tile_size = t.tile_size;
  h.tile_ix = t.tile_ix;
  h.tile_iy = t.tile_iy;
  h.cells_x = t.cells_x;
  h.cells_y = t.cells_y;
  h.checksum = t.checksum;
  h.encoding = t.encoding;
  h.num_bytes = t.num_bytes;
  h.bytes = t.bytes;
  h.num_cells = 0;
  return h;
}

void Generated(const cairn::lcmt_grid_tile& tile, std::vector<uint8_t>* out) {
  out->resize(static_cast<size_t>(tile.getEncodedSize()));
  tile.encode(out->data(), 0, static_cast<int>(out->size()));
}

void Fast(const cairn::lcmt_grid_tile& tile, std::vector<uint8_t>* out) {
  const cairn::lcmt_grid_tile head = Header(tile);
  const size_t head_size = static_cast<size_t>(head.getEncodedSize());
  const size_t cells = tile.data.size();
  out->resize(head_size + 4 * cells);
  head.encode(out->data(), 0, static_cast<int>(head_size));
  const uint32_t n = __builtin_bswap32(static_cast<uint32_t>(tile.num_cells));
  std::memcpy(out->data() + head_size - 4, &n, 4);
  uint8_t* dst = out->data() + head_size;
  for (size_t i = 0; i < cells; ++i) {
    uint32_t v;
    std::memcpy(&v, &tile.data[i], 4);
    v = __builtin_bswap32(v);
    std::memcpy(dst + 4 * i, &v, 4);
  }
}

// Whether the fast path writes the generated encoder's bytes (checked once).
bool FastPathMatches() {
  static const bool matches = [] {
    cairn::lcmt_grid_tile t{};
    t.utime = 123456789;
    t.robot = "r";
    t.map_name = "7/m";
    t.layer = "cost/x";
    t.layer_version = 3;
    t.tile_version = 2;
    t.resolution_m = 0.2;
    t.origin_x_m = -1.5;
    t.origin_y_m = 2.25;
    t.origin_yaw_rad = 0.3;
    t.layer_size_x = 5;
    t.layer_size_y = 3;
    t.tile_size = 4;
    t.tile_ix = 1;
    t.tile_iy = 0;
    t.cells_x = 1;
    t.cells_y = 3;
    t.checksum = 0x1234abcd;
    t.encoding = 0;
    t.num_bytes = 2;
    t.bytes = {7, 9};
    t.num_cells = 3;
    t.data = {1.5f, -0.f, 1e-30f};
    std::vector<uint8_t> a, b;
    Generated(t, &a);
    Fast(t, &b);
    return a == b;
  }();
  return matches;
}

}  // namespace

int8_t WireEncoding(Codec codec) {
  using T = cairn::lcmt_grid_tile;
  switch (codec) {
    case Codec::kZstdShuffle4:
      return T::ENCODING_ZSTD_SHUFFLE4;
    case Codec::kZstdBytes:
      return T::ENCODING_ZSTD_BYTES;
    default:
      return T::ENCODING_FLOAT32;
  }
}

std::optional<Codec> CodecOfEncoding(int8_t encoding) {
  using T = cairn::lcmt_grid_tile;
  if (encoding == T::ENCODING_ZSTD_SHUFFLE4) return Codec::kZstdShuffle4;
  if (encoding == T::ENCODING_ZSTD_BYTES) return Codec::kZstdBytes;
  return std::nullopt;
}

void EncodeTile(const cairn::lcmt_grid_tile& tile, std::vector<uint8_t>* out) {
  // A compressed tile has no cells to swap: the generated encoder copies its bytes in one go.
  if (tile.num_cells > 0 && static_cast<size_t>(tile.num_cells) == tile.data.size() &&
      tile.num_bytes >= 0 && static_cast<size_t>(tile.num_bytes) == tile.bytes.size() &&
      FastPathMatches()) {
    Fast(tile, out);
  } else {
    Generated(tile, out);
  }
}

bool CompressTile(cairn::lcmt_grid_tile* tile, int zstd_level) {
  using T = cairn::lcmt_grid_tile;
  if (tile->encoding != T::ENCODING_FLOAT32 || tile->data.empty() ||
      static_cast<size_t>(tile->num_cells) != tile->data.size()) {
    return false;
  }
  EncodedBlob blob;
  try {
    blob = EncodeBlob(tile->data.data(), tile->data.size() * sizeof(float),
                      FloatCodec(tile->data.data(), tile->data.size()), zstd_level,
                      static_cast<uint32_t>(tile->checksum));
  } catch (const std::exception&) {
    return false;  // zstd failed (out of memory): the floats travel as they are
  }
  if (blob.data.size() >= tile->data.size() * sizeof(float)) {
    return false;  // incompressible: the floats travel as they are
  }
  tile->bytes.assign(blob.data.begin(), blob.data.end());
  tile->num_bytes = static_cast<int32_t>(tile->bytes.size());
  tile->encoding = WireEncoding(blob.codec);
  tile->data.clear();
  tile->data.shrink_to_fit();
  tile->num_cells = 0;
  return true;
}

namespace {

// The codec of a compressed tile whose sizes are sane; kInvalidArgument otherwise.
common::Result<Codec> CompressedTileCodec(const cairn::lcmt_grid_tile& tile) {
  const std::optional<Codec> codec = CodecOfEncoding(tile.encoding);
  if (!codec) {
    return common::InvalidArgumentError("tile encoding " + std::to_string(tile.encoding) +
                                        " is not a compressed one");
  }
  if (tile.cells_x <= 0 || tile.cells_y <= 0 || tile.cells_x > 4096 || tile.cells_y > 4096 ||
      static_cast<size_t>(tile.num_bytes) != tile.bytes.size()) {
    return common::InvalidArgumentError("compressed tile with a bad size");
  }
  return *codec;
}

// Threads for decoding n tiles: at most `threads`, and one per 4 tiles.
int DecodeWorkers(size_t n, int threads) {
  constexpr size_t kTilesPerThread = 4;
  return static_cast<int>(
      std::min<size_t>(static_cast<size_t>(std::max(1, threads)), n / kTilesPerThread + 1));
}

// Decodes a compressed tile into its reserved place.
bool DecodeIntoSlot(const cairn::lcmt_grid_tile& tile,
                    const runtime::LayerAssembler::TileSlot& slot) {
  const common::Result<Codec> codec = CompressedTileCodec(tile);
  if (!codec.ok()) return false;
  FloatRows rows;
  rows.first = slot.first;
  rows.row_stride = slot.row_stride;
  rows.cells_per_row = slot.cells_x;
  rows.rows = slot.cells_y;
  return DecodeFloatBlobRows(*codec, reinterpret_cast<const char*>(tile.bytes.data()),
                             tile.bytes.size(), tile.cells_x, tile.cells_y,
                             static_cast<uint32_t>(tile.checksum), rows)
      .ok();
}

}  // namespace

common::Status DecodeTileCells(const cairn::lcmt_grid_tile& tile, std::vector<float>* cells,
                               bool verify_checksum) {
  const common::Result<Codec> codec = CompressedTileCodec(tile);
  if (!codec.ok()) return codec.status();
  const size_t n = static_cast<size_t>(tile.cells_x) * tile.cells_y;
  cells->resize(n);
  return DecodeBlobTo(*codec, reinterpret_cast<const char*>(tile.bytes.data()), tile.bytes.size(),
                      static_cast<int64_t>(n * sizeof(float)), static_cast<uint32_t>(tile.checksum),
                      reinterpret_cast<uint8_t*>(cells->data()), verify_checksum);
}

common::Status DecompressTile(cairn::lcmt_grid_tile* tile, bool verify_checksum) {
  using T = cairn::lcmt_grid_tile;
  if (tile->encoding == T::ENCODING_FLOAT32) return common::Status::Ok();
  std::vector<float> data;
  const common::Status s = DecodeTileCells(*tile, &data, verify_checksum);
  if (!s.ok()) return s;
  tile->num_cells = static_cast<int32_t>(data.size());
  tile->data = std::move(data);
  tile->encoding = T::ENCODING_FLOAT32;
  tile->bytes.clear();
  tile->num_bytes = 0;
  return common::Status::Ok();
}

bool PublishTile(lcm::LCM& lcm, const std::string& channel, const cairn::lcmt_grid_tile& tile) {
  thread_local std::vector<uint8_t> buffer;
  EncodeTile(tile, &buffer);
  return lcm.publish(channel, buffer.data(), static_cast<unsigned>(buffer.size())) == 0;
}

int64_t TilePayloadBytes(const cairn::lcmt_grid_tile& tile) {
  return tile.encoding == cairn::lcmt_grid_tile::ENCODING_FLOAT32
             ? static_cast<int64_t>(tile.data.size() * sizeof(float))
             : static_cast<int64_t>(tile.bytes.size());
}

void DecodeTiles(const std::vector<cairn::lcmt_grid_tile>& tiles, const std::string& map_name,
                 int threads, std::vector<std::vector<float>>* cells, std::vector<char>* ok) {
  const size_t n = tiles.size();
  if (cells->size() < n) cells->resize(n);
  for (std::vector<float>& buffer : *cells) {
    if (buffer.capacity() > kKeptBufferCells) std::vector<float>().swap(buffer);
  }
  // Which tiles the batch's budget of decoded cells admits, in order.
  std::vector<char> admitted(n, 0);
  int64_t budget = kMaxBatchDecodedCells;
  for (size_t i = 0; i < n; ++i) {
    const int64_t claimed = int64_t{std::max(0, tiles[i].cells_x)} * std::max(0, tiles[i].cells_y);
    if (claimed > budget) continue;
    budget -= claimed;
    admitted[i] = 1;
  }
  ok->assign(n, 0);
  ParallelFor(n, DecodeWorkers(n, threads), [&](size_t i) {
    const cairn::lcmt_grid_tile& tile = tiles[i];
    (*ok)[i] = admitted[i] && tile.encoding != cairn::lcmt_grid_tile::ENCODING_FLOAT32 &&
               tile.map_name == map_name && DecodeTileCells(tile, &(*cells)[i]).ok();
  });
}

bool AssembleTile(const cairn::lcmt_grid_tile& tile, const std::string& map_name,
                  runtime::LayerAssembler* assembler) {
  if (tile.map_name != map_name) return false;
  if (tile.encoding == cairn::lcmt_grid_tile::ENCODING_FLOAT32) return assembler->OnTile(tile);
  const auto slot = assembler->BeginTile(tile);
  if (!slot) return false;
  if (slot->first == nullptr) return true;  // older than the tile held there
  const bool ok = DecodeIntoSlot(tile, *slot);
  assembler->EndTile(tile, ok);
  return ok;
}

int AssembleTiles(const std::vector<cairn::lcmt_grid_tile>& tiles, const std::string& map_name,
                  int threads, runtime::LayerAssembler* assembler) {
  using Tile = cairn::lcmt_grid_tile;
  struct Job {
    const Tile* tile;
    runtime::LayerAssembler::TileSlot slot;
    bool ok{false};
  };
  int held = 0;
  std::vector<Job> jobs;
  jobs.reserve(tiles.size());
  // A tile whose place another tile of the batch already took, a tile whose layer changed grid
  // within the batch (which moves the layer) and a float tile wait for the parallel pass.
  std::vector<const Tile*> later;
  std::set<std::tuple<std::string, int, int>> places;
  std::map<std::string, std::tuple<double, double, double, double, int, int, int>> grids;
  for (const Tile& tile : tiles) {
    if (tile.map_name != map_name) continue;
    if (tile.encoding == Tile::ENCODING_FLOAT32) {
      later.push_back(&tile);  // it could move its layer under the slots taken
      continue;
    }
    const auto grid =
        std::make_tuple(tile.resolution_m, tile.origin_x_m, tile.origin_y_m, tile.origin_yaw_rad,
                        tile.layer_size_x, tile.layer_size_y, tile.tile_size);
    const auto [g, new_layer] = grids.emplace(tile.layer, grid);
    if ((!new_layer && g->second != grid) ||
        !places.emplace(tile.layer, tile.tile_ix, tile.tile_iy).second) {
      later.push_back(&tile);
      continue;
    }
    const auto slot = assembler->BeginTile(tile);
    if (!slot) continue;
    if (slot->first == nullptr) {
      ++held;  // older than the tile held there
      continue;
    }
    jobs.push_back(Job{&tile, *slot});
  }
  ParallelFor(jobs.size(), DecodeWorkers(jobs.size(), threads),
              [&](size_t i) { jobs[i].ok = DecodeIntoSlot(*jobs[i].tile, jobs[i].slot); });
  for (const Job& job : jobs) {
    assembler->EndTile(*job.tile, job.ok);
    held += job.ok ? 1 : 0;
  }
  for (const Tile* tile : later) held += AssembleTile(*tile, map_name, assembler) ? 1 : 0;
  return held;
}

void PacingPause(double ms) {
  thread_local const bool tight_timer = prctl(PR_SET_TIMERSLACK, 1UL, 0, 0, 0) == 0;
  (void)tight_timer;
  if (ms > 0) std::this_thread::sleep_for(std::chrono::duration<double, std::milli>(ms));
}

}  // namespace cairn::mapstore
