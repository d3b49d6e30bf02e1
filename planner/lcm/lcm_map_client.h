#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <variant>
#include <vector>

#include "cairn/lcmt_grid_manifest.hpp"
#include "cairn/lcmt_grid_tile.hpp"
#include "cairn/lcmt_occupancy_tile.hpp"

#include "planner/cost_map.h"
#include "planner/map_snapshot_policy.h"
#include "planner/map_source.h"
#include "services/runtime/layer_assembler.h"
#include "services/runtime/node.h"
#include "services/runtime/tiler.h"

/// @file
/// LcmMapClient: a MapSource that rebuilds one layer from a mapper's tiles and manifests
/// (<robot>.MAP.MANIFEST) and asks for missing tiles on <robot>.MAP.TILE_RESEND. The layer is
/// either a cost layer ("cost/<profile>", float tiles on <robot>.MAP.TILES) or a 2-D occupancy
/// layer (the dynamic map server's "final", int8 tiles on <robot>.MAP.OCCUPANCY). When and how
/// an assembled version becomes a CostMap (occupancy converted to cost, missing tiles lethal,
/// the wait for them) is the core's MapSnapshotPolicy: this class only moves tiles.
///
/// Beside a cost layer it also reads the profile's directed layer ("directed/<profile>", float
/// tiles on the same channels) when `directed_layer` names it and the mapper publishes it: each
/// snapshot carries the directed layer held when it is built, if it has the cost layer's grid,
/// and a directed version that completes while the cost version stays makes a new snapshot of
/// that cost version. The two layers are one pair: a cost version counts as complete for the
/// policy only when the directed version held has all its tiles too, so a lost directed tile is
/// waited for (and asked for again) like a lost cost tile, up to the policy's
/// incomplete_timeout_s; only then does a snapshot read the missing directed tiles as 0 (the
/// cost layer alone, its one-way cells blocking every heading). Without directed tiles (an older
/// mapper) the snapshots are the cost layer's alone.

namespace cairn::planner {

struct LcmMapClientParams {
  std::string robot;
  std::string layer;  ///< "cost/<profile>" (kCost), or "final", "long_term"... (kOccupancy)
  /// "directed/<profile>" to read beside a cost layer; "" (default): none.
  std::string directed_layer;
  std::string map_name;  ///< accept only this map name ("" = any)
  std::string requester{"cairn-navigator"};
  double resend_interval_s{0.5};
  /// The map policy; its `encoding` also says which tiles to read (float or occupancy).
  MapSnapshotParams snapshot;
  /// Tiles and manifests from the bus are assembled, and snapshots built, on the client's own
  /// thread: the node's thread (which runs the navigator's control loop) only queues them, so
  /// no layer, however large, delays a command or the stale-input stop. Off: on the node's
  /// thread, as the handlers are called (tests that drive the handlers).
  bool own_thread{false};
  /// Messages waiting for the client's thread; beyond, the oldest goes (counted as
  /// map_queue_drops; a lost tile is asked for again).
  size_t max_queued_messages{4096};
};

class LcmMapClient : public MapSource {
 public:
  /// Subscribes on `node` (which must outlive the client).
  /// @throws std::invalid_argument for an invalid footprint or snapshot params.
  LcmMapClient(runtime::Node& node, LcmMapClientParams params,
               std::vector<common::Vector2> footprint_m);
  ~LcmMapClient() override;
  LcmMapClient(const LcmMapClient&) = delete;
  LcmMapClient& operator=(const LcmMapClient&) = delete;

  std::shared_ptr<const CostMap> Latest() const override;
  int64_t last_heard_utime() const override;

  /// Handlers (public for tests that drive the client without a bus).
  void OnTile(const cairn::lcmt_grid_tile& tile);
  void OnTile(const cairn::lcmt_occupancy_tile& tile);
  void OnManifest(const cairn::lcmt_grid_manifest& manifest);
  /// Sends resend requests and builds overdue incomplete snapshots; call periodically. With
  /// own_thread it only asks the client's thread to do so.
  void Poll();

  int64_t snapshots() const { return snapshots_.load(); }

 private:
  bool Accepts(const std::string& robot, const std::string& map_name,
               const std::string& layer) const;
  template <typename TileMsg>
  void OnTileImpl(const TileMsg& tile);
  void Heard();
  void Carry(SnapshotAction action);
  void AttachDirected(AssembledLayer* assembled);
  void RefreshDirected();
  // True while the directed layer's newest version lacks tiles.
  bool DirectedPending() const;
  // The cost version complete, and the directed version beside it too.
  bool PairComplete() const;
  void AskForMissing(const std::string& layer, int64_t now);
  void PollNow();
  /// A message from the bus: handled now, or queued for the client's thread.
  using Message =
      std::variant<cairn::lcmt_grid_tile, cairn::lcmt_occupancy_tile, cairn::lcmt_grid_manifest>;
  void Deliver(Message message);
  void Handle(const Message& message);
  void ThreadLoop();

  runtime::Node& node_;
  LcmMapClientParams params_;
  MapSnapshotPolicy policy_;
  runtime::LayerAssembler assembler_;
  mutable std::mutex mutex_;
  std::shared_ptr<const CostMap> latest_;
  int64_t heard_utime_{0};
  int64_t last_resend_utime_{0};
  std::atomic<int64_t> snapshots_{0};
  int tile_size_{0};  // of the newest manifest
  // The directed layer in the snapshot in use: its version (-1: none) and whether it was whole.
  int64_t built_directed_version_{-1};
  bool built_directed_complete_{false};

  // own_thread: what waits for the client's thread.
  std::mutex queue_mutex_;
  std::condition_variable queue_cv_;
  std::deque<Message> queue_;
  bool poll_requested_{false};
  bool stop_{false};
  std::thread thread_;
};

}  // namespace cairn::planner
