#pragma once

#include <optional>
#include <string>
#include <vector>

#include "common/obstacle.h"
#include "common/status.h"
#include "mapstore/map_operations.h"
#include "mapstore/map_store.h"

/// @file
/// What the map store answers to a load request (OP_LOAD, OP_LOAD_OBSTACLES), in core terms:
/// which version, which layers (decoded, or the stored tiles as they are), which obstacles and
/// OctoMap. MapstoreService turns an answer into a reply and its tiles.

namespace cairn::mapstore {

/// A load of base and derived layers (and "octomap") of a map version for a profile.
struct LoadRequest {
  MapRef ref;
  std::string profile;              ///< "" = base layers and stored obstacles only
  std::vector<std::string> layers;  ///< base or derived layer names, or "octomap"; "" = all
  /// The answer may hand over stored tiles as they are (no decoding, tiling or compressing):
  /// a load without a profile of base layers only (MapStore::LoadStoredTiles), or of cached
  /// derived layers only for a profile (MapStore::FindDerivedTiles).
  bool may_send_stored{true};
  int tile_size{100};  ///< tile side when the store has to cut tiles itself
};

/// What a load answers.
struct LoadAnswer {
  /// The version, the obstacles (with the profile's verdicts) and, unless `stored_layers` or
  /// `only_octomap`, the layers decoded.
  ProfileView view;
  /// The layers as stored tiles, of view.info.geometry (when the store sends them as they are).
  std::vector<StoredLayer> stored_layers;
  bool stored{false};                  ///< the layers are `stored_layers`
  bool only_octomap{false};            ///< the request named "octomap" alone: no layers
  std::optional<OctomapData> octomap;  ///< when the request named "octomap"
  /// The layers answered, in order.
  std::vector<std::string> layer_names() const;
  /// "<n> layers[, derived layers from the cache | , derived now (not cached)][, OctoMap
  /// follows]".
  std::string Summary(bool with_profile) const;
};

/// Answers a load. Errors of the store (kNotFound for an unknown map, version, layer or
/// profile; kCorrupt; kUnavailable when a derivation is needed and `deriver` is invalid).
common::Result<LoadAnswer> AnswerLoad(const MapStore& store, const ProfileDeriver& deriver,
                                      const LoadRequest& request);

/// The obstacles of a map version: as stored (no profile), or with `profile`'s verdicts.
struct ObstacleAnswer {
  MapInfo info;
  common::ObstacleRegistry registry;
};
common::Result<ObstacleAnswer> AnswerObstacles(const MapStore& store, const ProfileDeriver& deriver,
                                               const MapRef& ref, const std::string& profile);

}  // namespace cairn::mapstore
