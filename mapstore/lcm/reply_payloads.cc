#include "mapstore/lcm/reply_payloads.h"

#include <algorithm>
#include <chrono>
#include <stdexcept>

#include "cairn/lcmt_grid_tile_batch.hpp"

#include "common/channels.h"
#include "mapstore/blob_codec.h"
#include "mapstore/lcm/mapstore_conversions.h"
#include "mapstore/lcm/tile_wire.h"
#include "mapstore/octomap_chunks.h"
#include "mapstore/save_assembler.h"

namespace cairn::mapstore {

namespace {

using Clock = std::chrono::steady_clock;

double MsSince(Clock::time_point t) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t).count();
}

// A stored tile as the tiler sends it: its blob as it is when the wire has its codec, else its
// cells as floats (another codec: raw, plain zstd).
runtime::LayerTiler::EncodedTile WireTileOf(const StoredTile& t) {
  runtime::LayerTiler::EncodedTile e;
  e.tile_ix = t.tile_ix;
  e.tile_iy = t.tile_iy;
  e.cells_x = t.cells_x;
  e.cells_y = t.cells_y;
  e.checksum = t.raw_crc32;
  e.encoding = WireEncoding(static_cast<Codec>(t.codec));
  if (e.encoding != cairn::lcmt_grid_tile::ENCODING_FLOAT32) {
    e.bytes.assign(t.data.begin(), t.data.end());
    return e;
  }
  e.data.resize(static_cast<size_t>(t.cells_x) * t.cells_y);
  const common::Status s = DecodeBlobTo(static_cast<Codec>(t.codec), t.data.data(), t.data.size(),
                                        static_cast<int64_t>(e.data.size() * sizeof(float)),
                                        t.raw_crc32, reinterpret_cast<uint8_t*>(e.data.data()));
  if (!s.ok()) throw std::runtime_error(s.message());  // checked when loaded
  return e;
}

}  // namespace

ReplyPayloads::ReplyPayloads(runtime::Node& node, ReplyPayloadParams params)
    : node_(node), params_(params) {}

ReplyPayloads::~ReplyPayloads() = default;

void ReplyPayloads::MakeStored(Payload* out, const PayloadContent& content) const {
  const auto tile_started = Clock::now();
  out->as_stored = true;
  out->tiler = std::make_unique<runtime::LayerTiler>(out->robot, out->map_name,
                                                     content.stored_layers.front().tile_size);
  const int64_t utime = node_.NowUtime();
  for (const StoredLayer& layer : content.stored_layers) {
    std::vector<runtime::LayerTiler::EncodedTile> tiles;
    tiles.reserve(layer.tiles.size());
    for (const StoredTile& t : layer.tiles) tiles.push_back(WireTileOf(t));
    out->first_send.push_back(
        out->tiler->Adopt(layer.name, content.stored_geometry, std::move(tiles), utime));
    out->layers.push_back(layer.name);
    out->cells += content.stored_geometry.num_cells();
  }
  out->tile_ms = MsSince(tile_started);
}

void ReplyPayloads::MakeTiled(Payload* out, const common::GridMap& layers) const {
  out->tiler = std::make_unique<runtime::LayerTiler>(out->robot, out->map_name, params_.tile_size);
  const int64_t utime = node_.NowUtime();
  const auto tile_started = Clock::now();
  for (const std::string& name : layers.layer_names()) {
    out->first_send.push_back(
        out->tiler->Update(layers, name, runtime::TileEncoding::kFloat, utime, true));
    out->layers.push_back(name);
    out->cells += layers.geometry().num_cells();
  }
  out->tile_ms = MsSince(tile_started);
  if (!params_.compress_tiles) return;
  std::vector<cairn::lcmt_grid_tile*> tiles;
  for (auto& batch : out->first_send) {
    for (auto& tile : batch.tiles) tiles.push_back(&tile);
  }
  const auto compress_started = Clock::now();
  ParallelFor(tiles.size(), std::max(1, params_.compress_threads),
              [&](size_t i) { CompressTile(tiles[i]); });
  out->compress_ms = MsSince(compress_started);
}

std::shared_ptr<ReplyPayloads::Payload> ReplyPayloads::Make(const std::string& map_name,
                                                            const PayloadContent& content) const {
  auto out = std::make_shared<Payload>();
  out->map_name = map_name;
  out->robot = content.robot;
  out->octomap = content.octomap;
  if (!content.stored_layers.empty()) {
    MakeStored(out.get(), content);
  } else if (content.layers) {
    MakeTiled(out.get(), *content.layers);
  }
  for (const auto& batch : out->first_send) {
    out->num_tiles += static_cast<int32_t>(batch.tiles.size());
    for (const auto& tile : batch.tiles) out->bytes += TilePayloadBytes(tile);
  }
  return out;
}

