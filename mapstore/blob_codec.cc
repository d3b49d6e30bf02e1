#include "mapstore/blob_codec.h"

#include <zlib.h>
#include <zstd.h>

#include "common/crc32.h"
#include "common/robot_profile.h"
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <cstring>
#include <exception>
#include <limits>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <thread>

namespace cairn::mapstore {

static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__,
              "blobs are stored little endian; a big-endian port needs byte swaps here");

namespace {

// Splits n 4-byte elements into 4 byte planes (and back).
void Shuffle4(const uint8_t* in, size_t n, uint8_t* out) {
  for (size_t i = 0; i < n; ++i) {
    out[i] = in[4 * i];
    out[n + i] = in[4 * i + 1];
    out[2 * n + i] = in[4 * i + 2];
    out[3 * n + i] = in[4 * i + 3];
  }
}

void Unshuffle4(const uint8_t* in, size_t n, uint8_t* out) {
  size_t i = 0;
#if defined(__SSE2__)
  // Interleave 16 elements at a time: bytes b0 b1 | b2 b3, then the two halves.
  for (; i + 16 <= n; i += 16) {
    const __m128i p0 = _mm_loadu_si128(reinterpret_cast<const __m128i*>(in + i));
    const __m128i p1 = _mm_loadu_si128(reinterpret_cast<const __m128i*>(in + n + i));
    const __m128i p2 = _mm_loadu_si128(reinterpret_cast<const __m128i*>(in + 2 * n + i));
    const __m128i p3 = _mm_loadu_si128(reinterpret_cast<const __m128i*>(in + 3 * n + i));
    const __m128i a_lo = _mm_unpacklo_epi8(p0, p1), a_hi = _mm_unpackhi_epi8(p0, p1);
    const __m128i b_lo = _mm_unpacklo_epi8(p2, p3), b_hi = _mm_unpackhi_epi8(p2, p3);
    __m128i* dst = reinterpret_cast<__m128i*>(out + 4 * i);
    _mm_storeu_si128(dst + 0, _mm_unpacklo_epi16(a_lo, b_lo));
    _mm_storeu_si128(dst + 1, _mm_unpackhi_epi16(a_lo, b_lo));
    _mm_storeu_si128(dst + 2, _mm_unpacklo_epi16(a_hi, b_hi));
    _mm_storeu_si128(dst + 3, _mm_unpackhi_epi16(a_hi, b_hi));
  }
#endif
  for (; i < n; ++i) {
    out[4 * i] = in[i];
    out[4 * i + 1] = in[n + i];
    out[4 * i + 2] = in[2 * n + i];
    out[4 * i + 3] = in[3 * n + i];
  }
}

// The byte codec: cell value k in 0..254 is byte k, the product's NaN (common::kUnknown) is
// byte 255. Only values whose float bits come back unchanged qualify (not -0, not another NaN).
constexpr uint8_t kByteUnknown = 255;

uint32_t FloatBits(float v) {
  uint32_t b;
  std::memcpy(&b, &v, 4);
  return b;
}

const std::array<uint32_t, 256>& ByteCodeBits() {
  static const std::array<uint32_t, 256> table = [] {
    std::array<uint32_t, 256> t{};
    for (int k = 0; k < 255; ++k) t[k] = FloatBits(static_cast<float>(k));
    t[kByteUnknown] = FloatBits(std::numeric_limits<float>::quiet_NaN());
    return t;
  }();
  return table;
}

// Writes the byte code of every float to out (when not null); false as soon as one has none.
bool ToByteCodes(const uint8_t* raw, size_t n, uint8_t* out) {
  const std::array<uint32_t, 256>& bits = ByteCodeBits();
  for (size_t i = 0; i < n; ++i) {
    uint32_t b;
    std::memcpy(&b, raw + 4 * i, 4);
    float v;
    std::memcpy(&v, &b, 4);
    uint8_t code;
    if (v >= 0.f && v <= 254.f) {
      code = static_cast<uint8_t>(v);
    } else {
      code = kByteUnknown;
    }
    if (bits[code] != b) return false;
    if (out != nullptr) out[i] = code;
  }
  return true;
}

// The float of every byte code: 0..254 convert exactly, 255 is the product's NaN. Sixteen codes
// per step (SSE2); the table does the rest.
void FromByteCodes(const uint8_t* codes, size_t n, uint8_t* out) {
  const std::array<uint32_t, 256>& bits = ByteCodeBits();
  const __m128i zero = _mm_setzero_si128();
  const __m128i unknown_code = _mm_set1_epi8(static_cast<char>(kByteUnknown));
  const __m128 unknown = _mm_castsi128_ps(_mm_set1_epi32(static_cast<int>(bits[kByteUnknown])));
  size_t i = 0;
  for (; i + 16 <= n; i += 16) {
    const __m128i c = _mm_loadu_si128(reinterpret_cast<const __m128i*>(codes + i));
    const __m128i is_unknown = _mm_cmpeq_epi8(c, unknown_code);
    const __m128i lo = _mm_unpacklo_epi8(c, zero), hi = _mm_unpackhi_epi8(c, zero);
    const __m128i unknown_lo = _mm_unpacklo_epi8(is_unknown, is_unknown);
    const __m128i unknown_hi = _mm_unpackhi_epi8(is_unknown, is_unknown);
    const __m128i values[4] = {_mm_unpacklo_epi16(lo, zero), _mm_unpackhi_epi16(lo, zero),
                               _mm_unpacklo_epi16(hi, zero), _mm_unpackhi_epi16(hi, zero)};
    const __m128i masks[4] = {
        _mm_unpacklo_epi16(unknown_lo, unknown_lo), _mm_unpackhi_epi16(unknown_lo, unknown_lo),
        _mm_unpacklo_epi16(unknown_hi, unknown_hi), _mm_unpackhi_epi16(unknown_hi, unknown_hi)};
    for (int k = 0; k < 4; ++k) {
      const __m128 value = _mm_cvtepi32_ps(values[k]);
      const __m128 mask = _mm_castsi128_ps(masks[k]);
      _mm_storeu_ps(reinterpret_cast<float*>(out + 4 * (i + 4 * k)),
                    _mm_or_ps(_mm_and_ps(mask, unknown), _mm_andnot_ps(mask, value)));
    }
  }
  for (; i < n; ++i) std::memcpy(out + 4 * i, &bits[codes[i]], 4);
}

std::string Hex32(uint32_t v) {
  char buf[16];
  std::snprintf(buf, sizeof(buf), "%08x", v);
  return buf;
}

}  // namespace

