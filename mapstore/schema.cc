#include "mapstore/schema.h"

#include <string>

#include <sqlite3.h>

#include "common/crc32.h"
#include "common/robot_profile.h"
#include "mapstore/blob_codec.h"

namespace cairn::mapstore::schema {
namespace {

constexpr char kSchemaV2[] = R"SQL(
CREATE TABLE sites(
  id INTEGER PRIMARY KEY,
  name TEXT NOT NULL UNIQUE,
  created_utime INTEGER NOT NULL);

CREATE TABLE maps(
  id INTEGER PRIMARY KEY,
  site_id INTEGER NOT NULL REFERENCES sites(id),
  name TEXT NOT NULL,
  created_utime INTEGER NOT NULL,
  UNIQUE(site_id, name));

CREATE TABLE map_versions(
  id INTEGER PRIMARY KEY,
  map_id INTEGER NOT NULL REFERENCES maps(id),
  version INTEGER NOT NULL CHECK(version > 0),
  source_robot TEXT NOT NULL,
  source_profile TEXT NOT NULL,
  source_profile_hash TEXT NOT NULL,
  code_version TEXT NOT NULL,
  parameters TEXT NOT NULL,
  created_utime INTEGER NOT NULL,
  resolution_m REAL NOT NULL CHECK(resolution_m > 0),
  size_x INTEGER NOT NULL CHECK(size_x > 0),
  size_y INTEGER NOT NULL CHECK(size_y > 0),
  origin_x_m REAL NOT NULL,
  origin_y_m REAL NOT NULL,
  origin_yaw_rad REAL NOT NULL,
  tile_size INTEGER NOT NULL CHECK(tile_size > 0),
  deleted_utime INTEGER,
  UNIQUE(map_id, version));

CREATE TABLE blobs(
  id INTEGER PRIMARY KEY,
  key TEXT NOT NULL UNIQUE,
  codec INTEGER NOT NULL,
  raw_size INTEGER NOT NULL CHECK(raw_size >= 0),
  raw_crc32 INTEGER NOT NULL,
  data BLOB NOT NULL);

CREATE TABLE layers(
  id INTEGER PRIMARY KEY,
  map_version_id INTEGER NOT NULL REFERENCES map_versions(id),
  name TEXT NOT NULL,
  UNIQUE(map_version_id, name));

CREATE TABLE layer_tiles(
  layer_id INTEGER NOT NULL REFERENCES layers(id),
  tile_ix INTEGER NOT NULL,
  tile_iy INTEGER NOT NULL,
  blob_id INTEGER NOT NULL REFERENCES blobs(id),
  PRIMARY KEY(layer_id, tile_iy, tile_ix)) WITHOUT ROWID;
CREATE INDEX layer_tiles_blob ON layer_tiles(blob_id);

CREATE TABLE obstacles(
  map_version_id INTEGER NOT NULL REFERENCES map_versions(id),
  obstacle_id INTEGER NOT NULL,
  kind INTEGER NOT NULL CHECK(kind BETWEEN 1 AND 5),
  centroid_x_m REAL,
  centroid_y_m REAL,
  slope_rad REAL,
  height_m REAL,
  width_m REAL,
  length_m REAL,
  depth_m REAL,
  area_m2 REAL,
  num_cells INTEGER NOT NULL,
  outline BLOB NOT NULL,
  PRIMARY KEY(map_version_id, obstacle_id)) WITHOUT ROWID;

CREATE TABLE obstacle_verdicts(
  map_version_id INTEGER NOT NULL,
  obstacle_id INTEGER NOT NULL,
  profile TEXT NOT NULL,
  profile_hash TEXT NOT NULL,
  crossable INTEGER NOT NULL,
  reason TEXT NOT NULL,
  PRIMARY KEY(map_version_id, obstacle_id, profile),
  FOREIGN KEY(map_version_id, obstacle_id) REFERENCES obstacles(map_version_id, obstacle_id))
  WITHOUT ROWID;

CREATE TABLE octomaps(
  map_version_id INTEGER PRIMARY KEY REFERENCES map_versions(id),
  binary INTEGER NOT NULL,
  resolution_m REAL NOT NULL,
  blob_id INTEGER NOT NULL REFERENCES blobs(id));
CREATE INDEX octomaps_blob ON octomaps(blob_id);

CREATE TABLE profiles(
  id INTEGER PRIMARY KEY,
  name TEXT NOT NULL,
  content_hash TEXT NOT NULL,
  yaml TEXT NOT NULL,
  created_utime INTEGER NOT NULL,
  UNIQUE(name, content_hash));

CREATE TABLE derived(
  id INTEGER PRIMARY KEY,
  map_version_id INTEGER NOT NULL REFERENCES map_versions(id),
  profile_hash TEXT NOT NULL,
  code_version TEXT NOT NULL,
  profile_name TEXT NOT NULL,
  created_utime INTEGER NOT NULL,
  size_x INTEGER NOT NULL,
  size_y INTEGER NOT NULL,
  registry_blob_id INTEGER NOT NULL REFERENCES blobs(id),
  UNIQUE(map_version_id, profile_hash, code_version));
CREATE INDEX derived_registry_blob ON derived(registry_blob_id);

CREATE TABLE derived_layers(
  derived_id INTEGER NOT NULL REFERENCES derived(id),
  name TEXT NOT NULL,
  PRIMARY KEY(derived_id, name)) WITHOUT ROWID;

CREATE TABLE derived_tiles(
  derived_id INTEGER NOT NULL REFERENCES derived(id),
  layer TEXT NOT NULL,
  tile_ix INTEGER NOT NULL,
  tile_iy INTEGER NOT NULL,
  blob_id INTEGER NOT NULL REFERENCES blobs(id),
  PRIMARY KEY(derived_id, layer, tile_iy, tile_ix)) WITHOUT ROWID;
CREATE INDEX derived_tiles_blob ON derived_tiles(blob_id);

CREATE TABLE places(
  site_id INTEGER NOT NULL REFERENCES sites(id),
  name TEXT NOT NULL,
  polygon BLOB NOT NULL,
  updated_utime INTEGER NOT NULL,
  PRIMARY KEY(site_id, name)) WITHOUT ROWID;

CREATE TABLE audit_log(
  id INTEGER PRIMARY KEY,
  utime INTEGER NOT NULL,
  actor TEXT NOT NULL,
  op TEXT NOT NULL,
  site TEXT NOT NULL,
  map TEXT NOT NULL,
  version INTEGER NOT NULL,
  request_id INTEGER NOT NULL,
  detail TEXT NOT NULL);
CREATE INDEX audit_request ON audit_log(actor, request_id);

CREATE TRIGGER blobs_immutable BEFORE UPDATE ON blobs
  BEGIN SELECT RAISE(ABORT, 'stored blobs are immutable'); END;
CREATE TRIGGER layer_tiles_immutable BEFORE UPDATE ON layer_tiles
  BEGIN SELECT RAISE(ABORT, 'stored tiles are immutable'); END;
CREATE TRIGGER layer_tiles_kept BEFORE DELETE ON layer_tiles
  BEGIN SELECT RAISE(ABORT, 'stored tiles are never deleted'); END;
CREATE TRIGGER map_versions_immutable BEFORE UPDATE OF
  id, map_id, version, source_robot, source_profile, source_profile_hash, code_version, parameters,
  created_utime, resolution_m, size_x, size_y, origin_x_m, origin_y_m, origin_yaw_rad, tile_size
  ON map_versions
  BEGIN SELECT RAISE(ABORT, 'map versions are immutable'); END;
)SQL";

// Version 2 -> 3, the schema part: every blob row records StoredBlobCrc32 of itself, so a read
// can check a blob without decompressing it. NULL means not recorded (a reader then decodes).
constexpr char kSchemaV2ToV3[] = R"SQL(
ALTER TABLE blobs ADD COLUMN stored_crc32 INTEGER;
)SQL";

