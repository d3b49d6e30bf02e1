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
#include "cairn/lcmt_octomap.hpp"
#include "cairn/lcmt_tile_resend_request.hpp"

#include "mapstore/lcm/reply_payloads.h"
#include "mapstore/map_store.h"
#include "mapstore/mapstore_params.h"
#include "mapstore/save_assembler.h"
#include "services/runtime/node.h"

/// @file
/// MapstoreService: the map store on the bus (the process is cairn-mapstore). It converts
/// messages and moves them; what the store does lives in the core (SaveAssembler for saves,
/// AnswerLoad, ShareMap, ExportMap, ImportMap, ...).
///
/// Requests arrive on MAPSTORE.REQUEST (lcmt_mapstore_request) and are answered on
/// MAPSTORE.REPLY with the same request_id. Replaying a request id (same requester) returns
/// the first reply, and a save replayed after a restart returns the version it made (the audit
/// log remembers request ids). Layers of a reply go out as lcmt_grid_tile with map_name
/// "<request_id>/<map>": compressed tiles several to an lcmt_grid_tile_batch on
/// MAPSTORE.TILE_BATCHES, float tiles singly on MAPSTORE.TILES; one manifest per layer on
/// MAPSTORE.MANIFEST, and an OctoMap as lcmt_octomap chunks on MAPSTORE.OCTOMAP; the reply says
/// how many tiles follow and receivers ask for what they missed on MAPSTORE.TILE_RESEND
/// (lcm/reply_payloads.h).
///
/// Saves come two ways (mapstore/save_assembler.h):
/// - push: the client first publishes, with map_name "<request_id>/<map>", a manifest and the
///   tiles of every layer (MAPSTORE.PUSH.MANIFEST; compressed tiles several to a batch on
///   MAPSTORE.PUSH.TILE_BATCHES, float tiles on MAPSTORE.PUSH.TILES), the obstacles
///   (MAPSTORE.PUSH.OBSTACLES) and the OctoMap (MAPSTORE.PUSH.OCTOMAP), then OP_SAVE naming the
///   layers. The store asks for missing tiles on MAPSTORE.PUSH.TILE_RESEND;
/// - pull: OP_SAVE with `robot` set. The store listens to <robot>.MAP.* (the mapper's "live"
///   map), asks the mapper to publish everything (<robot>.MAP.CONTROL, OP_PUBLISH_ALL), asks for
///   missed tiles on <robot>.MAP.TILE_RESEND and saves the robot-agnostic layers (cost and other
///   profile layers are left out: the store derives them per profile). A pull naming no layers
///   waits for the mapper's reply (<robot>.MAP.CONTROL_REPLY, sending the request again with the
///   same id until it comes), then for every robot-agnostic layer it lists.
///
/// Statuses: NOT_FOUND (unknown map, version, layer, profile), INVALID (bad names, values or
/// requests; counted as dropped inputs in HEALTH), CORRUPT (a stored blob failed its checksum),
/// BUSY (the database stayed locked), ERROR (anything else, with a message). Nothing a request
/// carries can crash the process.

namespace cairn::mapstore {

class MapstoreService {
 public:
  /// `store` and `node` must outlive the service. `deriver` may be invalid (no derivation:
  /// profile loads and shares answer with an error). @throws std::invalid_argument for bad
  /// params.
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
  using Reply = cairn::lcmt_mapstore_reply;
  using Request = cairn::lcmt_mapstore_request;
  /// What a worker job produced; applied on the worker's thread after the work.
  struct JobResult {
    Reply reply{};
    common::Status status;
    PayloadContent payload;  ///< layers and OctoMap sent after the reply
    std::string event;       ///< one log line, when notable
    std::string counter;     ///< a HEALTH counter to bump
  };
  struct Job {
    Request request{};
    Clock::time_point started;
    Reply reply{};
  };

