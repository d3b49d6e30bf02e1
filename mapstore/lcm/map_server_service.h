#pragma once

#include <chrono>
#include <functional>
#include <future>
#include <map>
#include <optional>
#include <string>

#include "cairn/lcmt_grid_manifest.hpp"
#include "cairn/lcmt_tile_resend_request.hpp"

#include "mapstore/map_server.h"
#include "mapstore/map_store.h"
#include "services/runtime/node.h"
#include "services/runtime/tiler.h"

/// @file
/// MapServerService: cairn-map-server on the bus. It serves a stored map to a robot without a
/// mapper of its own, on the channels a mapper would use, so the robot's navigator cannot tell
/// the difference:
///
/// | channel                  | type                     | what                                   |
/// |--------------------------|--------------------------|----------------------------------------|
/// | `<robot>.MAP.TILES`      | lcmt_grid_tile           | elevation and cost/<profile> (out)     |
/// | `<robot>.MAP.MANIFEST`   | lcmt_grid_manifest       | every announce_period_s, changed or not|
/// | `<robot>.MAP.OBSTACLES`  | lcmt_obstacle_registry   | obstacles with the profile's verdicts  |
/// | `<robot>.MAP.TILE_RESEND`| lcmt_tile_resend_request | in: tiles a receiver missed            |
/// | `HEALTH`                 | lcmt_health              | counters tiles_sent, manifests_sent,   |
/// |                          |                          | resend_requests, tiles_resent, loads   |
///
/// Loading (store reads and, on a cache miss, the derivation) runs on a worker thread, so the
/// heartbeat keeps going while a large map is derived or while the server waits for a map that
/// has not been saved yet. Everything else runs on the node's thread.

namespace cairn::mapstore {

class MapServerService {
 public:
  /// Opens the store for one attempt (called on the worker thread, one call at a time); may be
  /// called again after it failed. The store it returns must stay valid while the service lives.
  using StoreOpener = std::function<common::Result<const MapStore*>()>;

  enum class State { kLoading, kWaiting, kServing, kFailed };

  /// Registers its handlers and timers on `node` (which must outlive the service) and starts
  /// the first load. `deriver` (which must outlive the service) keys the store's derived cache
  /// and derives on a miss.
  /// @throws std::invalid_argument for invalid params or a null or invalid deriver.
  MapServerService(runtime::Node& node, MapServerParams params, const ProfileDeriver* deriver,
                   StoreOpener open_store);
  ~MapServerService();
  MapServerService(const MapServerService&) = delete;
  MapServerService& operator=(const MapServerService&) = delete;

  State state() const { return state_; }
  /// The map being served (nullptr before the first one).
  const ServedMap* served() const { return served_ ? &*served_ : nullptr; }
  const std::string& bus_map_name() const { return map_name_; }

  /// Handlers and timer bodies (public so tests can drive the service without waiting).
  void OnResend(const cairn::lcmt_tile_resend_request& request);
  /// Collects a finished load and starts the next one when due.
  void Tick();
  /// Publishes the manifest of every served layer.
  void Announce();
  void PublishRegistry();

 private:
  using Clock = std::chrono::steady_clock;
  // A load outcome: nullopt when following found no newer version.
  using Outcome = common::Result<std::optional<ServedMap>>;

  void StartLoad();
  void OnOutcome(Outcome outcome);
  void Serve(ServedMap map);
  template <typename Msg>
  void Send(const std::string& channel, const std::vector<Msg>& messages);
  double SinceFirstAttempt() const;

  runtime::Node& node_;
  MapServerParams params_;
  const ProfileDeriver* deriver_;
  StoreOpener open_store_;
  std::string map_name_;
  runtime::LayerTiler tiler_;
  MapWaiter waiter_;
  State state_{State::kLoading};
  std::optional<ServedMap> served_;
  std::map<std::string, cairn::lcmt_grid_manifest> manifests_;  // by layer
  std::future<Outcome> job_;
  std::optional<Clock::time_point> first_attempt_;
  Clock::time_point next_load_;
};

}  // namespace cairn::mapstore