// Version 3 -> 4: obstacles may be terraces (kind 6) and carry their parts (SerializeParts; NULL
// for every other kind) and a downhill heading (NULL: none). SQLite cannot change a CHECK in place:
// the verdicts and obstacles are copied aside, the table is made again and both are copied back
// (children first out, last in, so no foreign key is ever broken).
constexpr char kSchemaV3ToV4[] = R"SQL(
CREATE TEMP TABLE v3_obstacles AS SELECT * FROM main.obstacles;
CREATE TEMP TABLE v3_obstacle_verdicts AS SELECT * FROM main.obstacle_verdicts;
DELETE FROM main.obstacle_verdicts;
DROP TABLE main.obstacles;
CREATE TABLE main.obstacles(
  map_version_id INTEGER NOT NULL REFERENCES map_versions(id),
  obstacle_id INTEGER NOT NULL,
  kind INTEGER NOT NULL CHECK(kind BETWEEN 1 AND 6),
  centroid_x_m REAL,
  centroid_y_m REAL,
  slope_rad REAL,
  height_m REAL,
  width_m REAL,
  length_m REAL,
  depth_m REAL,
  area_m2 REAL,
  num_cells INTEGER NOT NULL,
  outline BLOB NOT NULL,
  parts BLOB,
  downhill_heading_rad REAL,
  PRIMARY KEY(map_version_id, obstacle_id)) WITHOUT ROWID;
