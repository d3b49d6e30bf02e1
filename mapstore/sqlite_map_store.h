#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "mapstore/blob_codec.h"
#include "mapstore/map_store.h"
#include "mapstore/sqlite_db.h"

/// @file
/// SqliteMapStore: the map store in one SQLite file (schema in mapstore/schema.h).
///
/// - WAL journal: readers never block the writer and the writer never blocks readers.
/// - Every write is one BEGIN IMMEDIATE transaction, retried while another writer holds the
///   lock (busy_timeout plus a bounded retry), so two processes saving at once both succeed.
///   A process killed mid-save leaves the previous versions intact: the save either committed
///   or never happened.
/// - Tiles are compressed and checksummed before the transaction starts (in parallel), so the
///   write lock is held only for the inserts.
/// - Blobs are content-addressed and never updated; identical tiles of successive versions are
///   stored once.
/// - Read-only use (loads, lists, checks) never writes to the file.
/// - A file that is not a cairn database, or is from a newer schema, is refused with a message;
///   an older schema is migrated when the store is opened for writing.

namespace cairn::mapstore {

/// Durability of a commit (SqliteOptions::synchronous).
enum class Synchronous { kNormal, kFull };
/// "normal" / "full".
const char* SynchronousName(Synchronous mode);
/// Parses "normal" or "full" (any case); nullopt otherwise.
std::optional<Synchronous> ParseSynchronous(const std::string& text);

struct SqliteOptions {
  bool read_only{false};         ///< open without write access (no migration, no creation)
  bool create_if_missing{true};  ///< create an empty database when the file does not exist
  int busy_timeout_ms{5000};     ///< how long one statement waits for a lock
  int write_attempts{10};        ///< BEGIN IMMEDIATE attempts while the database stays busy
  /// When a commit reaches the disk (PRAGMA synchronous; the journal is always WAL):
  /// - kNormal: the WAL is synced only at checkpoints. A killed process loses nothing
  ///   committed; a power cut or kernel crash may lose the newest commits (they roll back: the
  ///   file stays consistent, an older version is the latest), never corrupt older ones.
  /// - kFull: the WAL is synced at every commit, so an acknowledged save survives a power cut
  ///   too, at the price of one fsync per save.
  Synchronous synchronous{Synchronous::kNormal};
  int tile_size_cells{100};    ///< tile side of newly saved layers
  int zstd_level{1};           ///< compression level of new blobs
  int compression_threads{2};  ///< threads compressing/decompressing tiles
  int cache_size_kib{32768};   ///< SQLite page cache
  int64_t max_page_count{0};   ///< size quota in pages (0 = none); beyond it writes fail
                               ///< with kResourceExhausted like a full disk
  /// WAL pages after which a commit also checkpoints (SQLite's default is 1000). A long-running
  /// writer sets it high and calls CheckpointIfIdle() so saves do not pay for checkpoints.
  int wal_autocheckpoint_pages{1000};
};

class SqliteMapStore final : public MapStore {
 public:
  /// Opens (and creates or migrates) a database. ":memory:" gives a private in-memory database.
  /// A file this process cannot write (its mode, its folder's, or a read-only file system) is
  /// opened read-only instead of failing: loads, lists and checks work, and every write fails
  /// with kPermissionDenied naming the file and the reason (write_refusal()). A read-only open
  /// of a file whose folder this process cannot write either (a read-only mount, mode 0555),
  /// with no WAL beside it, reads the file as immutable (SQLite takes no lock and needs no -shm
  /// file): a change another process makes to it meanwhile is not seen. Errors: kCorrupt (not a
  /// cairn database), kInvalidArgument (schema newer than this build, or an older schema opened
  /// read-only), kUnavailable/kNotFound (cannot open the file).
  static common::Result<std::unique_ptr<SqliteMapStore>> Open(const std::string& path,
                                                              const SqliteOptions& options = {});
  ~SqliteMapStore() override;

