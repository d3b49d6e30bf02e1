#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "cairn/lcmt_grid_manifest.hpp"
#include "cairn/lcmt_grid_tile.hpp"
#include "cairn/lcmt_grid_tile_batch.hpp"
#include "cairn/lcmt_mapstore_reply.hpp"
#include "cairn/lcmt_mapstore_request.hpp"
#include "cairn/lcmt_obstacle_registry.hpp"
#include "cairn/lcmt_occupancy_tile.hpp"
#include "cairn/lcmt_octomap.hpp"
#include "cairn/lcmt_tile_resend_request.hpp"

#include "mapstore/map_store.h"
#include "services/runtime/node.h"
#include "services/runtime/tiler.h"

/// @file
/// MapstoreService: the map store on the bus (the process is cairn-mapstore).
///
/// Requests arrive on MAPSTORE.REQUEST (lcmt_mapstore_request) and are answered on
/// MAPSTORE.REPLY with the same request_id. Replaying a request id (same requester) returns
/// the first reply, and a save replayed after a restart returns the version it made (the audit
/// log remembers request ids). Layers of a reply go out as lcmt_grid_tile with map_name
/// "<request_id>/<map>": compressed tiles several to an lcmt_grid_tile_batch on
/// MAPSTORE.TILE_BATCHES, float tiles singly on MAPSTORE.TILES; one manifest per layer on
/// MAPSTORE.MANIFEST, and an
/// OctoMap as lcmt_octomap chunks on MAPSTORE.OCTOMAP; the reply says how many tiles follow and
/// receivers ask for what they missed on MAPSTORE.TILE_RESEND.
///
/// Saves come two ways:
/// - push: the client first publishes, with map_name "<request_id>/<map>", a manifest and the
///   tiles of every layer (MAPSTORE.PUSH.MANIFEST; compressed tiles several to a batch on
///   MAPSTORE.PUSH.TILE_BATCHES, float tiles on MAPSTORE.PUSH.TILES), the obstacles
///   (MAPSTORE.PUSH.OBSTACLES) and the OctoMap (MAPSTORE.PUSH.OCTOMAP), then OP_SAVE naming the
///   layers. The store asks for missing tiles on MAPSTORE.PUSH.TILE_RESEND;
/// - pull: OP_SAVE with `robot` set. The store listens to <robot>.MAP.* (the mapper's "live"
///   map), asks the mapper to publish everything (<robot>.MAP.CONTROL, OP_PUBLISH_ALL), asks for
///   missed tiles on <robot>.MAP.TILE_RESEND and saves the robot-agnostic layers (cost and other
///   profile layers are left out: the store derives them per profile).
///
/// Statuses: NOT_FOUND (unknown map, version, layer, profile), INVALID (bad names, values or
/// requests; counted as dropped inputs in HEALTH), CORRUPT (a stored blob failed its checksum),
/// BUSY (the database stayed locked), ERROR (anything else, with a message). Nothing a request
/// carries can crash the process.