INSERT INTO main.obstacles(map_version_id, obstacle_id, kind, centroid_x_m, centroid_y_m,
    slope_rad, height_m, width_m, length_m, depth_m, area_m2, num_cells, outline, parts,
    downhill_heading_rad)
  SELECT map_version_id, obstacle_id, kind, centroid_x_m, centroid_y_m, slope_rad, height_m,
         width_m, length_m, depth_m, area_m2, num_cells, outline, NULL, NULL
  FROM temp.v3_obstacles;
INSERT INTO main.obstacle_verdicts SELECT * FROM temp.v3_obstacle_verdicts;
DROP TABLE temp.v3_obstacles;
DROP TABLE temp.v3_obstacle_verdicts;
)SQL";

// The version 2 tables, for the version 1 migration (later steps then apply as for any version 2
// file).
common::Status CreateV2(sqlite::Database* db) { return db->Exec(kSchemaV2); }

// The audit line of one migration step.
common::Status AuditMigration(sqlite::Database* db, int64_t utime, const std::string& detail) {
  sqlite::Statement audit = db->Prepare(
      "INSERT INTO audit_log(utime, actor, op, site, map, version, request_id, detail) "
      "VALUES(?, 'cairn-mapstore', 'migrate', '', '', 0, 0, ?)");
  audit.Bind(1, utime).Bind(2, detail);
  return audit.Run();
}

// Version 1 -> 2, rows: sites, maps, versions with full provenance, layers and obstacles.
common::Status MoveV1Rows(sqlite::Database* db) {
  common::Status s;
  s = db->Exec(R"SQL(
    INSERT INTO sites(id, name, created_utime) SELECT id, name, created_utime FROM v1_sites;
    INSERT INTO maps(site_id, name, created_utime)
      SELECT site_id, name, MIN(created_utime) FROM v1_maps GROUP BY site_id, name;
    INSERT INTO map_versions(id, map_id, version, source_robot, source_profile,
        source_profile_hash, code_version, parameters, created_utime, resolution_m, size_x,
        size_y, origin_x_m, origin_y_m, origin_yaw_rad, tile_size, deleted_utime)
      SELECT v.id, m.id, v.version, v.source_robot, v.source_profile, '', 'unknown (schema 1)',
             '', v.created_utime, v.resolution_m, v.size_x, v.size_y, v.origin_x_m, v.origin_y_m,
             v.origin_yaw_rad, v.tile_size, CASE WHEN v.deleted != 0 THEN v.created_utime END
      FROM v1_maps v JOIN maps m ON m.site_id = v.site_id AND m.name = v.name;
    INSERT INTO layers(map_version_id, name) SELECT DISTINCT map_id, layer FROM v1_tiles;
    INSERT INTO obstacles(map_version_id, obstacle_id, kind, centroid_x_m, centroid_y_m,
        slope_rad, height_m, width_m, length_m, depth_m, area_m2, num_cells, outline)
      SELECT map_id, obstacle_id, kind, centroid_x_m, centroid_y_m, slope_rad, height_m, width_m,
             length_m, depth_m, area_m2, num_cells, X'' FROM v1_obstacles;
  )SQL");
  return s;
}

