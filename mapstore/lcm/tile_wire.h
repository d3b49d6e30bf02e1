#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "cairn/lcmt_grid_tile.hpp"

#include "common/status.h"
#include "mapstore/blob_codec.h"
#include "services/runtime/layer_assembler.h"
#include "services/runtime/tiler.h"

/// @file
/// Fast publishing of grid tiles. lcmt_grid_tile::encode byte-swaps its cells one call at a time;
/// a map of four 1000 x 1000 layers spends more time there than in the database. The encoding
/// here writes the same bytes (the cells are the last field of the message) with one swap loop,
/// after checking once, at first use, that it matches the generated encoder (if it ever does
/// not, the generated one is used).

namespace cairn::mapstore {

/// Encodes a tile exactly as lcmt_grid_tile::encode does.
void EncodeTile(const cairn::lcmt_grid_tile& tile, std::vector<uint8_t>* out);

/// The wire encoding of a stored blob codec: ENCODING_ZSTD_SHUFFLE4 and ENCODING_ZSTD_BYTES carry
/// the blob's bytes as they are; any other codec travels as floats (ENCODING_FLOAT32).
int8_t WireEncoding(Codec codec);
/// The blob codec of a compressed wire encoding; nullopt for floats or an unknown encoding.
std::optional<Codec> CodecOfEncoding(int8_t encoding);

/// Compresses a float tile in place with the store's own blob codec (FloatCodec: bytes for whole
/// numbers 0..254 and NaN, else shuffled floats); false, and the tile unchanged, when it is not
/// a float tile or would not get smaller. The tile's checksum stands for its cells (it is not
/// computed again).
bool CompressTile(cairn::lcmt_grid_tile* tile, int zstd_level = 1);

/// The cells of a compressed tile, checked by zstd's frame checksum and, with
/// `verify_checksum` (or a frame without one), against the tile's checksum. kInvalidArgument for
/// a float tile, an unknown encoding or a bad size, kCorrupt for damaged bytes.
common::Status DecodeTileCells(const cairn::lcmt_grid_tile& tile, std::vector<float>* cells,
                               bool verify_checksum = false);

/// Turns a compressed tile back into a float tile in place, checking zstd's frame checksum
/// and, with `verify_checksum`, the float bytes against the tile's checksum; a float tile is
/// left as it is. kInvalidArgument for an unknown encoding or a bad size, kCorrupt for damaged
/// bytes.
common::Status DecompressTile(cairn::lcmt_grid_tile* tile, bool verify_checksum = true);

/// Decodes the compressed tiles of `tiles` that carry `map_name`, on up to `threads` threads
/// (one per 4 tiles at the most), into (*cells)[i], buffers kept between calls; (*ok)[i] says
/// tile i decoded. Float tiles and tiles of another map are left alone (ok false). A batch
/// decodes at most kMaxBatchDecodedCells cells (a few bytes of zstd can claim 4096² cells each):
/// the tiles beyond are refused (ok false), and buffers over kKeptBufferCells are released
/// before the batch, so what a batch makes the receiver hold stays bounded.
inline constexpr int64_t kMaxBatchDecodedCells = int64_t{4096} * 4096;
inline constexpr size_t kKeptBufferCells = size_t{1} << 20;
void DecodeTiles(const std::vector<cairn::lcmt_grid_tile>& tiles, const std::string& map_name,
                 int threads, std::vector<std::vector<float>>* cells, std::vector<char>* ok);

/// Decodes the compressed tiles of `tiles` that carry `map_name` straight into their places in
/// `assembler`'s layers (LayerAssembler::BeginTile: no buffer, no second copy), on up to
/// `threads` threads (one per 4 tiles at the most); float tiles go through OnTile. A tile that
/// does not decode is not held (a resend asks for it). Returns how many tiles are held.
int AssembleTiles(const std::vector<cairn::lcmt_grid_tile>& tiles, const std::string& map_name,
                  int threads, runtime::LayerAssembler* assembler);
/// AssembleTiles for one tile, on the calling thread; whether it is held.
bool AssembleTile(const cairn::lcmt_grid_tile& tile, const std::string& map_name,
                  runtime::LayerAssembler* assembler);

/// Sleeps `ms` between two bursts of a paced send. The pauses are about a tenth of a
/// millisecond, so the calling thread's timer slack is set to 1 us first (the kernel's default
/// 50 us would make each half as long again).
void PacingPause(double ms);

/// Encodes and publishes a tile; false when LCM refuses it.
bool PublishTile(lcm::LCM& lcm, const std::string& channel, const cairn::lcmt_grid_tile& tile);

/// Bytes of a tile's cells on the bus (its floats, or its encoded bytes): what pacing counts.
int64_t TilePayloadBytes(const cairn::lcmt_grid_tile& tile);

}  // namespace cairn::mapstore