uint32_t StoredBlobCrc32(int codec, int64_t raw_size, uint32_t raw_crc32, const void* data,
                         size_t size) {
  uint8_t header[16];
  const int32_t codec32 = codec;
  std::memcpy(header, &codec32, 4);
  std::memcpy(header + 4, &raw_size, 8);
  std::memcpy(header + 12, &raw_crc32, 4);
  static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "the header is written little-endian");
  uLong crc = common::Crc32(data, size);
  crc = crc32(crc, header, sizeof(header));
  return static_cast<uint32_t>(crc);
}

namespace {

// One zstd context per thread: creating one per blob costs more than compressing a tile.
ZSTD_CCtx* ThreadCompressor() {
  thread_local std::unique_ptr<ZSTD_CCtx, size_t (*)(ZSTD_CCtx*)> ctx(ZSTD_createCCtx(),
                                                                      ZSTD_freeCCtx);
  return ctx.get();
}

ZSTD_DCtx* ThreadDecompressor() {
  thread_local std::unique_ptr<ZSTD_DCtx, size_t (*)(ZSTD_DCtx*)> ctx(ZSTD_createDCtx(),
                                                                      ZSTD_freeDCtx);
  return ctx.get();
}

// Whether a zstd frame carries a content checksum (RFC 8878: bit 2 of the frame header
// descriptor, the byte after the magic number).
bool HasContentChecksum(const char* frame, size_t size) {
  if (size < 5) return false;
  uint32_t magic = 0;
  std::memcpy(&magic, frame, 4);
  return magic == 0xFD2FB528u && (static_cast<uint8_t>(frame[4]) & 0x04) != 0;
}

std::vector<uint8_t>& ThreadScratch() {
  thread_local std::vector<uint8_t> scratch;
  return scratch;
}

}  // namespace