// Version 1 -> 2, tiles: their data move into blobs under their content address.
common::Status MoveV1Tiles(sqlite::Database* db) {
  common::Status s;
  sqlite::Statement read = db->Prepare(
      "SELECT t.map_id, t.layer, t.tile_ix, t.tile_iy, t.codec, t.raw_size, t.crc32, t.data, "
      "l.id FROM v1_tiles t JOIN layers l ON l.map_version_id = t.map_id AND l.name = t.layer");
  sqlite::Statement insert_blob = db->Prepare(
      "INSERT INTO blobs(key, codec, raw_size, raw_crc32, data) VALUES(?, ?, ?, ?, ?) "
      "ON CONFLICT(key) DO NOTHING");
  sqlite::Statement find_blob = db->Prepare("SELECT id FROM blobs WHERE key = ?");
  sqlite::Statement insert_tile = db->Prepare(
      "INSERT INTO layer_tiles(layer_id, tile_ix, tile_iy, blob_id) VALUES(?, ?, ?, ?)");
  while (read.Step()) {
    const std::string data = read.Blob(7);
    const uint32_t raw_crc = static_cast<uint32_t>(read.Int(6));
    const std::string key = [&] {
      char buf[64];
      std::snprintf(buf, sizeof(buf), "%08x-%08x-%lld", raw_crc,
                    common::Crc32(data.data(), data.size()), static_cast<long long>(read.Int(5)));
      return std::string(buf);
    }();
    insert_blob.Reset();
    insert_blob.Bind(1, key).Bind(2, read.Int(4)).Bind(3, read.Int(5)).Bind(4, read.Int(6));
    insert_blob.BindBlob(5, data.data(), data.size());
    if (!(s = insert_blob.Run()).ok()) return s;
    find_blob.Reset();
    find_blob.Bind(1, key);
    if (!find_blob.Step()) return common::InternalError("migrated blob vanished");
    insert_tile.Reset();
    insert_tile.Bind(1, read.Int(8)).Bind(2, read.Int(2)).Bind(3, read.Int(3));
    insert_tile.Bind(4, find_blob.Int(0));
    if (!(s = insert_tile.Run()).ok()) return s;
  }
  if (!read.status().ok()) return read.status();
  return common::Status::Ok();
}

// Version 1 -> 2, profiles: re-read with today's loader so hashes and canonical text match new
// puts; a profile today's loader refuses is kept verbatim.
common::Status MoveV1Profiles(sqlite::Database* db) {
  common::Status s;
  sqlite::Statement read =
      db->Prepare("SELECT name, content_hash, yaml, updated_utime FROM v1_profiles");
  sqlite::Statement insert = db->Prepare(
      "INSERT OR IGNORE INTO profiles(name, content_hash, yaml, created_utime) "
      "VALUES(?, ?, ?, ?)");
  while (read.Step()) {
    std::string name = read.Text(0), hash = read.Text(1), yaml = read.Text(2);
    try {
      const common::RobotProfile p = common::LoadRobotProfileString(yaml, "profile " + name);
      hash = p.ContentHash();
      yaml = p.ToYaml();
    } catch (const std::exception&) {
    }
    insert.Reset();
    insert.Bind(1, name).Bind(2, hash).Bind(3, yaml).Bind(4, read.Int(3));
    if (!(s = insert.Run()).ok()) return s;
  }
  if (!read.status().ok()) return read.status();
  return common::Status::Ok();
}

// Version 1 -> 2: versions get their own table with full provenance, tile data move into the
// content-addressed blob table, and the new tables start empty.
common::Status MigrateV1ToV2(sqlite::Database* db, int64_t utime) {
  common::Status s = db->Exec(R"SQL(
    ALTER TABLE maps RENAME TO v1_maps;
    ALTER TABLE tiles RENAME TO v1_tiles;
    ALTER TABLE obstacles RENAME TO v1_obstacles;
    ALTER TABLE profiles RENAME TO v1_profiles;
    ALTER TABLE sites RENAME TO v1_sites;
  )SQL");
  if (s.ok()) s = CreateV2(db);
  if (s.ok()) s = MoveV1Rows(db);
  if (s.ok()) s = MoveV1Tiles(db);
  if (s.ok()) s = MoveV1Profiles(db);
  if (!s.ok()) return s;
  s = db->Exec(R"SQL(
    DROP TABLE v1_tiles;
    DROP TABLE v1_obstacles;
    DROP TABLE v1_maps;
    DROP TABLE v1_profiles;
    DROP TABLE v1_sites;
  )SQL");
  if (!s.ok()) return s;
  return AuditMigration(db, utime, "schema 1 -> 2");
}

