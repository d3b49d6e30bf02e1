#pragma once

#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "cairn/lcmt_tile_resend_request.hpp"

#include "common/grid_map.h"
#include "mapstore/map_store.h"
#include "services/runtime/node.h"
#include "services/runtime/tiler.h"

/// @file
/// The payloads of MapstoreService's replies: layers as tiles (MAPSTORE.TILE_BATCHES for
/// compressed tiles several to a message, MAPSTORE.TILES for float tiles, a manifest per layer
/// on MAPSTORE.MANIFEST) and an OctoMap as chunks (MAPSTORE.OCTOMAP), all with map_name
/// "<request_id>/<map>". Payloads are kept, within a memory bound, for the resend requests of
/// receivers that missed some (MAPSTORE.TILE_RESEND).

namespace cairn::mapstore {

struct ReplyPayloadParams {
  int tile_size{100};                  ///< cells per side of tiles cut from decoded layers
  bool compress_tiles{true};           ///< decoded layers' tiles travel compressed
  int compress_threads{2};             ///< threads compressing those tiles
  int64_t batch_bytes{60000};          ///< tile bytes of one batch (0: one tile per message)
  int tiles_per_burst{2};              ///< float tiles sent back to back ...
  double burst_pause_ms{0.1};          ///< ... then (and after every batch) this pause
  int64_t max_kept_cells{64'000'000};  ///< payload cells kept for resends
};

/// What a reply carries beside the reply message.
struct PayloadContent {
  std::string robot;                       ///< robot field of the tiles and chunks
  std::optional<common::GridMap> layers;   ///< decoded layers: tiled (and compressed) now
  std::vector<StoredLayer> stored_layers;  ///< or stored tiles, sent as they are
  common::GridGeometry stored_geometry;    ///< the grid of `stored_layers`
  std::optional<OctomapData> octomap;
  bool empty() const { return !layers && stored_layers.empty() && !octomap; }
};

class ReplyPayloads {
 public:
  /// One reply's payload, tiled and ready to send.
  struct Payload {
    std::mutex sending;  ///< one send of this payload at a time
    std::string map_name;
    std::string robot;
    std::unique_ptr<runtime::LayerTiler> tiler;
    std::vector<runtime::LayerTiler::Batch> first_send;  ///< sent once, then dropped
    std::vector<std::string> layers;
    std::optional<OctomapData> octomap;
    bool as_stored{false};    ///< the tiles are the store's blobs as they are
    int32_t num_tiles{0};     ///< tiles of the first send
    int64_t cells{0};         ///< cells of the layers
    double tile_ms{0.0};      ///< cutting the layers into tiles
    double compress_ms{0.0};  ///< compressing the tiles
    int64_t bytes{0};         ///< tile bytes of the first send
  };

  /// `node` must outlive this.
  ReplyPayloads(runtime::Node& node, ReplyPayloadParams params);
  ~ReplyPayloads();
  ReplyPayloads(const ReplyPayloads&) = delete;
  ReplyPayloads& operator=(const ReplyPayloads&) = delete;

  /// Tiles (and compresses) a payload; thread-safe, no lock held. @throws on a stored tile that
  /// does not decode (it was checked when loaded) or bad geometry.
  std::shared_ptr<Payload> Make(const std::string& map_name, const PayloadContent& content) const;
  /// Keeps a payload for resends, forgetting the oldest beyond the memory bound. Thread-safe.
  void Keep(std::shared_ptr<Payload> payload);
  /// A kept payload by map_name, or null. Thread-safe.
  std::shared_ptr<Payload> Find(const std::string& map_name) const;
  /// Publishes a payload: all of it (request null: a first send, or a replay), or what a
  /// resend request names. One send of a payload at a time.
  void Send(Payload& payload, const cairn::lcmt_tile_resend_request* request);

 private:
  /// Publishes a batch's manifest and tiles; `burst_tiles` counts float tiles since a pause.
  void PublishBatch(Payload& payload, const runtime::LayerTiler::Batch& batch, int* burst_tiles);
  void MakeStored(Payload* out, const PayloadContent& content) const;
  void MakeTiled(Payload* out, const common::GridMap& layers) const;

  runtime::Node& node_;
  ReplyPayloadParams params_;
  mutable std::mutex mutex_;  // guards the kept payloads
  std::map<std::string, std::shared_ptr<Payload>> kept_;
  std::deque<std::string> order_;
  int64_t kept_cells_{0};
};

}  // namespace cairn::mapstore