  common::Result<MapInfo> SaveMap(const MapSnapshot& snapshot, const WriteContext& ctx) override;
  common::Result<MapInfo> GetMapInfo(const MapRef& ref) const override;
  common::Result<std::vector<MapInfo>> ListMaps(const MapFilter& filter) const override;
  common::Result<common::GridMap> LoadLayers(const MapRef& ref,
                                             const LayerQuery& query) const override;
  common::Result<std::vector<StoredLayer>> LoadStoredTiles(const MapRef& ref,
                                                           const std::vector<std::string>& layers,
                                                           int tile_size = 100) const override;
  common::Result<common::ObstacleRegistry> LoadObstacles(const MapRef& ref) const override;
  common::Result<OctomapData> LoadOctomap(const MapRef& ref) const override;
  common::Status DeleteMap(const MapRef& ref, const WriteContext& ctx) override;
  common::Status PutProfile(const common::RobotProfile& profile, const WriteContext& ctx) override;
  common::Result<StoredProfile> GetProfile(const std::string& name) const override;
  common::Result<std::string> GetProfileHash(const std::string& name) const override;
  common::Result<std::vector<StoredProfile>> ListProfiles() const override;
  common::Result<std::optional<DerivedProfile>> FindDerived(const MapRef& ref,
                                                            const std::string& profile_hash,
                                                            const std::string& code_version,
                                                            const LayerQuery& query) const override;
  common::Result<std::optional<StoredDerived>> FindDerivedTiles(
      const MapRef& ref, const std::string& profile_hash, const std::string& code_version,
      const std::vector<std::string>& layers, int tile_size = 100) const override;
  common::Result<std::vector<DerivedInfo>> ListDerived(const MapRef& ref) const override;
  common::Status PutDerived(const MapRef& ref, const DerivedProfile& derived,
                            const WriteContext& ctx) override;
  common::Status PutPlaces(const std::string& site, const std::vector<Place>& places,
                           const WriteContext& ctx) override;
  common::Result<std::vector<Place>> ListPlaces(const std::string& site) const override;
  common::Result<std::vector<std::string>> ListSites() const override;
  common::Result<std::vector<AuditEntry>> ListAudit(int limit) const override;
  common::Result<std::optional<AuditEntry>> FindRequest(const std::string& actor,
                                                        int64_t request_id) const override;
  /// PRAGMA integrity_check, PRAGMA foreign_key_check, the header, and every blob decoded
  /// against its checksum.
  common::Result<CheckReport> Check(const ProgressFn& progress = nullptr) const override;

  /// Copies the WAL into the database file (PASSIVE: never waits for readers) when something
  /// was written and nothing for `idle_s`. Returns true when it checkpointed.
  bool CheckpointIfIdle(double idle_s = 1.0);

  /// Removes blobs no version or cache refers to (never a referenced one), then VACUUMs.
  /// Returns the bytes the file shrank by.
  common::Result<int64_t> Vacuum(const ProgressFn& progress = nullptr);
  /// Raw stored bytes of every blob referenced by a version's base layers, by "layer/tx/ty":
  /// lets tests and `cairn-map check` prove that base blobs never change.
  common::Result<std::map<std::string, std::string>> BaseBlobBytes(const MapRef& ref) const;
  /// Total stored (compressed) bytes of a version's base layers.
  common::Result<int64_t> BaseBytes(const MapRef& ref) const;

  const std::string& path() const { return path_; }
  int schema_version() const { return schema_version_; }
  /// Why this store cannot write its file ("'<path>' is read-only for this process: the file
  /// is not writable (Permission denied)"), or empty when it can (or was opened read-only on
  /// purpose).
  const std::string& write_refusal() const { return write_refusal_; }
  /// The SQLite synchronous level in effect (1 NORMAL, 2 FULL; 0 OFF), for tests and logs.
  common::Result<int64_t> SynchronousLevel() const;

 private:
  // Rows and the blobs of a save (mapstore/sqlite_store_rows.h).
  struct VersionRow;
  struct TileRow;
  struct DerivedHeader;
  struct EncodedTiles;
  SqliteMapStore(std::string path, SqliteOptions options, std::unique_ptr<sqlite::Database> db);

  // ---- Opening (sqlite_map_store.cc) ----
  common::Status Initialise();
  common::Status InitialiseReadOnly(bool empty, int64_t version);
  /// kCorrupt naming the first table or column of the current schema the file lacks.
  common::Status VerifySchema();
  common::Status InitialiseWritable(bool empty, int64_t version);
  /// Runs `body` inside BEGIN IMMEDIATE ... COMMIT, retrying while the database is busy.
  common::Status WriteTransaction(const std::function<common::Status()>& body);
  /// A failed write with what was being done, the file and the reason; a full disk says "disk
  /// full" and that nothing was lost.
  common::Status WriteError(const common::Status& s, const std::string& what) const;
  /// A failed read (damaged page or blob, I/O error) with the file named and how to find every
  /// damaged map; other statuses unchanged.
  common::Status Located(const common::Status& s) const;

  // ---- Version rows (sqlite_map_store.cc): the one decoder of a kVersionSelect row ----
  static VersionRow ReadVersionRow(const sqlite::Statement& st);
  common::Result<VersionRow> Resolve(const MapRef& ref) const;
  /// Why `ref` resolves to no version: no such map, deleted, or no such version.
  common::Status NoVersion(const MapRef& ref) const;
  common::Result<MapInfo> InfoOf(const VersionRow& row) const;
  common::Result<int64_t> SiteId(const std::string& site, bool create, int64_t utime);
  common::Status Audit(const WriteContext& ctx, int64_t utime, const std::string& op,
                       const std::string& site, const std::string& map, int64_t version,
                       const std::string& detail);

