#include "mapstore/octomap_chunks.h"

#include <algorithm>

#include "common/crc32.h"

namespace cairn::mapstore {

std::vector<OctomapChunk> SplitOctomap(const OctomapData& octomap, size_t chunk_bytes) {
  chunk_bytes = std::max<size_t>(1, chunk_bytes);
  const size_t total = octomap.bytes.size();
  const int32_t count =
      static_cast<int32_t>(std::max<size_t>(1, (total + chunk_bytes - 1) / chunk_bytes));
  const uint32_t crc = common::Crc32(octomap.bytes.data(), total);
  std::vector<OctomapChunk> out;
  out.reserve(count);
  for (int32_t i = 0; i < count; ++i) {
    OctomapChunk c;
    c.version = 1;
    c.chunk_index = i;
    c.chunk_count = count;
    c.total_bytes = static_cast<int64_t>(total);
    c.checksum = crc;
    c.binary = octomap.binary;
    c.resolution_m = octomap.resolution_m;
    const size_t begin = std::min(total, static_cast<size_t>(i) * chunk_bytes);
    c.data = octomap.bytes.data() + begin;
    c.size = std::min(total, begin + chunk_bytes) - begin;
    out.push_back(c);
  }
  return out;
}

bool OctomapAssembler::Add(const OctomapChunk& c) {
  if (c.chunk_count <= 0 || c.chunk_count > kMaxChunks || c.chunk_index < 0 ||
      c.chunk_index >= c.chunk_count || c.total_bytes < 0 || c.total_bytes > kMaxTotalBytes ||
      static_cast<int64_t>(c.size) > c.total_bytes || (c.size > 0 && c.data == nullptr)) {
    return false;
  }
  const bool same_tree = !chunks_.empty() && c.version == version_ && c.chunk_count == chunk_count_;
  if (same_tree && (c.total_bytes != total_bytes_ || c.checksum != checksum_)) return false;
  if (same_tree) {
    auto held = chunks_.find(c.chunk_index);
    const int64_t replaced = held == chunks_.end() ? 0 : static_cast<int64_t>(held->second.size());
    if (held_bytes_ - replaced + static_cast<int64_t>(c.size) > total_bytes_) return false;
    held_bytes_ -= replaced;
  } else {
    chunks_.clear();
    held_bytes_ = 0;
    version_ = c.version;
    chunk_count_ = c.chunk_count;
    total_bytes_ = c.total_bytes;
    checksum_ = c.checksum;
    binary_ = c.binary;
    resolution_m_ = c.resolution_m;
  }
  chunks_[c.chunk_index].assign(c.data, c.size);
  held_bytes_ += static_cast<int64_t>(c.size);
  complete_ = Assemble();
  return true;
}

std::optional<OctomapData> OctomapAssembler::Assemble() const {
  if (chunk_count_ == 0 || static_cast<int32_t>(chunks_.size()) != chunk_count_) {
    return std::nullopt;
  }
  OctomapData out;
  out.binary = binary_;
  out.resolution_m = resolution_m_;
  for (const auto& [index, bytes] : chunks_) out.bytes += bytes;
  if (static_cast<int64_t>(out.bytes.size()) != total_bytes_ ||
      common::Crc32(out.bytes.data(), out.bytes.size()) != checksum_) {
    return std::nullopt;
  }
  return out;
}

}  // namespace cairn::mapstore
