#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "common/grid_map.h"
#include "common/obstacle.h"
#include "common/robot_profile.h"
#include "common/status.h"
#include "common/types.h"

/// @file
/// MapStore: where robots leave maps for other robots.
///
/// A *site* holds named *maps*; every save of a map makes a new immutable *version* with its
/// provenance (source robot and profile, mapping code version, parameters, time). A version
/// holds robot-agnostic base layers (GridMap layers, stored tiled so a region loads without
/// reading the whole map), the obstacle registry with its measurements, and optionally an
/// OctoMap tree. Layers derived for one robot profile (cost/<profile>, slope, ...) are a cache
/// keyed by (map version, profile content hash, mapping code version): sharing a map with
/// another profile fills the cache and never touches the base layers.
///
/// Two implementations: SqliteMapStore (one SQLite file per site or fleet) and InMemoryMapStore
/// (a twin for unit tests). Both behave the same; one behavioural test suite runs on both.
///
/// Expected outcomes are Status values: kNotFound (unknown map, version or profile; a deleted
/// map), kInvalidArgument (bad names, empty maps), kCorrupt (a blob whose checksum fails, a
/// file that is not a cairn database), kUnavailable (the database stayed locked),
/// kResourceExhausted (disk full: nothing was written).

namespace cairn::mapstore {

/// Site used when a caller names none.
inline constexpr char kDefaultSite[] = "default";

/// Names one map version. version 0 means the latest version that is not deleted.
struct MapRef {
  std::string site{kDefaultSite};
  std::string name;
  int64_t version{0};
};

/// Where a map version came from.
struct Provenance {
  std::string source_robot;
  std::string source_profile;       ///< profile the mapper ran with ("" when unknown)
  std::string source_profile_hash;  ///< its RobotProfile::ContentHash() ("" when unknown)
  std::string code_version;         ///< mapping code version that produced the layers
  std::string parameters;           ///< the mapper's parameters as text (YAML), verbatim
  int64_t created_utime{0};         ///< 0 on save means "now" (wall clock)
  bool operator==(const Provenance& o) const {
    return source_robot == o.source_robot && source_profile == o.source_profile &&
           source_profile_hash == o.source_profile_hash && code_version == o.code_version &&
           parameters == o.parameters && created_utime == o.created_utime;
  }
};

/// An OctoMap tree as its stream bytes: AbstractOcTree::write (.ot) or writeBinary (.bt).
struct OctomapData {
  bool binary{true};
  double resolution_m{0.0};
  std::string bytes;
  bool operator==(const OctomapData& o) const {
    return binary == o.binary && resolution_m == o.resolution_m && bytes == o.bytes;
  }
};

/// One stored tile of a base layer as the store keeps it, so that a load reply can send it
/// without decoding and encoding it again. Tile (tile_ix, tile_iy) covers cells
/// [tile_ix * tile_size, + cells_x) x [tile_iy * tile_size, + cells_y) of the version's grid.
struct StoredTile {
  int tile_ix{0};
  int tile_iy{0};
  int cells_x{0};
  int cells_y{0};
  int codec{0};           ///< how `data` is encoded (mapstore::Codec)
  uint32_t raw_crc32{0};  ///< CRC-32 of the float cells (x fastest, host byte order)
  std::string data;       ///< the stored bytes
  /// StoredBlobCrc32 of the row, when the store recorded one (SqliteMapStore from schema 3):
  /// CheckStoredTile then compares it instead of decompressing the bytes.
  std::optional<uint32_t> stored_crc32;
};

/// A base layer as stored tiles. Tiles the store does not hold are all unknown.
struct StoredLayer {
  std::string name;
  int tile_size{0};
  std::vector<StoredTile> tiles;  ///< row by row
};

/// Everything one save stores.
struct MapSnapshot {
  std::string site{kDefaultSite};
  std::string name;
  Provenance provenance;
  common::GridMap base;                ///< robot-agnostic layers (at least one)
  common::ObstacleRegistry obstacles;  ///< measurements and the verdicts known at save time
  std::optional<OctomapData> octomap;
  /// Optional: base tiles the caller already holds compressed (a pushed save's, as they came),
  /// by layer. A store may keep such a blob instead of compressing its tile again when the
  /// tile is one of its own (same tile size, place and cells) and the blob's CRC is that of the
  /// base's cells there; `base` stays what is saved.
  std::vector<StoredLayer> encoded_layers;
  /// The caller checked that every encoded tile's CRC is that of the base's cells it stands
  /// for (a pushed save: each tile was decoded on receipt and checked against its CRC): the
  /// store then adopts matching tiles without reading those cells again.
  bool encoded_layers_checked{false};
};

/// A stored map version as listed.
struct MapInfo {
  std::string site;
  std::string name;
  int64_t version{0};
  Provenance provenance;
  common::GridGeometry geometry;
  int tile_size{0};
  std::vector<std::string> layers;  ///< base layers, sorted
  int num_obstacles{0};
  bool has_octomap{false};
  bool deleted{false};
};

/// A rectangle of cells [min_ix, max_ix) x [min_iy, max_iy).
struct CellBox {
  int min_ix{0};
  int min_iy{0};
  int max_ix{0};
  int max_iy{0};
  bool empty() const { return max_ix <= min_ix || max_iy <= min_iy; }
};

/// Which layers (empty = all) of which region (nullopt = whole map) to read. A region is
/// clipped to the map; the result is a GridMap covering the clipped box, whose origin is the
/// world pose of the box's minimum corner.
struct LayerQuery {
  std::vector<std::string> layers;
  std::optional<CellBox> region;
};

/// A cached derivation with its layers as stored tiles (FindDerived without decoding them).
struct StoredDerived {
  std::string profile_name;
  common::ObstacleRegistry registry;  ///< the obstacles with this profile's verdict
  std::vector<StoredLayer> layers;
};

/// Which maps to list.
struct MapFilter {
  std::string site;          ///< empty = every site
  std::string name;          ///< empty = every map
  bool all_versions{false};  ///< false: the latest version of each map only
  bool include_deleted{false};
};

/// A robot profile as stored.
struct StoredProfile {
  common::RobotProfile profile;
  std::string content_hash;
  int64_t updated_utime{0};
};

/// A semantic place of a site: a name and an area (world-frame polygon), such as a room.
struct Place {
  std::string name;
  std::vector<common::Vector2> polygon_m;
  bool operator==(const Place& o) const { return name == o.name && polygon_m == o.polygon_m; }
};

/// Layers and verdicts derived from a map version for one robot profile (the cache entry).
struct DerivedProfile {
  std::string profile_name;
  std::string profile_hash;
  std::string code_version;
  common::GridMap layers;             ///< e.g. slope, step, roughness, cost/<profile>
  common::ObstacleRegistry registry;  ///< the obstacles with this profile's verdict
  int64_t created_utime{0};
};

/// One cached derivation of a map version, as listed.
struct DerivedInfo {
  std::string profile_name;
  std::string profile_hash;
  std::string code_version;
  int64_t created_utime{0};
  std::vector<std::string> layers;
};

/// Who changes the store, for the audit log.
struct WriteContext {
  std::string actor;      ///< "cairn-map", a requester name, ...
  int64_t request_id{0};  ///< the request that caused the change (0 = none)
  int64_t utime{0};       ///< 0 = now (wall clock)
};

/// One line of the audit log.
struct AuditEntry {
  int64_t id{0};
  int64_t utime{0};
  std::string actor;
  std::string op;  ///< "save", "delete", "put_profile", "put_place", "derive", "import", ...
  std::string site;
  std::string map;
  int64_t version{0};
  int64_t request_id{0};
  std::string detail;
};

/// Result of an integrity check.
struct CheckReport {
  bool ok{true};
  std::vector<std::string> problems;  ///< one line per problem
  int64_t maps_checked{0};
  int64_t blobs_checked{0};
};

/// Progress callback of long operations: fraction in [0, 1] and what is being done.
using ProgressFn = std::function<void(double fraction, const std::string& stage)>;

/// Derivation of profile layers, injected so that unit tests can use a fake and production
/// the mapping core (mapstore/mapping_deriver.h).
struct ProfileDeriver {
  /// Output of one derivation.
  struct Output {
    common::GridMap layers;             ///< cost/<profile> and any helper layers
    common::ObstacleRegistry registry;  ///< obstacles found in the base with this profile's verdict
  };
  /// Part of the derived-cache key: changes whenever derivation results could change.
  std::string code_version;
  /// Derives the profile layers from the base layers. May throw std::invalid_argument (for
  /// example when the base has no elevation); callers turn that into a status.
  std::function<Output(const common::GridMap& base, const common::RobotProfile& profile)> derive;
  /// Verdict of one stored obstacle for a profile, from its measurements alone.
  std::function<common::ObstacleVerdict(const common::Obstacle& obstacle,
                                        const common::RobotProfile& profile)>
      judge;
  /// A terrace's parts judged for a profile, one verdict per part in order (optional: without it
  /// a registry judged for another profile keeps no part verdicts).
  std::function<std::vector<common::ObstacleVerdict>(const common::Obstacle& obstacle,
                                                     const common::RobotProfile& profile)>
      judge_parts;