namespace {

// Bytes in the zstd frame of a float blob: one per float for the byte codec, else the raw size.
size_t FrameSize(Codec codec, int64_t raw_size) {
  return static_cast<size_t>(codec == Codec::kZstdBytes ? raw_size / 4 : raw_size);
}

// Decompresses a zstd frame of frame_size bytes into target; kCorrupt saying what did not match.
// zstd verifies the frame's content checksum, when it has one, on the way.
common::Status DecompressFrame(const char* data, size_t size, size_t frame_size, uint8_t* target) {
  const unsigned long long frame = ZSTD_getFrameContentSize(data, size);
  if (frame == ZSTD_CONTENTSIZE_ERROR || frame != static_cast<unsigned long long>(frame_size)) {
    return common::CorruptError("blob is not a zstd frame of " + std::to_string(frame_size) +
                                " bytes");
  }
  const size_t n = ZSTD_decompressDCtx(ThreadDecompressor(), target, frame_size, data, size);
  if (ZSTD_isError(n) || n != frame_size) {
    return common::CorruptError(std::string("blob does not decompress: ") +
                                (ZSTD_isError(n) ? ZSTD_getErrorName(n) : "short output"));
  }
  return common::Status::Ok();
}

}  // namespace

Codec FloatCodec(const float* cells, size_t n) {
  return ToByteCodes(reinterpret_cast<const uint8_t*>(cells), n, nullptr) ? Codec::kZstdBytes
                                                                          : Codec::kZstdShuffle4;
}

EncodedBlob EncodeBlob(const void* raw, size_t size, Codec codec, int zstd_level,
                       std::optional<uint32_t> raw_crc32) {
  EncodedBlob blob;
  blob.codec = codec;
  blob.raw_size = static_cast<int64_t>(size);
  blob.raw_crc32 = raw_crc32 ? *raw_crc32 : common::Crc32(raw, size);
  switch (codec) {
    case Codec::kRaw:
      blob.data.assign(static_cast<const char*>(raw), size);
      // Content address: both checksums of the bytes themselves.
      blob.key = Hex32(blob.raw_crc32) + "-" +
                 Hex32(static_cast<uint32_t>(common::Fnv1a64(raw, size))) + "-" +
                 std::to_string(size) + "r";
      blob.stored_crc32 = StoredBlobCrc32(static_cast<int>(codec), blob.raw_size, blob.raw_crc32,
                                          blob.data.data(), blob.data.size());
      return blob;
    case Codec::kZstd:
    case Codec::kZstdShuffle4:
    case Codec::kZstdBytes: {
      const void* src = raw;
      size_t src_size = size;
      if (codec == Codec::kZstdShuffle4) {
        if (size % 4 != 0) throw std::invalid_argument("shuffle4 needs a multiple of 4 bytes");
        std::vector<uint8_t>& shuffled = ThreadScratch();
        shuffled.resize(size);
        Shuffle4(static_cast<const uint8_t*>(raw), size / 4, shuffled.data());
        src = shuffled.data();
      } else if (codec == Codec::kZstdBytes) {
        std::vector<uint8_t>& codes = ThreadScratch();
        codes.resize(size / 4);
        if (size % 4 != 0 ||
            !ToByteCodes(static_cast<const uint8_t*>(raw), size / 4, codes.data())) {
          throw std::invalid_argument("the byte codec takes floats that are 0..254 or NaN only");
        }
        src = codes.data();
        src_size = size / 4;
      }
      // The frame carries zstd's own content checksum (XXH64): it is verified on every
      // decompression and, with the CRC-32, makes the content address.
      ZSTD_CCtx* ctx = ThreadCompressor();
      ZSTD_CCtx_reset(ctx, ZSTD_reset_session_and_parameters);
      ZSTD_CCtx_setParameter(ctx, ZSTD_c_compressionLevel, zstd_level);
      ZSTD_CCtx_setParameter(ctx, ZSTD_c_checksumFlag, 1);
      blob.data.resize(ZSTD_compressBound(src_size));
      const size_t n = ZSTD_compress2(ctx, blob.data.data(), blob.data.size(), src, src_size);
      if (ZSTD_isError(n) || n < 4) {
        throw std::runtime_error(std::string("zstd compression failed: ") +
                                 (ZSTD_isError(n) ? ZSTD_getErrorName(n) : "short frame"));
      }
      blob.data.resize(n);
      uint32_t frame_checksum = 0;
      std::memcpy(&frame_checksum, blob.data.data() + n - 4, 4);
      blob.key =
          Hex32(blob.raw_crc32) + "-" + Hex32(frame_checksum) + "-" + std::to_string(size) + "z";
      blob.stored_crc32 = StoredBlobCrc32(static_cast<int>(codec), blob.raw_size, blob.raw_crc32,
                                          blob.data.data(), blob.data.size());
      return blob;
    }
    default:
      throw std::invalid_argument("unknown codec " + std::to_string(static_cast<int>(codec)));
  }
}