// SQL function cairn_stored_crc32(codec, raw_size, raw_crc32, data): StoredBlobCrc32 of a row.
void StoredCrcFunction(sqlite3_context* context, int argc, sqlite3_value** argv) {
  if (argc != 4 || sqlite3_value_type(argv[3]) != SQLITE_BLOB) {
    sqlite3_result_error(context, "cairn_stored_crc32 takes (codec, raw_size, raw_crc32, data)",
                         -1);
    return;
  }
  const void* data = sqlite3_value_blob(argv[3]);
  const int size = sqlite3_value_bytes(argv[3]);
  const uint32_t crc = StoredBlobCrc32(sqlite3_value_int(argv[0]), sqlite3_value_int64(argv[1]),
                                       static_cast<uint32_t>(sqlite3_value_int64(argv[2])), data,
                                       static_cast<size_t>(size));
  sqlite3_result_int64(context, crc);
}

// Version 2 -> 3: the stored_crc32 column, filled in for every blob (the immutability trigger is
// lifted for that one statement, inside the migration's transaction).
common::Status MigrateV2ToV3(sqlite::Database* db, int64_t utime) {
  common::Status s = db->Exec(kSchemaV2ToV3);
  if (!s.ok()) return s;
  const int rc = sqlite3_create_function(db->raw(), "cairn_stored_crc32", 4,
                                         SQLITE_UTF8 | SQLITE_DETERMINISTIC, nullptr,
                                         &StoredCrcFunction, nullptr, nullptr);
  if (rc != SQLITE_OK)
    return sqlite::StatusFromCode(rc, "registering cairn_stored_crc32", db->raw());
  s = db->Exec(R"SQL(
    DROP TRIGGER blobs_immutable;
    UPDATE blobs SET stored_crc32 = cairn_stored_crc32(codec, raw_size, raw_crc32, data);
    CREATE TRIGGER blobs_immutable BEFORE UPDATE ON blobs
      BEGIN SELECT RAISE(ABORT, 'stored blobs are immutable'); END;
  )SQL");
  sqlite3_create_function(db->raw(), "cairn_stored_crc32", 4, SQLITE_UTF8, nullptr, nullptr,
                          nullptr, nullptr);
  if (!s.ok()) return s;
  return AuditMigration(db, utime, "schema 2 -> 3");
}

common::Status MigrateV3ToV4(sqlite::Database* db, int64_t utime) {
  common::Status s = db->Exec(kSchemaV3ToV4);
  if (!s.ok()) return s;
  return AuditMigration(db, utime, "schema 3 -> 4");
}

}  // namespace

common::Status Create(sqlite::Database* db) {
  common::Status s = db->Exec(kSchemaV2);
  if (!s.ok()) return s;
  s = db->Exec(kSchemaV2ToV3);
  if (!s.ok()) return s;
  s = db->Exec(kSchemaV3ToV4);
  if (!s.ok()) return s;
  return db->Exec("PRAGMA application_id = " + std::to_string(kApplicationId) +
                  "; PRAGMA user_version = " + std::to_string(kCurrentVersion) + ";");
}

common::Status Migrate(sqlite::Database* db, int from_version, int64_t utime) {
  for (int v = from_version; v < kCurrentVersion; ++v) {
    common::Status s;
    switch (v) {
      case 1:
        s = MigrateV1ToV2(db, utime);
        break;
      case 2:
        s = MigrateV2ToV3(db, utime);
        break;
      case 3:
        s = MigrateV3ToV4(db, utime);
        break;
      default:
        return common::InternalError("no migration from schema version " + std::to_string(v));
    }
    if (!s.ok()) {
      return common::Status(s.code(), "migration from schema " + std::to_string(v) + " to " +
                                          std::to_string(v + 1) + " failed: " + s.message());
    }
  }
  return db->Exec("PRAGMA user_version = " + std::to_string(kCurrentVersion));
}

}  // namespace cairn::mapstore::schema
