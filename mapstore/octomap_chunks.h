#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "mapstore/map_store.h"

/// @file
/// An OctoMap tree travels in chunks (a bus message stays under about 256 KB): each chunk names
/// the tree's version, its place among `chunk_count` chunks, the tree's total size and the
/// CRC-32 of the whole tree. Core terms of lcmt_octomap (the conversions live in
/// mapstore/lcm/mapstore_conversions.h).

namespace cairn::mapstore {

/// One chunk; `data` is borrowed (from the message it came in, or the tree it was cut from).
struct OctomapChunk {
  int64_t version{0};
  int32_t chunk_index{0};
  int32_t chunk_count{0};
  int64_t total_bytes{0};
  uint32_t checksum{0};  ///< CRC-32 of the whole tree's bytes
  bool binary{true};
  double resolution_m{0.0};
  const char* data{nullptr};
  size_t size{0};
};

/// Bytes of one chunk a store sends.
inline constexpr size_t kOctomapChunkBytes = 192 * 1024;

/// Cuts a tree into chunks of at most `chunk_bytes` bytes (one chunk for an empty tree), all of
/// version 1. The chunks borrow `octomap.bytes`.
std::vector<OctomapChunk> SplitOctomap(const OctomapData& octomap,
                                       size_t chunk_bytes = kOctomapChunkBytes);

/// Reassembles the chunks of one tree; a chunk of another version or count starts over.
/// Chunks come from the bus: what they make it hold is bounded by the tree size they declare,
/// itself at most kMaxTotalBytes.
class OctomapAssembler {
 public:
  /// Largest tree taken (a site's binary tree at 5 cm is tens of MB).
  static constexpr int64_t kMaxTotalBytes = int64_t{512} << 20;
  /// Most chunks a tree may come in (a store's chunks are 192 KB: 2,731 for the largest tree).
  static constexpr int32_t kMaxChunks = 65536;

  /// Keeps a chunk (copying its bytes). False, and nothing held changes, for one that cannot be
  /// a sender's: an index outside its count, a count or size beyond the limits, a size that
  /// disagrees with the tree's (its bytes and those held would exceed the declared total), or a
  /// total or checksum that disagrees with the other chunks of its version. The tree is put
  /// together (and checked) when its last chunk arrives.
  bool Add(const OctomapChunk& chunk);
  /// The whole tree once every chunk arrived and the checksum holds.
  const std::optional<OctomapData>& complete() const { return complete_; }
  /// Bytes held: the chunks, and the whole tree once complete.
  int64_t held_bytes() const {
    return held_bytes_ + (complete_ ? static_cast<int64_t>(complete_->bytes.size()) : 0);
  }

 private:
  /// The tree of the chunks held when they are all there and hold together.
  std::optional<OctomapData> Assemble() const;

  int64_t version_{0};
  int32_t chunk_count_{0};
  int64_t total_bytes_{0};
  uint32_t checksum_{0};
  bool binary_{true};
  double resolution_m_{0.0};
  std::map<int32_t, std::string> chunks_;
  int64_t held_bytes_{0};  // of chunks_
  std::optional<OctomapData> complete_;
};

}  // namespace cairn::mapstore
