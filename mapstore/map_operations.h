#pragma once

#include <optional>
#include <string>
#include <vector>

#include "common/grid_map.h"
#include "common/obstacle.h"
#include "common/status.h"
#include "mapstore/map_store.h"

/// @file
/// What robots ask of a map store, built on the MapStore interface (so both implementations
/// behave alike): a map for a profile, sharing a map with another profile, and diffs.

namespace cairn::mapstore {

/// A map as one robot profile sees it.
struct ProfileView {
  MapInfo info;
  common::GridMap layers;              ///< requested base layers + the profile's derived layers
  common::ObstacleRegistry obstacles;  ///< stored obstacles with this profile's verdict
  bool from_cache{false};              ///< derived layers came from the cache
  double derive_ms{0.0};               ///< time spent deriving (0 on a cache hit)
};

/// Loads a map version for `profile` (empty profile: base layers and stored obstacles only).
/// `query.layers` may name base and derived layers (empty = all of both); `query.region` crops.
/// Derived layers come from the cache; on a miss they are derived (never written: read-only use
/// leaves the store unchanged; ShareMap fills the cache). kNotFound for an unknown map,
/// version, layer or profile; kUnavailable when a derivation is needed and `deriver` is null.
common::Result<ProfileView> LoadForProfile(const MapStore& store, const ProfileDeriver* deriver,
                                           const MapRef& ref, const std::string& profile,
                                           const LayerQuery& query = {});

/// Result of sharing a map with a profile.
struct ShareResult {
  MapInfo info;
  DerivedProfile derived;      ///< the target profile's layers and verdicts
  std::string source_profile;  ///< the profile the map was made with
  /// Obstacles whose verdict for the target differs from the source profile's; each carries
  /// both verdicts (source first, then target). An obstacle with no known source verdict is
  /// included when the target cannot cross it.
  std::vector<common::Obstacle> changed;
  bool was_cached{false};  ///< the derivation was already in the cache
};

/// Derives the target profile's layers (or takes them from the cache), caches them, and
/// compares verdicts with the source profile. The base layers are never modified.
common::Result<ShareResult> ShareMap(MapStore& store, const ProfileDeriver& deriver,
                                     const MapRef& ref, const std::string& target_profile,
                                     const WriteContext& ctx);

/// Cells of one pair of layers that differ.
struct LayerDiff {
  std::string layer_a;
  std::string layer_b;
  int64_t cells_compared{0};
  int64_t cells_different{0};               ///< known/unknown changes count; NaN equals NaN
  std::vector<common::CellIndex> examples;  ///< the first few differing cells
};

/// One obstacle that differs: added, removed, measurements changed or verdict changed.
struct ObstacleDiff {
  int32_t id{0};
  std::string what;  ///< "only in A", "only in B", "height 0.03 -> 0.05", "crossable -> blocked"
};

struct MapDiff {
  std::string a_label;
  std::string b_label;
  std::vector<LayerDiff> layers;
  std::vector<ObstacleDiff> obstacles;
  bool identical() const;
};

/// Two versions of maps (layers by name, obstacles by id). Geometries must match.
/// `tolerance` is the largest absolute difference still counted as equal.
common::Result<MapDiff> DiffVersions(const MapStore& store, const MapRef& a, const MapRef& b,
                                     const std::vector<std::string>& layers = {},
                                     double tolerance = 0.0);

/// One version under two profiles: cost/<a> against cost/<b>, and verdicts.
common::Result<MapDiff> DiffProfiles(const MapStore& store, const ProfileDeriver* deriver,
                                     const MapRef& ref, const std::string& profile_a,
                                     const std::string& profile_b);

/// Compares two layers of equal size.
LayerDiff CompareLayers(const std::string& name_a, const common::Layer& a,
                        const std::string& name_b, const common::Layer& b, double tolerance);

}  // namespace cairn::mapstore