namespace cairn::mapstore {

struct MapstoreServiceParams {
  std::string files_root{"var/mapstore-files"};  ///< OP_EXPORT/OP_IMPORT paths stay below it
  double save_timeout_s{20.0};                   ///< a save gives up waiting for tiles after this
  double resend_interval_s{0.05};                ///< asks again for missing tiles this often
  double staging_timeout_s{30.0};  ///< pushed data without a request are dropped after this
  double pull_settle_s{0.5};       ///< a pull without named layers waits this long for more
  int reply_cache_size{512};       ///< replies kept for replays
  int64_t max_kept_reply_cells{64'000'000};  ///< reply tiles kept for resends (cells)
  int64_t max_staged_cells{128'000'000};     ///< pushed tiles held at once (cells)
  int reply_tile_size{100};                  ///< cells per side of reply tiles
  int max_reply_obstacles{1500};             ///< obstacles carried in one reply (bus size limit)
  /// Compressed reply tiles go out several to a message (MAPSTORE.TILE_BATCHES) of at most
  /// batch_bytes of tile bytes (0: one tile per message on MAPSTORE.TILES); float tiles one per
  /// message, in bursts of tiles_per_burst. A pause follows every batch and every burst: UDP
  /// drops what a receiver's socket buffer (~200 KB) cannot hold while its process waits for a
  /// core.
  int64_t batch_bytes{60000};
  int tiles_per_burst{2};
  double burst_pause_ms{0.1};
  int worker_threads{2};  ///< loads, shares, exports and imports run on these
  int decode_threads{2};  ///< threads decoding a batch of pushed tiles as it arrives
  /// Pending saves are checked this often (timeouts, resend rounds, pulled data); a push save
  /// also finishes the moment its last piece arrives.
  double poll_period_s{0.05};
  /// Reply tiles travel compressed (the store's zstd codec): a third of the bytes of smooth
  /// terrain, a tenth of a cost layer's. Resent tiles travel as floats.
  bool compress_reply_tiles{true};
};

class MapstoreService {
 public:
  /// `store` and `node` must outlive the service. `deriver` may be invalid (no derivation:
  /// profile loads and shares answer with an error).
  MapstoreService(runtime::Node& node, MapStore& store, ProfileDeriver deriver,
                  MapstoreServiceParams params);
  ~MapstoreService();
  MapstoreService(const MapstoreService&) = delete;
  MapstoreService& operator=(const MapstoreService&) = delete;

  /// Checks pending saves (timeouts, resend requests); called from a node timer.
  void Poll();

  /// Saves waiting for their data.
  int64_t pending_saves() const;
  /// Worker requests queued or running.
  int64_t running_jobs() const;

 private:
  using Clock = std::chrono::steady_clock;
  struct Outgoing;
  struct Staging;
  struct PendingSave;
  struct LiveMirror;
  /// What a worker job produced; applied on the node's thread.
  struct JobResult {
    cairn::lcmt_mapstore_reply reply{};
    common::Status status;
    std::optional<common::GridMap> layers;  ///< payload sent as tiles
    /// Or base layers as the store keeps them, sent as they are (a load without a profile).
    std::vector<StoredLayer> stored_layers;
    common::GridGeometry stored_geometry;
    std::string robot;                   ///< robot field of the payload tiles
    std::optional<OctomapData> octomap;  ///< payload sent as chunks
    std::string event;                   ///< one log line, when notable
    std::string counter;                 ///< a HEALTH counter to bump
  };
  struct Job {
    cairn::lcmt_mapstore_request request{};
    std::chrono::steady_clock::time_point started;
    cairn::lcmt_mapstore_reply reply{};
  };

  void OnRequest(const cairn::lcmt_mapstore_request& request);
  void OnPushTile(const cairn::lcmt_grid_tile& tile);
  /// Compressed pushed tiles, decoded on worker threads before the lock is taken.
  void OnPushTileBatch(const cairn::lcmt_grid_tile_batch& batch);
  /// Stages a pushed tile; `cells` are a compressed tile's decoded cells (empty for floats).
  void StagePushTile(const cairn::lcmt_grid_tile& tile, std::vector<float> cells);
  void OnPushManifest(const cairn::lcmt_grid_manifest& manifest);
  void OnPushObstacles(const cairn::lcmt_obstacle_registry& registry);
  void OnPushOctomap(const cairn::lcmt_octomap& chunk);
  /// Pushed data for `map_name` arrived: the push save waiting for it, if any, finishes now when
  /// nothing is missing any more (not at the next Poll).
  void OnPushed(const std::string& map_name);
  /// Subscribes `handler` to a push channel, then OnPushed.
  template <typename Msg>
  void SubscribePush(const std::string& channel, void (MapstoreService::*handler)(const Msg&)) {
    node_.Subscribe<Msg>(channel, [this, handler](const Msg& m) {
      (this->*handler)(m);
      OnPushed(m.map_name);
    });
  }
  void OnResend(const cairn::lcmt_tile_resend_request& request);

