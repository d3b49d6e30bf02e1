#pragma once

#include <cstdint>

#include "common/status.h"
#include "mapstore/sqlite_db.h"

/// @file
/// The SQLite schema of the map store and its migrations.
///
/// A cairn database carries PRAGMA application_id = kApplicationId ("CARN") and PRAGMA
/// user_version = its schema version. Opening a file with another application id is refused;
/// an older version is migrated step by step (1 -> 2 -> ...) in one transaction; a newer
/// version is refused.
///
/// Version 4 (current): version 3 whose obstacles may be terraces (kind 6) with their parts
/// (obstacles.parts, registry_codec.h SerializeParts; NULL for every other kind), and carry the
/// heading down a ramp or step (obstacles.downhill_heading_rad; NULL: none).
///
/// Version 3: version 2 with blobs.stored_crc32, StoredBlobCrc32 of each row (bytes and
/// header), so that a read checks a blob without decompressing it. Migrating from 2 fills it in.
/// See tests/unit/mapstore/fixtures/v2.db.
///
/// Version 2:
///   sites(id, name)                          one row per site
///   maps(id, site_id, name)                  one row per map name in a site
///   map_versions(id, map_id, version, provenance..., geometry..., tile_size, deleted_utime)
///                                            immutable (a trigger refuses updates, except the
///                                            soft-delete mark)
///   blobs(id, key, codec, raw_size, raw_crc32, data)
///                                            content-addressed, never updated (trigger)
///   layers(id, map_version_id, name), layer_tiles(layer_id, tile_ix, tile_iy, blob_id)
///                                            base layers, tiled; all-unknown tiles are absent
///   obstacles(map_version_id, obstacle_id, kind, measurements..., outline)
///   obstacle_verdicts(map_version_id, obstacle_id, profile, profile_hash, crossable, reason)
///   octomaps(map_version_id, binary, resolution_m, blob_id)
///   profiles(id, name, content_hash, yaml, created_utime)   every content ever stored
///   derived(id, map_version_id, profile_hash, code_version, profile_name, registry_blob_id),
///   derived_layers(derived_id, name), derived_tiles(derived_id, layer, tile_ix, tile_iy, blob_id)
///                                            the per-profile cache
///   places(site_id, name, polygon, updated_utime)
///   audit_log(id, utime, actor, op, site, map, version, request_id, detail)
///
/// Version 1 (kept readable through migration): maps(id, site_id, name, version, ...) with one
/// row per version, tiles(map_id, layer, tile_ix, tile_iy, codec, raw_size, crc32, data) holding
/// blobs inline, obstacles without outlines or verdicts, profiles(name, ...) with one row per
/// name. See tests/unit/mapstore/fixtures/v1.sql.

namespace cairn::mapstore::schema {

inline constexpr int64_t kApplicationId = 0x4341524E;  // "CARN"
inline constexpr int kCurrentVersion = 4;

/// Creates the current schema in an empty database (inside the caller's transaction).
common::Status Create(sqlite::Database* db);

/// Migrates from `from_version` to kCurrentVersion inside the caller's transaction.
/// `utime` stamps the audit entry of the migration.
common::Status Migrate(sqlite::Database* db, int from_version, int64_t utime);

}  // namespace cairn::mapstore::schema