  // ---- Requests (mapstore_service.cc) ----
  void OnRequest(const Request& request);
  /// Handles one request; fills the reply. Returns false when the reply is deferred (a save
  /// waiting for tiles, a worker job).
  bool Handle(const Request& request, Reply* reply);
  bool QueueJob(const Request& request, Reply* reply);
  void HandleList(const Request& request, Reply* reply);
  void HandlePutProfile(const Request& request, Reply* reply);
  void HandleDelete(const Request& request, Reply* reply);
  void HandlePutPlaces(const Request& request, Reply* reply);
  /// Caches a finished reply for replays, then publishes it (mutex_ held).
  void Finish(const Request& request, Reply reply, Clock::time_point started);
  /// Fills the reply's counts and duration and caches it for replays (mutex_ held).
  void CacheReply(const Request& request, Reply* reply, Clock::time_point started);
  void Publish(const Reply& reply);
  void SetStatus(const common::Status& status, Reply* reply);
  std::string RequestKey(const Request& request) const;
  static double SecondsSince(Clock::time_point t);
  void OnResend(const cairn::lcmt_tile_resend_request& request);

  // ---- Worker jobs (mapstore_jobs.cc): they use the store, the deriver and the parameters ----
  void WorkerLoop();
  void RunQueued(Job& job);
  JobResult RunJob(const Request& request, Reply reply) const;
  void JobLoad(const Request& request, JobResult* out) const;
  void JobShare(const Request& request, JobResult* out) const;
  void JobLoadObstacles(const Request& request, JobResult* out) const;
  void JobExport(const Request& request, JobResult* out) const;
  void JobImport(const Request& request, JobResult* out) const;

  // ---- Saves (mapstore_saves.cc): messages to and from the SaveAssembler ----
  void SubscribeSaves();
  void StartSave(const Request& request, Reply* reply, Clock::time_point started);
  void OnPushTile(const cairn::lcmt_grid_tile& tile);
  /// Compressed pushed tiles, decoded on worker threads before the lock is taken.
  void OnPushTileBatch(const cairn::lcmt_grid_tile_batch& batch);
  /// Stages a pushed tile; `cells` are a compressed tile's decoded cells (empty for floats).
  void StagePushTile(const cairn::lcmt_grid_tile& tile, const std::vector<float>& cells);
  void OnPushManifest(const cairn::lcmt_grid_manifest& manifest);
  void OnPushObstacles(const cairn::lcmt_obstacle_registry& registry);
  void OnPushOctomap(const cairn::lcmt_octomap& chunk);
  /// Subscribes `handler` to a push channel; after it, the save waiting for that map_name
  /// finishes when nothing is missing any more (not at the next Poll).
  template <typename Msg>
  void SubscribePush(const std::string& channel, void (MapstoreService::*handler)(const Msg&));
  /// Counts a refused push message under `counter`.
  void CountIntake(SaveAssembler::Intake intake, const char* counter);
  /// Follows a robot's live map (<robot>.MAP.*) for pull saves.
  void FollowRobot(const std::string& robot);
  /// Sends what a SaveAssembler call asks for and replies to the saves it finished (mutex_
  /// held). `first_reply`: the reply a request started with, for a save that ends at once.
  void Apply(SaveProgress progress, const Reply* first_reply = nullptr);
  void FinishSave(SaveOutcome outcome, const Reply* first_reply);

  runtime::Node& node_;
  MapStore& store_;
  ProfileDeriver deriver_;
  MapstoreServiceParams params_;
  ReplyPayloads payloads_;

  // Guards everything below: handlers run on the node's thread, finished requests are applied
  // by the worker threads.
  mutable std::mutex mutex_;
  // Replies by request key, oldest first, for replays.
  std::map<std::string, Reply> replies_;
  std::deque<std::string> reply_order_;
  SaveAssembler saves_;
  common::TokenBuckets resend_limits_;  // OnResend (the node's thread) only
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