  bool valid() const { return !code_version.empty() && derive && judge; }
};

/// The storage interface. Implementations are not required to be thread-safe unless they say so.
class MapStore {
 public:
  MapStore() = default;
  virtual ~MapStore() = default;
  MapStore(const MapStore&) = delete;
  MapStore& operator=(const MapStore&) = delete;

  /// Stores a new version of snapshot.site/snapshot.name (version = previous highest + 1, deleted
  /// versions included). Layer names, site and map names are validated. Returns the new version.
  virtual common::Result<MapInfo> SaveMap(const MapSnapshot& snapshot, const WriteContext& ctx) = 0;
  /// A map version (version 0 = latest not deleted). kNotFound when unknown or deleted.
  virtual common::Result<MapInfo> GetMapInfo(const MapRef& ref) const = 0;
  /// Maps matching the filter, sorted by site, name and version.
  virtual common::Result<std::vector<MapInfo>> ListMaps(const MapFilter& filter) const = 0;
  /// Base layers of a version. kNotFound for an unknown layer, kCorrupt for a bad blob.
  virtual common::Result<common::GridMap> LoadLayers(const MapRef& ref,
                                                     const LayerQuery& query) const = 0;
  /// Base layers of a version (`layers` empty = all) as their stored tiles, each blob checked
  /// (kCorrupt when its bytes do not decode to what its checksums say). The default cuts
  /// LoadLayers' grid into tiles of `tile_size` and compresses them as SqliteMapStore stores
  /// them; SqliteMapStore returns its own blobs (tiles of the size the version was saved with).
  virtual common::Result<std::vector<StoredLayer>> LoadStoredTiles(
      const MapRef& ref, const std::vector<std::string>& layers, int tile_size = 100) const;
  virtual common::Result<common::ObstacleRegistry> LoadObstacles(const MapRef& ref) const = 0;
  /// kNotFound when the version has no OctoMap.
  virtual common::Result<OctomapData> LoadOctomap(const MapRef& ref) const = 0;
  /// Soft delete: version 0 marks every version of the map deleted, else that version only.
  /// Stored data stay (the audit log says who deleted what).
  virtual common::Status DeleteMap(const MapRef& ref, const WriteContext& ctx) = 0;

