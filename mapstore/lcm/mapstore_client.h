#pragma once

#include <chrono>
#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "cairn/lcmt_grid_manifest.hpp"
#include "cairn/lcmt_grid_tile.hpp"
#include "cairn/lcmt_grid_tile_batch.hpp"
#include "cairn/lcmt_mapstore_reply.hpp"
#include "cairn/lcmt_mapstore_request.hpp"
#include "cairn/lcmt_octomap.hpp"
#include "cairn/lcmt_tile_resend_request.hpp"

#include "common/status.h"
#include "mapstore/map_store.h"
#include "services/runtime/tiler.h"

/// @file
/// MapstoreClient: the caller's side of the cairn-mapstore protocol (see mapstore_service.h):
/// request ids, replays on silence, push saves that answer the store's resend requests, and
/// loads that reassemble the reply tiles and ask for what went missing. Single-threaded: the
/// calls handle the LCM traffic themselves.

namespace cairn::mapstore {

struct MapstoreClientOptions {
  double reply_timeout_s{2.0};     ///< re-send the request (same id) after this much silence
  double total_timeout_s{60.0};    ///< give up after this
  double resend_interval_s{0.02};  ///< ask for missing tiles after this long without progress
  int tile_size{100};              ///< cells per side of pushed tiles
  int tiles_per_burst{2};          ///< pushed float tiles sent back to back before a short pause
  double burst_pause_ms{0.1};      ///< lets the store's receive buffer drain (UDP drops the rest)
  bool compress_tiles{true};       ///< pushed tiles travel compressed (resent ones as floats)
  /// Compressed pushed tiles travel several to an lcmt_grid_tile_batch of about this many tile
  /// bytes, with burst_pause_ms after each (0: one tile per message, in bursts).
  int64_t batch_bytes{60000};
  int compression_threads{2};  ///< threads compressing a push
  int decode_threads{2};       ///< threads decoding a batch of compressed reply tiles
};

class MapstoreClient {
 public:
  /// `lcm` must outlive the client. `requester` names the caller in the store's audit log.
  MapstoreClient(lcm::LCM& lcm, std::string requester, MapstoreClientOptions options = {});
  ~MapstoreClient();
  MapstoreClient(const MapstoreClient&) = delete;
  MapstoreClient& operator=(const MapstoreClient&) = delete;

  /// A fresh request id (unique per process and time).
  int64_t NextRequestId();

  /// Sends a request (request_id and requester filled in when empty) and waits for its reply.
  /// kUnavailable when no reply came in time. The reply's own status is not interpreted.
  common::Result<cairn::lcmt_mapstore_reply> Call(cairn::lcmt_mapstore_request request);

  /// Push save of a snapshot: its layers, obstacles and OctoMap, then OP_SAVE carrying its
  /// provenance (source profile, code version, parameters; the tiles carry the source robot).
  /// Answers the store's resend requests while it waits for the reply.
  common::Result<cairn::lcmt_mapstore_reply> Save(const MapSnapshot& snapshot);

  struct Loaded {
    cairn::lcmt_mapstore_reply reply{};
    common::GridMap layers;
    common::ObstacleRegistry obstacles;
    std::optional<OctomapData> octomap;
    int resend_requests{0};  ///< how often tiles had to be asked for again
  };
  /// Loads a map for a profile (empty: base layers only). `layers` may include "octomap".
  /// A reply status other than OK becomes an error status carrying the store's message.
  common::Result<Loaded> Load(const std::string& site, const std::string& map, int64_t version,
                              const std::string& profile,
                              const std::vector<std::string>& layers = {});

 /// Messages refused on the client's channels (undecodable, or whose handler failed): none
  /// of them unwinds through liblcm's C dispatch.
  int64_t dropped_messages() const { return dropped_messages_; }

 private:
  struct Incoming;
  /// Every subscription's handler: decodes, calls `Handler`, and counts (never throws) a
  /// message that does not decode or whose handler throws.
  template <typename Msg, void (MapstoreClient::*Handler)(const lcm::ReceiveBuffer*,
                                                          const std::string&, const Msg*)>
  static void Guarded(const lcm::ReceiveBuffer* rbuf, const std::string& channel,
                      MapstoreClient* self);
  template <typename Msg, void (MapstoreClient::*Handler)(const lcm::ReceiveBuffer*,
                                                          const std::string&, const Msg*)>
  void Subscribe(const char* channel);
  int64_t dropped_messages_{0};
  void OnReply(const lcm::ReceiveBuffer*, const std::string&, const cairn::lcmt_mapstore_reply* m);
  void OnTile(const lcm::ReceiveBuffer*, const std::string&, const cairn::lcmt_grid_tile* m);
  void OnTileBatch(const lcm::ReceiveBuffer*, const std::string&,
                   const cairn::lcmt_grid_tile_batch* m);
  void HoldTile(const cairn::lcmt_grid_tile& tile);
  void OnManifest(const lcm::ReceiveBuffer*, const std::string&,
                  const cairn::lcmt_grid_manifest* m);
  void OnOctomap(const lcm::ReceiveBuffer*, const std::string&, const cairn::lcmt_octomap* m);
  void OnPushResend(const lcm::ReceiveBuffer*, const std::string&,
                    const cairn::lcmt_tile_resend_request* m);
  /// Tiles (and compresses) the layers on worker threads and publishes each as it is ready.
  common::Status PushLayers(const std::vector<std::string>& layers, const MapSnapshot& snapshot,
                            int64_t utime);
  void PushOctomap(const OctomapData& octomap, int64_t utime);
  /// Whether every layer a reply announces (and the OctoMap, when asked for) arrived.
  bool PayloadComplete(const cairn::lcmt_mapstore_reply& reply, bool want_octomap) const;
  bool OctomapComplete() const;
  /// Asks the store for what is missing; returns how many requests went out.
  int AskForMissing(const cairn::lcmt_mapstore_reply& reply, bool want_octomap, bool long_quiet);
  /// Waits for a reply's tiles and OctoMap, asking again for what does not arrive.
  common::Status AwaitPayload(const cairn::lcmt_mapstore_reply& reply, bool want_octomap,
                              std::chrono::steady_clock::time_point start, Loaded* loaded);
  /// Moves the arrived layers, obstacles and OctoMap into `loaded`.
  common::Status CollectPayload(const cairn::lcmt_mapstore_reply& reply, bool want_octomap,
                                Loaded* loaded);
  /// Publishes a pushed float tile, pausing after every burst.
  void PublishPaced(const cairn::lcmt_grid_tile& tile);
  /// Publishes pushed tiles: compressed ones in batches of batch_bytes, floats one by one.
  void PublishPushed(const std::string& map_name, const std::vector<cairn::lcmt_grid_tile>& tiles);
  int paced_{0};

  lcm::LCM& lcm_;
  std::string requester_;
  MapstoreClientOptions options_;
  std::vector<lcm::Subscription*> subscriptions_;
  int64_t counter_{0};
  // The call in progress.
  int64_t active_id_{0};
  std::optional<cairn::lcmt_mapstore_reply> reply_;
  std::unique_ptr<Incoming> incoming_;
  // A push in progress: what to send again when asked.
  struct Push;
  std::unique_ptr<Push> push_;
};

/// The core status matching a reply status (OK -> ok).
common::Status StatusOfReply(const cairn::lcmt_mapstore_reply& reply);

}  // namespace cairn::mapstore
