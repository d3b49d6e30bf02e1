#pragma once

#include <cstdint>
#include <string>

#include "common/token_buckets.h"
#include "common/yaml_reader.h"
#include "mapstore/save_assembler.h"
#include "mapstore/sqlite_map_store.h"

/// @file
/// cairn-mapstore's parameters (config/mapstore/mapstore.yaml): the service on the bus and the
/// SQLite database under it. Plain structs with their defaults; LoadMapstoreParams reads them
/// (every key optional, an unknown key is an error naming its line).

namespace cairn::mapstore {

/// How MapstoreService answers on the bus.
struct MapstoreServiceParams {
  std::string files_root{"var/mapstore-files"};  ///< OP_EXPORT/OP_IMPORT paths stay below it
  double save_timeout_s{20.0};                   ///< a save gives up waiting for tiles after this
  double resend_interval_s{0.05};                ///< asks again for missing tiles this often
  double staging_timeout_s{30.0};  ///< pushed data without a request are dropped after this
  double pull_settle_s{0.5};       ///< a pull without named layers waits this long for more
  int reply_cache_size{512};       ///< replies kept for replays
  /// OP_DELETE from the bus (a soft delete, in the audit log); off, it is refused (FORBIDDEN)
  /// with an audit line. `cairn-map delete` on the file is not affected.
  bool allow_delete{false};
  int max_queued_jobs{64};  ///< loads, shares, exports, imports waiting; more are refused (BUSY)
  /// Reply tiles resent on request, per requester and for every requester together; a request
  /// beyond is dropped (resend_rate_limited). A request for a whole layer counts as 200 tiles.
  common::TokenBucketsParams resend_limits;
  int64_t max_kept_reply_cells{64'000'000};  ///< reply tiles kept for resends (cells)
  int64_t max_staged_bytes{512LL << 20};     ///< pushed data held at once (SaveAssemblerParams)
  int max_pushes{64};                        ///< push names staged at once
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

  /// @throws std::invalid_argument naming the first bad field.
  void Validate() const;
  /// The save assembly's part of these parameters.
  SaveAssemblerParams save() const;
};

/// The database options of a long-running store: its WAL is checkpointed when idle, so commits
/// do not checkpoint before 16384 pages (128 MB) of WAL.
SqliteOptions ServiceDatabaseOptions();

/// Everything cairn-mapstore reads from its YAML file.
struct MapstoreParams {
  MapstoreServiceParams service;                     ///< `service:`
  SqliteOptions database{ServiceDatabaseOptions()};  ///< `database:`
};

/// Reads `service:` and `database:` (both optional). @throws common::ConfigError naming the
/// line of an unknown key or a bad value.
MapstoreParams LoadMapstoreParams(common::YamlMap& root);
/// LoadMapstoreParams of a file.
MapstoreParams LoadMapstoreParamsFile(const std::string& path);

}  // namespace cairn::mapstore