void ReplyPayloads::Keep(std::shared_ptr<Payload> payload) {
  std::lock_guard<std::mutex> lock(mutex_);
  // Kept for resends; the oldest payloads go first when memory runs short.
  kept_cells_ += payload->cells;
  auto existing = kept_.find(payload->map_name);
  if (existing != kept_.end()) {
    kept_cells_ -= existing->second->cells;
    existing->second = std::move(payload);
  } else {
    order_.push_back(payload->map_name);
    kept_[payload->map_name] = std::move(payload);
  }
  while (kept_cells_ > params_.max_kept_cells && order_.size() > 1) {
    auto victim = kept_.find(order_.front());
    if (victim != kept_.end()) {
      kept_cells_ -= victim->second->cells;
      kept_.erase(victim);
    }
    order_.pop_front();
  }
}

std::shared_ptr<ReplyPayloads::Payload> ReplyPayloads::Find(const std::string& map_name) const {
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = kept_.find(map_name);
  return it == kept_.end() ? nullptr : it->second;
}

void ReplyPayloads::PublishBatch(Payload& payload, const runtime::LayerTiler::Batch& batch,
                                 int* burst_tiles) {
  // Compressed tiles travel several to a message, up to batch_bytes, with a pause after each
  // message; float tiles (resends) travel singly, in bursts of tiles_per_burst.
  node_.Publish(channels::kMapstoreManifest, batch.manifest);
  cairn::lcmt_grid_tile_batch pending{};
  int64_t pending_bytes = 0;
  auto flush = [&] {
    if (pending.tiles.empty()) return;
    pending.utime = node_.NowUtime();
    pending.map_name = payload.map_name;
    pending.num_tiles = static_cast<int32_t>(pending.tiles.size());
    node_.Publish(channels::kMapstoreTileBatches, pending);
    node_.Count("tiles_sent", pending.num_tiles);
    pending.tiles.clear();
    pending_bytes = 0;
    PacingPause(params_.burst_pause_ms);
  };
  for (const auto& tile : batch.tiles) {
    if (tile.encoding != cairn::lcmt_grid_tile::ENCODING_FLOAT32 && params_.batch_bytes > 0) {
      const int64_t bytes = TilePayloadBytes(tile);
      if (!pending.tiles.empty() && pending_bytes + bytes > params_.batch_bytes) flush();
      pending.tiles.push_back(tile);
      pending_bytes += bytes;
      continue;
    }
    flush();
    if (!PublishTile(node_.lcm(), channels::kMapstoreTiles, tile)) {
      node_.Warn("publish_tiles", "could not publish reply tiles");
    }
    node_.Count("tiles_sent");
    if (++*burst_tiles >= params_.tiles_per_burst) {
      PacingPause(params_.burst_pause_ms);
      *burst_tiles = 0;
    }
  }
  flush();
}

void ReplyPayloads::Send(Payload& payload, const cairn::lcmt_tile_resend_request* request) {
  // A null request sends the whole payload: every layer's manifest and tiles, then the OctoMap.
  std::lock_guard<std::mutex> sending(payload.sending);
  const bool octomap_asked = request != nullptr && request->layer == kResendOctomap;
  int burst_tiles = 0;  // float tiles sent since the last pause
  if (request == nullptr && !payload.first_send.empty()) {
    // The first send of a reply: the batches made when the payload was tiled.
    for (const auto& batch : payload.first_send) PublishBatch(payload, batch, &burst_tiles);
    payload.first_send.clear();
  } else if (payload.tiler && request != nullptr && !octomap_asked) {
    PublishBatch(payload, payload.tiler->Resend(*request), &burst_tiles);
  } else if (payload.tiler && request == nullptr) {
    for (const std::string& layer : payload.layers) {
      cairn::lcmt_tile_resend_request all{};
      all.layer = layer;
      all.num_tiles = 0;
      PublishBatch(payload, payload.tiler->Resend(all), &burst_tiles);
    }
  }
  if (payload.octomap && (request == nullptr || octomap_asked)) {
    const int64_t utime = node_.NowUtime();
    for (const OctomapChunk& chunk : SplitOctomap(*payload.octomap)) {
      node_.Publish(channels::kMapstoreOctomap,
                    ToLcm(chunk, payload.robot, payload.map_name, utime));
    }
  }
}

}  // namespace cairn::mapstore