  /// Handles one request; fills the reply, may queue outgoing payload. Returns false when the
  /// reply is deferred (a save waiting for tiles).
  bool Handle(const cairn::lcmt_mapstore_request& request, cairn::lcmt_mapstore_reply* reply);
  // Worker jobs: they use only the store, the deriver and the parameters (never the node).
  JobResult RunJob(const cairn::lcmt_mapstore_request& request,
                   cairn::lcmt_mapstore_reply reply) const;
  void JobLoad(const cairn::lcmt_mapstore_request& request, JobResult* out) const;
  void JobShare(const cairn::lcmt_mapstore_request& request, JobResult* out) const;
  void JobLoadObstacles(const cairn::lcmt_mapstore_request& request, JobResult* out) const;
  void JobExport(const cairn::lcmt_mapstore_request& request, JobResult* out) const;
  void JobImport(const cairn::lcmt_mapstore_request& request, JobResult* out) const;
  void WorkerLoop();
  bool StartSave(const cairn::lcmt_mapstore_request& request, cairn::lcmt_mapstore_reply* reply);
  /// Tries to finish a pending save; true when it replied (saved or failed).
  bool TryFinishSave(PendingSave& save, bool timed_out);
  /// Caches a finished reply for replays, publishes it, then its payload (if any). Called with
  /// mutex_ held.
  void Finish(const cairn::lcmt_mapstore_request& request, cairn::lcmt_mapstore_reply reply,
              Clock::time_point started);
  /// Fills the reply's counts and duration and caches it for replays (mutex_ held).
  void CacheReply(const cairn::lcmt_mapstore_request& request, cairn::lcmt_mapstore_reply* reply,
                  Clock::time_point started);
  void Publish(const cairn::lcmt_mapstore_reply& reply);
  /// Tiles a reply's payload (no lock needed).
  std::shared_ptr<Outgoing> MakeOutgoing(const std::string& map_name,
                                         const JobResult& result) const;
  /// Keeps a payload for resends, forgetting the oldest ones beyond the memory bound (mutex_ held).
  void KeepOutgoing(std::shared_ptr<Outgoing> out);
  /// Publishes a payload: everything (request == nullptr) or what a resend request names.
  void Resend(Outgoing& out, const cairn::lcmt_tile_resend_request* request);
  void EnsureMirror(const std::string& robot);
  /// Resolves a path of a request below files_root; kInvalidArgument when it would leave it.
  common::Result<std::string> FilesPath(const std::string& relative) const;
  std::string RequestKey(const cairn::lcmt_mapstore_request& request) const;
  void SetStatus(const common::Status& status, cairn::lcmt_mapstore_reply* reply);

  runtime::Node& node_;
  MapStore& store_;
  ProfileDeriver deriver_;
  MapstoreServiceParams params_;

  // Guards everything below: handlers run on the node's thread, finished requests are applied
  // by the worker threads.
  mutable std::mutex mutex_;
  // Replies by request key, oldest first, for replays.
  std::map<std::string, cairn::lcmt_mapstore_reply> replies_;
  std::deque<std::string> reply_order_;
  // Reply payloads kept for resends, by map_name "<request_id>/<map>". Shared: a worker may
  // still be sending one the store already forgot.
  std::map<std::string, std::shared_ptr<Outgoing>> outgoing_;
  std::deque<std::string> outgoing_order_;
  int64_t outgoing_cells_{0};
  // Pushed data by map_name, and saves waiting for data, by request key.
  std::map<std::string, std::unique_ptr<Staging>> staging_;
  std::map<std::string, std::unique_ptr<PendingSave>> pending_;
  // The live maps of robots the store pulled from.
  std::map<std::string, std::unique_ptr<LiveMirror>> mirrors_;
  // Heavy requests waiting for a worker, and the keys of those queued or running.
  std::deque<std::unique_ptr<Job>> queue_;
  std::set<std::string> busy_keys_;
  std::condition_variable work_ready_;
  bool stopping_{false};
  std::vector<std::thread> workers_;
};

/// Maps a core status to a reply status constant.
int8_t ReplyStatus(const common::Status& status);

}  // namespace cairn::mapstore