common::Result<EncodedBlob> AdoptEncodedBlob(Codec codec, std::string data, int64_t raw_size,
                                             uint32_t raw_crc32) {
  if (codec != Codec::kZstd && codec != Codec::kZstdShuffle4 && codec != Codec::kZstdBytes) {
    return common::InvalidArgumentError("only zstd blobs are adopted, not codec " +
                                        std::to_string(static_cast<int>(codec)));
  }
  if (!HasContentChecksum(data.data(), data.size()) || data.size() < 9 || raw_size < 0) {
    return common::InvalidArgumentError("the blob is no zstd frame with a content checksum");
  }
  EncodedBlob blob;
  blob.codec = codec;
  blob.raw_size = raw_size;
  blob.raw_crc32 = raw_crc32;
  uint32_t frame_checksum = 0;
  std::memcpy(&frame_checksum, data.data() + data.size() - 4, 4);
  blob.key = Hex32(raw_crc32) + "-" + Hex32(frame_checksum) + "-" + std::to_string(raw_size) + "z";
  blob.data = std::move(data);
  blob.stored_crc32 = StoredBlobCrc32(static_cast<int>(codec), raw_size, raw_crc32,
                                      blob.data.data(), blob.data.size());
  return blob;
}

common::Status DecodeBlobTo(Codec codec, const char* data, size_t size, int64_t raw_size,
                            uint32_t raw_crc32, uint8_t* out, bool verify_crc) {
  if (raw_size < 0) return common::CorruptError("blob has a negative size");
  switch (codec) {
    case Codec::kRaw:
      if (size != static_cast<size_t>(raw_size)) {
        return common::CorruptError("blob holds " + std::to_string(size) + " bytes, expected " +
                                    std::to_string(raw_size));
      }
      if (size > 0) std::memcpy(out, data, size);  // null pointers when empty
      break;
    case Codec::kZstd:
    case Codec::kZstdShuffle4:
    case Codec::kZstdBytes: {
      if (codec != Codec::kZstd && raw_size % 4 != 0) {
        return common::CorruptError("float blob size not a multiple of 4");
      }
      const size_t n = FrameSize(codec, raw_size);
      uint8_t* target = out;
      if (codec != Codec::kZstd) {
        std::vector<uint8_t>& scratch = ThreadScratch();
        scratch.resize(n);
        target = scratch.data();
      }
      const common::Status s = DecompressFrame(data, size, n, target);
      if (!s.ok()) return s;
      if (codec == Codec::kZstdShuffle4) Unshuffle4(target, n / 4, out);
      if (codec == Codec::kZstdBytes) FromByteCodes(target, n, out);
      // zstd verified its content checksum (XXH64) while decompressing: that covers damage to
      // the stored bytes, so the CRC-32 pass is only needed for frames without one.
      if (!verify_crc && HasContentChecksum(data, size)) return common::Status::Ok();
      break;
    }
    default:
      return common::CorruptError("blob has unknown codec " +
                                  std::to_string(static_cast<int>(codec)));
  }
  const uint32_t crc = common::Crc32(out, static_cast<size_t>(raw_size));
  if (crc != raw_crc32) {
    return common::CorruptError("blob checksum mismatch (crc32 " + Hex32(crc) + ", stored " +
                                Hex32(raw_crc32) + ")");
  }
  return common::Status::Ok();
}