  // ---- Saves (sqlite_save.cc) ----
  /// Every tile of `layers` compressed and checksummed (all-unknown ones left out), or, where
  /// `caller` holds a compressed blob for it (layer-major, as the tiles are ordered), that blob
  /// adopted: at once when `caller_checked`, else when its CRC is that of the cells.
  EncodedTiles EncodeLayers(const common::GridMap& layers, int tile_size,
                            const std::vector<const StoredTile*>& caller,
                            bool caller_checked) const;
  /// EncodeLayers of a snapshot's base (adopting its encoded layers) and its OctoMap.
  EncodedTiles EncodeSnapshot(const MapSnapshot& snapshot) const;
  /// Inserts the site, map and version rows; (version, version row id).
  common::Result<std::pair<int64_t, int64_t>> InsertVersion(const MapSnapshot& snapshot,
                                                            int64_t now);
  common::Status InsertLayerTiles(int64_t version_id, const EncodedTiles& tiles);
  common::Status InsertObstacles(int64_t version_id, const common::ObstacleRegistry& registry);
  common::Status InsertOctomap(int64_t version_id, const EncodedBlob& blob,
                               const OctomapData& octomap);
  /// Writes blobs (or finds identical ones) and returns their ids.
  common::Status WriteBlobs(const std::vector<EncodedBlob>& blobs, std::vector<int64_t>* ids);

  // ---- Layers and tiles (sqlite_layers.cc): the one decoder of a kTileColumns row ----
  static TileRow ReadTileRow(const sqlite::Statement& st);
  /// Layer ids of a version by name; fills an empty `wanted` with every layer, and gives
  /// kNotFound for a wanted layer the version lacks.
  common::Result<std::map<std::string, int64_t>> LayerIds(const MapRef& ref, const VersionRow& row,
                                                          std::vector<std::string>* wanted) const;
  /// Reads the tiles a bound statement yields (kTileColumns) into `layer`, which covers `box`
  /// of the full grid and starts all unknown.
  common::Status ReadTiles(sqlite::Statement* stmt, const std::string& label, int tile_size,
                           const common::GridGeometry& full, const CellBox& box,
                           common::Layer* layer) const;
  /// Appends the tiles a bound statement yields (row by row) to `layer` as stored, checking
  /// their place and size; `label` names the layer in errors.
  common::Status ReadStoredTiles(sqlite::Statement* stmt, const std::string& label,
                                 const VersionRow& row, StoredLayer* layer) const;
  /// Decodes every tile of `layers` against its checksum (in parallel), naming the first bad one.
  common::Status CheckStoredLayers(const std::vector<StoredLayer>& layers,
                                   const std::string& label) const;

  // ---- The derived cache (sqlite_derived.cc) ----
  /// The cache entry of (version, profile hash, code version): its id, profile name, creation
  /// time, registry and layer names; nullopt on a miss.
  common::Result<std::optional<DerivedHeader>> FindDerivedHeader(
      const VersionRow& row, const std::string& profile_hash,
      const std::string& code_version) const;
  /// Resolve and FindDerivedHeader together: the version and its cache entry, nullopt on a
  /// miss. The caller holds mutex_.
  common::Result<std::optional<std::pair<VersionRow, DerivedHeader>>> ResolveDerived(
      const MapRef& ref, const std::string& profile_hash, const std::string& code_version) const;
  common::Status InsertDerived(const VersionRow& row, const DerivedProfile& derived,
                               const EncodedTiles& tiles, const EncodedBlob& registry, int64_t now);

  // ---- The integrity check (sqlite_catalog.cc) ----
  /// PRAGMA integrity_check (`*go_on` false when the file is too damaged to go on), foreign
  /// keys and the header.
  common::Status CheckPragmas(CheckReport* report, bool* go_on) const;
  common::Status CheckTilePlaces(CheckReport* report) const;
  common::Status CheckBlobs(CheckReport* report, const ProgressFn& progress) const;
  /// What refers to a blob: "map lab/yard v2 layer elevation tile (1, 0)", a derived cache's
  /// layer tile or registry, an OctoMap; "unreferenced" when nothing does.
  std::vector<std::string> BlobUsers(int64_t blob_id) const;
  /// The table or index whose b-tree has this root page ("table blobs", "index x of table y");
  /// empty when none.
  std::string RootOwner(int64_t root_page) const;
  /// The table or index a database page belongs to ("page 12 belongs to table blobs"), from the
  /// dbstat virtual table; empty when it cannot tell (a free page, dbstat missing or failing).
  std::string PageOwner(int64_t page) const;

  std::string path_;
  SqliteOptions options_;
  std::unique_ptr<sqlite::Database> db_;
  std::string write_refusal_;  // why writes are refused (a file this process cannot write)
  int schema_version_{0};
  bool dirty_{false};  // written since the last checkpoint
  int64_t last_write_utime_{0};
  mutable std::mutex mutex_;
};

}  // namespace cairn::mapstore
