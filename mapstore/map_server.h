#pragma once

#include <optional>
#include <string>
#include <vector>

#include "common/grid_map.h"
#include "common/obstacle.h"
#include "common/status.h"
#include "mapstore/map_store.h"

/// @file
/// The core of cairn-map-server: a stored map served to one robot that has no mapper of its
/// own (no lidar). The server loads a map version for the robot's profile through the MapStore
/// (base layers + the profile's derived layers, from the derived cache when present, else
/// derived in memory: serving never writes to the store), and the process publishes it on the
/// robot's map channels exactly as a mapper would (services: mapstore/map_server_service.h).
///
/// This part is pure (no LCM): which layers are served, how one load attempt goes, and whether
/// to keep waiting for a map that is not in the store yet.

namespace cairn::mapstore {

/// Parameters of a map server. Durations in seconds of wall-clock time.
struct MapServerParams {
  std::string db_path;  ///< the SQLite file (opened read-only)
  MapRef ref;           ///< map to serve (version 0 = the latest not deleted)
  std::string profile;  ///< the served robot's profile: its cost layer is cost/<profile>
  std::string robot;    ///< the served robot: channels <robot>.MAP.*
  double wait_s{0.0};   ///< wait this long for the map to appear (0: fail at once)
  double poll_period_s{1.0};      ///< look at the store this often while waiting (and following)
  double announce_period_s{0.2};  ///< manifests of every served layer, changed or not
  double registry_period_s{1.0};  ///< the obstacle registry with the profile's verdicts
  /// With version 0: serve a newer version as soon as it is saved (checked every
  /// follow_period_s).
  bool follow_latest{true};
  double follow_period_s{5.0};
  int tiles_per_burst{4};         ///< tiles sent back to back before a pause ...
  double burst_pause_ms{5.0};     ///< ... of this long (receivers with small UDP buffers)

  /// @throws std::invalid_argument naming the first bad field.
  void Validate() const;
};

/// A map as it is served to one profile.
struct ServedMap {
  MapInfo info;                        ///< the exact version served
  std::string profile;
  common::GridMap layers;              ///< ServedLayers(profile) present in the map
  common::ObstacleRegistry obstacles;  ///< stored obstacles with this profile's verdict
  bool from_cache{false};              ///< derived layers came from the store's cache
  double derive_ms{0.0};               ///< time spent deriving (0 on a cache hit)
};

/// Layers a server publishes for `profile`, each when the map has it: "elevation" (a terrain
/// map), "sonar/occupancy" (an AUV's sonar map: what its navigator reads live), and
/// "directed/<profile>" and "cost/<profile>", the layers the navigator plans on.
std::vector<std::string> ServedLayers(const std::string& profile);

/// Whether a served layer goes out as occupancy tiles (lcmt_occupancy_tile on
/// <robot>.MAP.OCCUPANCY, 0..100 and -1 unknown), as a mapper sends it: the sonar occupancy.
/// Others go out as float tiles on <robot>.MAP.TILES.
bool ServedAsOccupancy(const std::string& layer);

/// Map name on the bus (lcmt_grid_tile.map_name and friends): "<site>/<map>". A mapper's live
/// map is named otherwise ("live"), so a receiver can tell a served map from a mapped one.
std::string ServedMapName(const MapRef& ref);

/// One attempt: the map version `ref` for `profile`, with its elevation or sonar occupancy (if
/// stored), its cost
/// layer and the obstacles re-labelled for the profile. Read-only. kNotFound when the map, the
/// version or the profile is not in the store (yet); kUnavailable when `deriver` is null or
/// invalid (it also keys the derived cache); kInvalidArgument when the map cannot be derived (no
/// elevation); kNotFound when the derivation produces no cost layer.
common::Result<ServedMap> LoadServedMap(const MapStore& store, const ProfileDeriver* deriver,
                                        const MapRef& ref, const std::string& profile);

/// Whether a failed attempt may succeed later: the map, its version or the profile is not there
/// yet (kNotFound) or the database is locked or not created yet (kUnavailable).
bool MayAppearLater(const common::Status& status);

/// Decides, attempt after attempt, whether to keep waiting for a map.
class MapWaiter {
 public:
  /// `wait_s` bounds the wait, counted from the first attempt (0: give up at the first miss).
  explicit MapWaiter(double wait_s);

  enum class Action { kServe, kWait, kGiveUp };
  struct Decision {
    Action action{Action::kWait};
    /// Set once: on the first attempt that has to wait (say "waiting for ..."), and when the
    /// wait ends either way (say how long it took or why it gave up).
    std::optional<std::string> log;
  };

  /// The outcome of one attempt made `elapsed_s` after the first one.
  Decision OnAttempt(double elapsed_s, const common::Status& status);

  bool waited() const { return waiting_since_s_.has_value(); }

 private:
  double wait_s_;
  std::optional<double> waiting_since_s_;
};

}  // namespace cairn::mapstore
