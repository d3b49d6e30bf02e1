#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "common/grid_map.h"
#include "common/status.h"
#include "mapstore/map_store.h"
#include "mapstore/parallel_for.h"
#include "mapstore/registry_codec.h"
#include "mapstore/tile_grid.h"

/// @file
/// How the map store keeps bytes: blobs compressed with zstd (float tiles byte-shuffled first,
/// which lets zstd find the repeated exponent bytes of smooth terrain), each with the CRC-32 of
/// its raw bytes, addressed by content. How a layer is cut into tiles is in tile_grid.h, the
/// registry's bytes in registry_codec.h and the thread helper in parallel_for.h (included here:
/// most users of the codec want them too).

namespace cairn::mapstore {

/// Stored codec of a blob (a column of the blobs table: never renumber).
enum class Codec : int {
  kRaw = 0,           ///< bytes as they are
  kZstd = 1,          ///< zstd frame
  kZstdShuffle4 = 2,  ///< 4-byte elements split into byte planes, then zstd
  /// Floats that are each a whole number in 0..254 or NaN (cost layers, counts, 0..100 layers):
  /// one byte per float (255 = NaN), then zstd. Lossless: chosen only when every float's bits
  /// come back unchanged (see FloatCodec).
  kZstdBytes = 3,
};

/// A blob ready to store.
struct EncodedBlob {
  Codec codec{Codec::kRaw};
  int64_t raw_size{0};
  uint32_t raw_crc32{0};
  std::string data;  ///< stored bytes
  /// StoredBlobCrc32 of the blob as stored: lets a reader check it without decoding it.
  uint32_t stored_crc32{0};
  /// Content address: the CRC-32 of the raw bytes, a second independent checksum (zstd's
  /// frame checksum, XXH64-based, for compressed blobs) and the raw size.
  std::string key;
};

/// CRC-32 of a blob row as stored: its bytes, then its codec (int32), raw size (int64) and raw
/// CRC-32 (uint32), little-endian. A damaged byte or header field changes it, so a reader can
/// check a stored blob without decompressing it.
uint32_t StoredBlobCrc32(int codec, int64_t raw_size, uint32_t raw_crc32, const void* data,
                         size_t size);

/// The codec for float cells: kZstdBytes when every cell is a whole number in 0..254 or the
/// product's NaN (bit for bit), else kZstdShuffle4.
Codec FloatCodec(const float* cells, size_t n);

/// Encodes raw bytes. kZstdShuffle4 needs a size that is a multiple of 4; kZstdBytes floats
/// FloatCodec accepts.
/// `raw_crc32`, when given, is the caller's CRC-32 of `raw` (a tile's declared checksum): it
/// saves a pass over the bytes.
/// @throws std::invalid_argument for a bad codec or size, std::runtime_error if zstd fails.
EncodedBlob EncodeBlob(const void* raw, size_t size, Codec codec, int zstd_level = 1,
                       std::optional<uint32_t> raw_crc32 = std::nullopt);
/// A zstd blob made by EncodeBlob elsewhere (a pushed tile's bytes), as EncodeBlob would have
/// returned it, without compressing again: its content address comes from the CRC-32 the sender
/// declared and the frame's own checksum. The caller vouches that the bytes decode to raw_size
/// bytes with that CRC (checked on receipt); kInvalidArgument for another codec or a frame
/// without a content checksum.
common::Result<EncodedBlob> AdoptEncodedBlob(Codec codec, std::string data, int64_t raw_size,
                                             uint32_t raw_crc32);
/// Decodes stored bytes into `out` (raw_size bytes) and verifies them: zstd's frame checksum
/// when the frame has one, and the CRC-32 of the raw bytes when it has none or `verify_crc`.
/// kCorrupt says what did not match. Thread-safe.
common::Status DecodeBlobTo(Codec codec, const char* data, size_t size, int64_t raw_size,
                            uint32_t raw_crc32, uint8_t* out, bool verify_crc = false);
/// Where DecodeFloatBlobRows writes: `rows` rows of `cells_per_row` floats, the first at
/// `first`, each `row_stride` floats after the previous (a tile's place in its layer).
struct FloatRows {
  float* first{nullptr};
  int64_t row_stride{0};
  int cells_per_row{0};
  int rows{0};
};
/// As DecodeBlobTo for a blob of `source_cells_x` × `source_cells_y` floats (x fastest), but
/// writes the top-left `out.cells_per_row` × `out.rows` of them into `out` (no more than the
/// source holds): a tile decodes straight into its layer, without a second copy. Verification
/// is that of DecodeBlobTo; on an error the cells of `out` are undefined. Thread-safe.
common::Status DecodeFloatBlobRows(Codec codec, const char* data, size_t size, int source_cells_x,
                                   int source_cells_y, uint32_t raw_crc32, const FloatRows& out,
                                   bool verify_crc = false);
/// As DecodeBlobTo, into a new string.
common::Result<std::string> DecodeBlob(Codec codec, const std::string& data, int64_t raw_size,
                                       uint32_t raw_crc32, bool verify_crc = false);

/// kOk when a stored tile's bytes decode to its size and checksums; kCorrupt saying what did
/// not match otherwise. Thread-safe.
common::Status CheckStoredTile(const StoredTile& tile);

}  // namespace cairn::mapstore