common::Status DecodeFloatBlobRows(Codec codec, const char* data, size_t size, int source_cells_x,
                                   int source_cells_y, uint32_t raw_crc32, const FloatRows& out,
                                   bool verify_crc) {
  if (source_cells_x < 0 || source_cells_y < 0 || out.cells_per_row < 0 || out.rows < 0 ||
      out.cells_per_row > source_cells_x || out.rows > source_cells_y ||
      (out.rows > 0 && out.first == nullptr) ||
      (out.rows > 1 && out.row_stride < out.cells_per_row)) {
    return common::InvalidArgumentError("float rows outside the blob's cells");
  }
  const size_t cells = static_cast<size_t>(source_cells_x) * static_cast<size_t>(source_cells_y);
  const int64_t raw_size = static_cast<int64_t>(cells * sizeof(float));
  if (codec == Codec::kZstdBytes && !verify_crc && HasContentChecksum(data, size)) {
    // The common case (cost and class layers): one byte code per cell, expanded row by row.
    std::vector<uint8_t>& codes = ThreadScratch();
    codes.resize(cells);
    const common::Status s = DecompressFrame(data, size, cells, codes.data());
    if (!s.ok()) return s;
    for (int y = 0; y < out.rows; ++y) {
      FromByteCodes(codes.data() + static_cast<size_t>(y) * source_cells_x,
                    static_cast<size_t>(out.cells_per_row),
                    reinterpret_cast<uint8_t*>(out.first + y * out.row_stride));
    }
    return common::Status::Ok();
  }
  // Every other codec decodes (and is verified) whole, then its rows are copied.
  thread_local std::vector<float> whole;
  whole.resize(cells);
  const common::Status s = DecodeBlobTo(codec, data, size, raw_size, raw_crc32,
                                        reinterpret_cast<uint8_t*>(whole.data()), verify_crc);
  if (!s.ok()) return s;
  if (out.cells_per_row <= 0) return common::Status::Ok();  // nothing to copy (no null memcpy)
  for (int y = 0; y < out.rows; ++y) {
    std::memcpy(out.first + y * out.row_stride,
                whole.data() + static_cast<size_t>(y) * source_cells_x,
                sizeof(float) * static_cast<size_t>(out.cells_per_row));
  }
  return common::Status::Ok();
}

common::Result<std::string> DecodeBlob(Codec codec, const std::string& data, int64_t raw_size,
                                       uint32_t raw_crc32, bool verify_crc) {
  if (raw_size < 0 || raw_size > (int64_t{1} << 32)) {
    return common::CorruptError("blob has an impossible size " + std::to_string(raw_size));
  }
  std::string out(static_cast<size_t>(raw_size), '\0');
  common::Status s = DecodeBlobTo(codec, data.data(), data.size(), raw_size, raw_crc32,
                                  reinterpret_cast<uint8_t*>(out.data()), verify_crc);
  if (!s.ok()) return s;
  return out;
}

common::Status CheckStoredTile(const StoredTile& tile) {
  if (tile.cells_x <= 0 || tile.cells_y <= 0) {
    return common::CorruptError("a stored tile with no cells");
  }
  const int64_t raw_size =
      int64_t{tile.cells_x} * tile.cells_y * static_cast<int64_t>(sizeof(float));
  if (tile.stored_crc32) {
    // The row's own checksum covers its bytes and header: nothing needs decompressing.
    const uint32_t crc =
        StoredBlobCrc32(tile.codec, raw_size, tile.raw_crc32, tile.data.data(), tile.data.size());
    if (crc != *tile.stored_crc32) {
      return common::CorruptError("stored blob checksum mismatch (crc32 " + Hex32(crc) +
                                  ", recorded " + Hex32(*tile.stored_crc32) + ")");
    }
    return common::Status::Ok();
  }
  const Codec codec = static_cast<Codec>(tile.codec);
  const bool zstd =
      codec == Codec::kZstd || codec == Codec::kZstdShuffle4 || codec == Codec::kZstdBytes;
  if (zstd && HasContentChecksum(tile.data.data(), tile.data.size())) {
    // zstd checks its frame against its content checksum while decompressing: the frame alone
    // is decoded, not turned back into floats.
    std::vector<uint8_t>& scratch = ThreadScratch();
    scratch.resize(FrameSize(codec, raw_size));
    return DecompressFrame(tile.data.data(), tile.data.size(), scratch.size(), scratch.data());
  }
  thread_local std::vector<uint8_t> out;
  out.resize(static_cast<size_t>(raw_size));
  return DecodeBlobTo(codec, tile.data.data(), tile.data.size(), raw_size, tile.raw_crc32,
                      out.data());
}

}  // namespace cairn::mapstore
