#pragma once

#include <cstddef>
#include <cstdint>

/// @file
/// CRC-32 (zlib's polynomial): the checksum of map tiles on the bus and of blobs in the store.

namespace cairn::common {

/// CRC-32 of `size` bytes (any size: zlib is fed in 1 GiB pieces).
uint32_t Crc32(const void* data, size_t size);

}  // namespace cairn::common