  /// Stores a profile; storing the same content again changes nothing.
  virtual common::Status PutProfile(const common::RobotProfile& profile,
                                    const WriteContext& ctx) = 0;
  /// The newest content stored under a name.
  virtual common::Result<StoredProfile> GetProfile(const std::string& name) const = 0;
  /// The content hash of the newest content stored under a name, as GetProfile has it (same
  /// errors); SqliteMapStore answers without parsing the profile.
  virtual common::Result<std::string> GetProfileHash(const std::string& name) const;
  /// The newest content of every profile, sorted by name.
  virtual common::Result<std::vector<StoredProfile>> ListProfiles() const = 0;

  /// The cached derivation for (map version, profile hash, code version), nullopt on a miss.
  /// The query selects derived layers and a region as in LoadLayers.
  virtual common::Result<std::optional<DerivedProfile>> FindDerived(
      const MapRef& ref, const std::string& profile_hash, const std::string& code_version,
      const LayerQuery& query) const = 0;
  /// The cached derivation as FindDerived finds it, its layers (`layers` empty = all) as stored
  /// tiles, each blob checked; nullopt on a miss. The default cuts FindDerived's layers into
  /// tiles of `tile_size` and compresses them; SqliteMapStore returns its own blobs.
  virtual common::Result<std::optional<StoredDerived>> FindDerivedTiles(
      const MapRef& ref, const std::string& profile_hash, const std::string& code_version,
      const std::vector<std::string>& layers, int tile_size = 100) const;
  /// Every cached derivation of a map version, by profile name.
  virtual common::Result<std::vector<DerivedInfo>> ListDerived(const MapRef& ref) const = 0;
  /// Caches a derivation (a second put of the same key keeps the first).
  virtual common::Status PutDerived(const MapRef& ref, const DerivedProfile& derived,
                                    const WriteContext& ctx) = 0;

  /// Adds or replaces places of a site by name (the site is created if needed).
  virtual common::Status PutPlaces(const std::string& site, const std::vector<Place>& places,
                                   const WriteContext& ctx) = 0;
  virtual common::Result<std::vector<Place>> ListPlaces(const std::string& site) const = 0;
  virtual common::Result<std::vector<std::string>> ListSites() const = 0;

  /// Newest first, at most `limit` entries.
  virtual common::Result<std::vector<AuditEntry>> ListAudit(int limit) const = 0;
  /// The newest audit entry recorded for (actor, request_id), if any: lets a replayed save
  /// request return the version it made the first time.
  virtual common::Result<std::optional<AuditEntry>> FindRequest(const std::string& actor,
                                                                int64_t request_id) const = 0;

  /// Verifies every stored blob against its checksum and every reference.
  virtual common::Result<CheckReport> Check(const ProgressFn& progress = nullptr) const = 0;
};

}  // namespace cairn::mapstore
