#include "mapstore/sqlite_map_store.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <set>
#include <thread>

#include <sqlite3.h>

#include "common/crc32.h"
#include "mapstore/names.h"
#include "mapstore/schema.h"
#include "mapstore/store_util.h"

namespace cairn::mapstore {

namespace fs = std::filesystem;
using common::Result;
using common::Status;

namespace {

constexpr char kVersionSelect[] =
    "SELECT v.id, v.map_id, m.site_id, s.name, m.name, v.version, v.source_robot, "
    "v.source_profile, v.source_profile_hash, v.code_version, v.parameters, v.created_utime, "
    "v.resolution_m, v.size_x, v.size_y, v.origin_x_m, v.origin_y_m, v.origin_yaw_rad, "
    "v.tile_size, v.deleted_utime IS NOT NULL "
    "FROM map_versions v JOIN maps m ON m.id = v.map_id JOIN sites s ON s.id = m.site_id ";

constexpr char kTileColumns[] =
    "t.tile_ix, t.tile_iy, b.codec, b.raw_size, b.raw_crc32, b.data, b.stored_crc32";

// Adds context to a failed write; a full disk also says that nothing was lost.
Status WriteError(const Status& s, const std::string& what) {
  if (s.code() == common::StatusCode::kResourceExhausted) {
    return common::ResourceExhaustedError(
        what +
        ": the disk is full (or the database quota is reached); nothing of this change "
        "was written and everything committed before is intact (" +
        s.message() + ")");
  }
  if (s.code() == common::StatusCode::kUnavailable) {
    return common::UnavailableError(what + ": the database stayed locked by another writer (" +
                                    s.message() + ")");
  }
  return Status(s.code(), what + ": " + s.message());
}

std::string JournalMode(sqlite::Database* db, const std::string& mode) {
  sqlite::Statement st = db->Prepare("PRAGMA journal_mode = " + mode);
  return st.Step() ? st.Text(0) : "";
}

// Reads one blob row (codec, raw_size, raw_crc32, data at columns first..first+3) and decodes it.
struct RawTile {
  int tile_ix{0};
  int tile_iy{0};
  Codec codec{Codec::kRaw};
  int64_t raw_size{0};
  uint32_t raw_crc32{0};
  std::string data;
};

}  // namespace

struct SqliteMapStore::VersionRow {
  int64_t id{0};
  int64_t map_id{0};
  int64_t site_id{0};
  std::string site;
  std::string name;
  int64_t version{0};
  Provenance provenance;
  common::GridGeometry geometry;
  int tile_size{0};
  bool deleted{false};
};

SqliteMapStore::SqliteMapStore(std::string path, SqliteOptions options,
                               std::unique_ptr<sqlite::Database> db)
    : path_(std::move(path)), options_(options), db_(std::move(db)) {}

SqliteMapStore::~SqliteMapStore() = default;

Result<std::unique_ptr<SqliteMapStore>> SqliteMapStore::Open(const std::string& path,
                                                             const SqliteOptions& options) {
  if (options.tile_size_cells <= 0 || options.tile_size_cells > 250) {
    return common::InvalidArgumentError(
        "tile_size_cells must be in 1..250 (a tile must fit one "
        "message on the bus)");
  }
  const bool memory = path == ":memory:";
  if (path.empty()) return common::InvalidArgumentError("no database path given");
  if (!memory) {
    std::error_code ec;
    const bool exists = fs::exists(path, ec);
    if (!exists && (options.read_only || !options.create_if_missing)) {
      return common::NotFoundError("no database at '" + path + "'");
    }
    if (exists && !fs::is_regular_file(path, ec)) {
      return common::InvalidArgumentError("'" + path + "' is not a regular file");
    }
  }
  auto db = sqlite::Database::Open(path, options.read_only, options.create_if_missing);
  if (!db.ok()) return db.status();
  std::unique_ptr<SqliteMapStore> store(new SqliteMapStore(path, options, std::move(db).value()));
  Status s = store->Initialise();
  if (!s.ok()) return s;
  return store;
}

Status SqliteMapStore::Initialise() {
  Status s = db_->Exec("PRAGMA busy_timeout = " + std::to_string(options_.busy_timeout_ms));
  if (!s.ok()) return s;
  const auto not_cairn = [&](const std::string& why) {
    return common::CorruptError("'" + path_ + "' is not a cairn map database: " + why);
  };
  // The three header reads share one read transaction: another process creating the schema
  // commits tables, application id and version together, and this one must see all or none.
  s = db_->Exec("BEGIN");
  if (!s.ok()) return s;
  auto app = db_->QueryInt("PRAGMA application_id");
  auto version = db_->QueryInt("PRAGMA user_version");
  auto tables = db_->QueryInt("SELECT count(*) FROM sqlite_master");
  db_->Exec("COMMIT");
  if (!app.ok()) return not_cairn(app.status().message());
  if (!version.ok()) return not_cairn(version.status().message());
  if (!tables.ok()) return not_cairn(tables.status().message());
  const bool memory = path_ == ":memory:";

  const bool empty = *app == 0 && *version == 0 && *tables == 0;
  if (!empty && *app != schema::kApplicationId) {
    char buf[64];
    std::snprintf(buf, sizeof(buf), "application_id 0x%08llx, expected 0x%08llx",
                  static_cast<unsigned long long>(*app),
                  static_cast<unsigned long long>(schema::kApplicationId));
    return not_cairn(buf);
  }
  if (*version > schema::kCurrentVersion) {
    return common::InvalidArgumentError("'" + path_ + "' has schema version " +
                                        std::to_string(*version) + ", newer than this build's " +
                                        std::to_string(schema::kCurrentVersion) +
                                        "; use a newer cairn");
  }
  if (options_.read_only) {
    if (empty) return common::InvalidArgumentError("'" + path_ + "' is an empty database");
    if (*version < schema::kCurrentVersion) {
      return common::InvalidArgumentError(
          "'" + path_ + "' has schema version " + std::to_string(*version) +
          "; open it for writing once (for example `cairn-map migrate --db " + path_ +
          "`) to migrate it to version " + std::to_string(schema::kCurrentVersion));
    }
    s = db_->Exec("PRAGMA query_only = 1; PRAGMA foreign_keys = ON; PRAGMA cache_size = -" +
                  std::to_string(options_.cache_size_kib));
    schema_version_ = static_cast<int>(*version);
    return s;
  }

  // Writable: WAL first (page size only matters for a new file), then create or migrate inside
  // one IMMEDIATE transaction that re-reads the version, in case another process got there first.
  if (empty) db_->Exec("PRAGMA page_size = 8192");
  if (!memory) {
    std::string mode;
    for (int attempt = 0; attempt < options_.write_attempts && mode != "wal"; ++attempt) {
      mode = JournalMode(db_.get(), "WAL");
      if (mode != "wal") std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    if (mode != "wal") {
      return common::UnavailableError("cannot switch '" + path_ + "' to WAL journaling");
    }
  }
  s = db_->Exec(std::string("PRAGMA foreign_keys = ON; PRAGMA synchronous = ") +
                (options_.synchronous_full ? "FULL" : "NORMAL") + "; PRAGMA cache_size = -" +
                std::to_string(options_.cache_size_kib));
  if (!s.ok()) return s;
  if (!memory) {
    s = db_->Exec("PRAGMA wal_autocheckpoint = " +
                  std::to_string(options_.wal_autocheckpoint_pages));
    if (!s.ok()) return s;
  }
  if (options_.max_page_count > 0) {
    s = db_->Exec("PRAGMA max_page_count = " + std::to_string(options_.max_page_count));
    if (!s.ok()) return s;
  }
  if (*version < schema::kCurrentVersion) {
    s = WriteTransaction([&]() -> Status {
      auto now_version = db_->QueryInt("PRAGMA user_version");
      auto now_tables = db_->QueryInt("SELECT count(*) FROM sqlite_master");
      if (!now_version.ok()) return now_version.status();
      if (!now_tables.ok()) return now_tables.status();
      if (*now_version == schema::kCurrentVersion) return Status::Ok();
      if (*now_version == 0 && *now_tables == 0) return schema::Create(db_.get());
      return schema::Migrate(db_.get(), static_cast<int>(*now_version), WallUtime());
    });
    if (!s.ok()) return WriteError(s, "cannot initialise '" + path_ + "'");
  }
  schema_version_ = schema::kCurrentVersion;
  return Status::Ok();
}

Status SqliteMapStore::WriteTransaction(const std::function<Status()>& body) {
  if (options_.read_only) {
    return common::InvalidArgumentError("the database '" + path_ + "' is open read-only");
  }
  Status s;
  for (int attempt = 0; attempt < std::max(1, options_.write_attempts); ++attempt) {
    {
      sqlite::Transaction txn(db_.get());
      s = txn.Begin();
      if (s.ok()) {
        try {
          s = body();
        } catch (const std::exception& e) {
          s = common::InternalError(e.what());
        }
        if (s.ok()) s = txn.Commit();
      }
    }
    if (s.ok()) {
      dirty_ = true;
      last_write_utime_ = WallUtime();
    }
    if (s.ok() || s.code() != common::StatusCode::kUnavailable) return s;
    std::this_thread::sleep_for(std::chrono::milliseconds(std::min(500, 20 << attempt)));
  }
  return s;
}

Result<SqliteMapStore::VersionRow> SqliteMapStore::Resolve(const MapRef& ref) const {
  Status s = ValidateName("site name", ref.site);
  if (!s.ok()) return s;
  if (!(s = ValidateName("map name", ref.name)).ok()) return s;
  if (ref.version < 0) return common::InvalidArgumentError("map version must be >= 0 (0 = latest)");
  sqlite::Statement st = db_->Prepare(
      std::string(kVersionSelect) +
      (ref.version == 0 ? "WHERE s.name = ? AND m.name = ? AND v.deleted_utime IS NULL "
                          "ORDER BY v.version DESC LIMIT 1"
                        : "WHERE s.name = ? AND m.name = ? AND v.version = ?"));
  st.Bind(1, ref.site).Bind(2, ref.name);
  if (ref.version != 0) st.Bind(3, ref.version);
  if (!st.Step()) {
    if (!st.status().ok()) return st.status();
    sqlite::Statement any = db_->Prepare(
        "SELECT count(*) FROM map_versions v JOIN maps m ON m.id = v.map_id JOIN sites s ON "
        "s.id = m.site_id WHERE s.name = ? AND m.name = ?");
    any.Bind(1, ref.site).Bind(2, ref.name);
    const int64_t versions = any.Step() ? any.Int(0) : 0;
    if (versions == 0) {
      return common::NotFoundError("no map '" + ref.name + "' in site '" + ref.site + "'");
    }
    if (ref.version == 0) {
      return common::NotFoundError("map '" + ref.site + "/" + ref.name + "' is deleted");
    }
    return common::NotFoundError("map '" + ref.site + "/" + ref.name + "' has no version " +
                                 std::to_string(ref.version));
  }
  VersionRow row;
  row.id = st.Int(0);
  row.map_id = st.Int(1);
  row.site_id = st.Int(2);
  row.site = st.Text(3);
  row.name = st.Text(4);
  row.version = st.Int(5);
  row.provenance.source_robot = st.Text(6);
  row.provenance.source_profile = st.Text(7);
  row.provenance.source_profile_hash = st.Text(8);
  row.provenance.code_version = st.Text(9);
  row.provenance.parameters = st.Text(10);
  row.provenance.created_utime = st.Int(11);
  row.geometry.resolution_m = st.Double(12);
  row.geometry.size_x = static_cast<int>(st.Int(13));
  row.geometry.size_y = static_cast<int>(st.Int(14));
  row.geometry.origin = {st.Double(15), st.Double(16), st.Double(17)};
  row.tile_size = static_cast<int>(st.Int(18));
  row.deleted = st.Int(19) != 0;
  if (row.deleted) {
    return common::NotFoundError("map '" + ref.site + "/" + ref.name + "' version " +
                                 std::to_string(row.version) + " is deleted");
  }
  return row;
}

Result<MapInfo> SqliteMapStore::InfoOf(const VersionRow& row) const {
  MapInfo info;
  info.site = row.site;
  info.name = row.name;
  info.version = row.version;
  info.provenance = row.provenance;
  info.geometry = row.geometry;
  info.tile_size = row.tile_size;
  info.deleted = row.deleted;
  sqlite::Statement layers =
      db_->Prepare("SELECT name FROM layers WHERE map_version_id = ? ORDER BY name");
  layers.Bind(1, row.id);
  while (layers.Step()) info.layers.push_back(layers.Text(0));
  if (!layers.status().ok()) return layers.status();
  sqlite::Statement counts = db_->Prepare(
      "SELECT (SELECT count(*) FROM obstacles WHERE map_version_id = ?1), "
      "(SELECT count(*) FROM octomaps WHERE map_version_id = ?1)");
  counts.Bind(1, row.id);
  if (!counts.Step())
    return counts.status().ok() ? common::InternalError("count") : counts.status();
  info.num_obstacles = static_cast<int>(counts.Int(0));
  info.has_octomap = counts.Int(1) > 0;
  return info;
}

Result<int64_t> SqliteMapStore::SiteId(const std::string& site, bool create, int64_t utime) {
  sqlite::Statement find = db_->Prepare("SELECT id FROM sites WHERE name = ?");
  find.Bind(1, site);
  if (find.Step()) return find.Int(0);
  if (!find.status().ok()) return find.status();
  if (!create) return common::NotFoundError("no site '" + site + "'");
  sqlite::Statement insert = db_->Prepare("INSERT INTO sites(name, created_utime) VALUES(?, ?)");
  insert.Bind(1, site).Bind(2, utime);
  Status s = insert.Run();
  if (!s.ok()) return s;
  return db_->LastInsertRowId();
}

Status SqliteMapStore::WriteBlobs(const std::vector<EncodedBlob>& blobs,
                                  std::vector<int64_t>* ids) {
  sqlite::Statement find = db_->Prepare("SELECT id FROM blobs WHERE key = ?");
  sqlite::Statement insert = db_->Prepare(
      "INSERT INTO blobs(key, codec, raw_size, raw_crc32, data, stored_crc32) "
      "VALUES(?, ?, ?, ?, ?, ?)");
  ids->clear();
  ids->reserve(blobs.size());
  for (const EncodedBlob& b : blobs) {
    find.Reset();
    find.Bind(1, b.key);
    if (find.Step()) {
      ids->push_back(find.Int(0));
      continue;
    }
    if (!find.status().ok()) return find.status();
    insert.Reset();
    insert.Bind(1, b.key).Bind(2, static_cast<int64_t>(b.codec)).Bind(3, b.raw_size);
    insert.Bind(4, static_cast<int64_t>(b.raw_crc32)).BindBlob(5, b.data.data(), b.data.size());
    insert.Bind(6, static_cast<int64_t>(b.stored_crc32));
    Status s = insert.Run();
    if (!s.ok()) return s;
    ids->push_back(db_->LastInsertRowId());
  }
  return Status::Ok();
}

Status SqliteMapStore::Audit(const WriteContext& ctx, int64_t utime, const std::string& op,
                             const std::string& site, const std::string& map, int64_t version,
                             const std::string& detail) {
  sqlite::Statement st = db_->Prepare(
      "INSERT INTO audit_log(utime, actor, op, site, map, version, request_id, detail) "
      "VALUES(?, ?, ?, ?, ?, ?, ?, ?)");
  st.Bind(1, utime).Bind(2, ctx.actor.empty() ? std::string("unknown") : ctx.actor).Bind(3, op);
  st.Bind(4, site).Bind(5, map).Bind(6, version).Bind(7, ctx.request_id).Bind(8, detail);
  return st.Run();
}

Result<MapInfo> SqliteMapStore::SaveMap(const MapSnapshot& snapshot, const WriteContext& ctx) {
  Status s = ValidateSnapshot(snapshot);
  if (!s.ok()) return s;
  const std::string label = "saving map '" + snapshot.site + "/" + snapshot.name + "'";

  // Compress and checksum every tile before taking the write lock.
  const int tile_size = options_.tile_size_cells;
  const common::GridGeometry& g = snapshot.base.geometry();
  const std::vector<std::string> layer_names = snapshot.base.layer_names();
  const std::vector<TileSpec> specs = TilesOf(g, tile_size);
  struct Job {
    size_t layer;
    size_t spec;
  };
  std::vector<Job> jobs;
  for (size_t l = 0; l < layer_names.size(); ++l) {
    for (size_t t = 0; t < specs.size(); ++t) jobs.push_back({l, t});
  }
  // Blobs the caller already compressed (a pushed save's) for tiles that are the store's own.
  std::vector<const StoredTile*> encoded(jobs.size(), nullptr);
  {
    std::map<std::string, const StoredLayer*> by_name;
    for (const StoredLayer& l : snapshot.encoded_layers) {
      if (l.tile_size == tile_size) by_name[l.name] = &l;
    }
    const int tiles_x = (g.size_x + tile_size - 1) / tile_size;
    std::vector<std::vector<const StoredTile*>> index(layer_names.size());
    for (size_t l = 0; l < layer_names.size(); ++l) {
      auto it = by_name.find(layer_names[l]);
      if (it == by_name.end()) continue;
      index[l].assign(specs.size(), nullptr);
      for (const StoredTile& t : it->second->tiles) {
        const size_t k = static_cast<size_t>(t.tile_iy) * tiles_x + t.tile_ix;
        if (t.tile_ix >= 0 && t.tile_iy >= 0 && t.tile_ix < tiles_x && k < specs.size()) {
          index[l][k] = &t;
        }
      }
    }
    for (size_t i = 0; i < jobs.size(); ++i) {
      if (!index[jobs[i].layer].empty()) encoded[i] = index[jobs[i].layer][jobs[i].spec];
    }
  }
  std::vector<EncodedBlob> blobs(jobs.size());
  std::vector<char> present(jobs.size(), 0);
  try {
    ParallelFor(jobs.size(), options_.compression_threads, [&](size_t i) {
      const TileSpec& spec = specs[jobs[i].spec];
      const size_t bytes = static_cast<size_t>(spec.cells_x) * spec.cells_y * sizeof(float);
      const StoredTile* e = encoded[i];
      const bool adoptable = e != nullptr &&
                             (e->codec == static_cast<int>(Codec::kZstdShuffle4) ||
                              e->codec == static_cast<int>(Codec::kZstdBytes)) &&
                             e->cells_x == spec.cells_x && e->cells_y == spec.cells_y;
      auto adopt = [&] {
        auto blob = AdoptEncodedBlob(static_cast<Codec>(e->codec), e->data,
                                     static_cast<int64_t>(bytes), e->raw_crc32);
        if (!blob.ok()) return false;
        blobs[i] = std::move(blob).value();
        present[i] = 1;
        return true;
      };
      // A checked caller's tile stands for the cells (an all-unknown tile is stored too).
      if (adoptable && snapshot.encoded_layers_checked && adopt()) return;
      const std::vector<float> cells =
          ExtractTile(snapshot.base.at(layer_names[jobs[i].layer]), spec);
      if (AllUnknown(cells)) return;
      if (adoptable && e->raw_crc32 == common::Crc32(cells.data(), bytes) && adopt()) {
        return;
      }
      blobs[i] = EncodeBlob(cells.data(), bytes, FloatCodec(cells.data(), cells.size()),
                            options_.zstd_level);
      present[i] = 1;
    });
  } catch (const std::exception& e) {
    return common::InternalError(label + ": " + e.what());
  }
  std::vector<EncodedBlob> stored;
  std::vector<size_t> stored_job;
  for (size_t i = 0; i < jobs.size(); ++i) {
    if (present[i]) {
      stored.push_back(std::move(blobs[i]));
      stored_job.push_back(i);
    }
  }
  std::optional<EncodedBlob> octomap_blob;
  if (snapshot.octomap) {
    octomap_blob = EncodeBlob(snapshot.octomap->bytes.data(), snapshot.octomap->bytes.size(),
                              Codec::kZstd, options_.zstd_level);
  }

  std::lock_guard<std::mutex> lock(mutex_);
  const int64_t now = WallUtime();
  const int64_t created =
      snapshot.provenance.created_utime != 0 ? snapshot.provenance.created_utime : now;
  const int64_t audit_utime = ctx.utime != 0 ? ctx.utime : now;
  int64_t version = 0;
  s = WriteTransaction([&]() -> Status {
    auto site_id = SiteId(snapshot.site, true, now);
    if (!site_id.ok()) return site_id.status();
    sqlite::Statement map_insert = db_->Prepare(
        "INSERT INTO maps(site_id, name, created_utime) VALUES(?, ?, ?) "
        "ON CONFLICT(site_id, name) DO NOTHING");
    map_insert.Bind(1, *site_id).Bind(2, snapshot.name).Bind(3, now);
    Status st = map_insert.Run();
    if (!st.ok()) return st;
    sqlite::Statement map_find = db_->Prepare(
        "SELECT m.id, (SELECT COALESCE(MAX(version), 0) FROM map_versions WHERE map_id = m.id) "
        "FROM maps m WHERE m.site_id = ? AND m.name = ?");
    map_find.Bind(1, *site_id).Bind(2, snapshot.name);
    if (!map_find.Step()) return common::InternalError("map row vanished");
    const int64_t map_id = map_find.Int(0);
    version = map_find.Int(1) + 1;

    sqlite::Statement v = db_->Prepare(
        "INSERT INTO map_versions(map_id, version, source_robot, source_profile, "
        "source_profile_hash, code_version, parameters, created_utime, resolution_m, size_x, "
        "size_y, origin_x_m, origin_y_m, origin_yaw_rad, tile_size) "
        "VALUES(?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)");
    const Provenance& p = snapshot.provenance;
    v.Bind(1, map_id).Bind(2, version).Bind(3, p.source_robot).Bind(4, p.source_profile);
    v.Bind(5, p.source_profile_hash).Bind(6, p.code_version).Bind(7, p.parameters);
    v.Bind(8, created).Bind(9, g.resolution_m).Bind(10, g.size_x).Bind(11, g.size_y);
    v.Bind(12, g.origin.x_m).Bind(13, g.origin.y_m).Bind(14, g.origin.yaw_rad).Bind(15, tile_size);
    if (!(st = v.Run()).ok()) return st;
    const int64_t version_id = db_->LastInsertRowId();

    // Layers and their tiles.
    std::vector<int64_t> layer_ids;
    sqlite::Statement layer_insert =
        db_->Prepare("INSERT INTO layers(map_version_id, name) VALUES(?, ?)");
    for (const std::string& name : layer_names) {
      layer_insert.Reset();
      layer_insert.Bind(1, version_id).Bind(2, name);
      if (!(st = layer_insert.Run()).ok()) return st;
      layer_ids.push_back(db_->LastInsertRowId());
    }
    std::vector<int64_t> blob_ids;
    if (!(st = WriteBlobs(stored, &blob_ids)).ok()) return st;
    sqlite::Statement tile_insert = db_->Prepare(
        "INSERT INTO layer_tiles(layer_id, tile_ix, tile_iy, blob_id) VALUES(?, ?, ?, ?)");
    for (size_t k = 0; k < stored.size(); ++k) {
      const Job& job = jobs[stored_job[k]];
      const TileSpec& spec = specs[job.spec];
      tile_insert.Reset();
      tile_insert.Bind(1, layer_ids[job.layer]).Bind(2, spec.tile_ix).Bind(3, spec.tile_iy);
      tile_insert.Bind(4, blob_ids[k]);
      if (!(st = tile_insert.Run()).ok()) return st;
    }

    // Obstacles with their measurements and verdicts.
    sqlite::Statement ob = db_->Prepare(
        "INSERT INTO obstacles(map_version_id, obstacle_id, kind, centroid_x_m, centroid_y_m, "
        "slope_rad, height_m, width_m, length_m, depth_m, area_m2, num_cells, outline) "
        "VALUES(?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)");
    sqlite::Statement vd = db_->Prepare(
        "INSERT INTO obstacle_verdicts(map_version_id, obstacle_id, profile, profile_hash, "
        "crossable, reason) VALUES(?, ?, ?, ?, ?, ?)");
    for (const common::Obstacle& o : snapshot.obstacles.obstacles) {
      ob.Reset();
      const std::string outline = SerializePolygon(o.outline_m);
      ob.Bind(1, version_id).Bind(2, o.id).Bind(3, static_cast<int64_t>(o.kind));
      ob.Bind(4, o.centroid_m.x()).Bind(5, o.centroid_m.y()).Bind(6, o.slope_rad);
      ob.Bind(7, o.height_m).Bind(8, o.width_m).Bind(9, o.length_m).Bind(10, o.depth_m);
      ob.Bind(11, o.area_m2).Bind(12, o.num_cells).BindBlob(13, outline.data(), outline.size());
      if (!(st = ob.Run()).ok()) return st;
      for (const common::ObstacleVerdict& verdict : o.verdicts) {
        vd.Reset();
        vd.Bind(1, version_id).Bind(2, o.id).Bind(3, verdict.profile).Bind(4, verdict.profile_hash);
        vd.Bind(5, verdict.crossable ? 1 : 0).Bind(6, verdict.reason);
        if (!(st = vd.Run()).ok()) return st;
      }
    }

    if (octomap_blob) {
      std::vector<int64_t> id;
      if (!(st = WriteBlobs({*octomap_blob}, &id)).ok()) return st;
      sqlite::Statement oc = db_->Prepare(
          "INSERT INTO octomaps(map_version_id, binary, resolution_m, blob_id) VALUES(?, ?, ?, ?)");
      oc.Bind(1, version_id).Bind(2, snapshot.octomap->binary ? 1 : 0);
      oc.Bind(3, snapshot.octomap->resolution_m).Bind(4, id[0]);
      if (!(st = oc.Run()).ok()) return st;
    }
    return Audit(ctx, audit_utime, "save", snapshot.site, snapshot.name, version,
                 std::to_string(layer_names.size()) + " layers, " + std::to_string(stored.size()) +
                     " tiles, " + std::to_string(snapshot.obstacles.obstacles.size()) +
                     " obstacles" + (snapshot.octomap ? ", octomap" : ""));
  });
  if (!s.ok()) return WriteError(s, label);
  auto row = Resolve({snapshot.site, snapshot.name, version});
  if (!row.ok()) return row.status();
  return InfoOf(*row);
}

Result<MapInfo> SqliteMapStore::GetMapInfo(const MapRef& ref) const {
  std::lock_guard<std::mutex> lock(mutex_);
  auto row = Resolve(ref);
  if (!row.ok()) return row.status();
  return InfoOf(*row);
}

Result<std::vector<MapInfo>> SqliteMapStore::ListMaps(const MapFilter& filter) const {
  std::lock_guard<std::mutex> lock(mutex_);
  Status s;
  if (!filter.site.empty() && !(s = ValidateName("site name", filter.site)).ok()) return s;
  if (!filter.name.empty() && !(s = ValidateName("map name", filter.name)).ok()) return s;
  sqlite::Statement st = db_->Prepare(std::string(kVersionSelect) +
                                      "WHERE (?1 = '' OR s.name = ?1) AND (?2 = '' OR m.name = ?2) "
                                      "ORDER BY s.name, m.name, v.version");
  st.Bind(1, filter.site).Bind(2, filter.name);
  std::vector<VersionRow> rows;
  while (st.Step()) {
    VersionRow row;
    row.id = st.Int(0);
    row.map_id = st.Int(1);
    row.site = st.Text(3);
    row.name = st.Text(4);
    row.version = st.Int(5);
    row.provenance.source_robot = st.Text(6);
    row.provenance.source_profile = st.Text(7);
    row.provenance.source_profile_hash = st.Text(8);
    row.provenance.code_version = st.Text(9);
    row.provenance.parameters = st.Text(10);
    row.provenance.created_utime = st.Int(11);
    row.geometry.resolution_m = st.Double(12);
    row.geometry.size_x = static_cast<int>(st.Int(13));
    row.geometry.size_y = static_cast<int>(st.Int(14));
    row.geometry.origin = {st.Double(15), st.Double(16), st.Double(17)};
    row.tile_size = static_cast<int>(st.Int(18));
    row.deleted = st.Int(19) != 0;
    rows.push_back(std::move(row));
  }
  if (!st.status().ok()) return st.status();
  std::vector<MapInfo> out;
  for (size_t i = 0; i < rows.size(); ++i) {
    const VersionRow& row = rows[i];
    if (row.deleted && !filter.include_deleted) continue;
    if (!filter.all_versions) {
      // Keep the newest eligible version of each map.
      bool newer = false;
      for (size_t j = i + 1; j < rows.size() && rows[j].map_id == row.map_id; ++j) {
        newer |= !rows[j].deleted || filter.include_deleted;
      }
      if (newer) continue;
    }
    auto info = InfoOf(row);
    if (!info.ok()) return info.status();
    out.push_back(std::move(info).value());
  }
  return out;
}

Status SqliteMapStore::ReadTiles(sqlite::Statement* stmt, const std::string& label, int tile_size,
                                 const common::GridGeometry& full, const CellBox& box,
                                 common::Layer* layer) const {
  std::vector<RawTile> raw;
  while (stmt->Step()) {
    RawTile t;
    t.tile_ix = static_cast<int>(stmt->Int(0));
    t.tile_iy = static_cast<int>(stmt->Int(1));
    t.codec = static_cast<Codec>(stmt->Int(2));
    t.raw_size = stmt->Int(3);
    t.raw_crc32 = static_cast<uint32_t>(stmt->Int(4));
    t.data = stmt->Blob(5);
    raw.push_back(std::move(t));
  }
  if (!stmt->status().ok()) return stmt->status();
  const int tiles_x = (full.size_x + tile_size - 1) / tile_size;
  const int tiles_y = (full.size_y + tile_size - 1) / tile_size;
  std::vector<Status> errors(raw.size());
  ParallelFor(raw.size(), options_.compression_threads, [&](size_t i) {
    const RawTile& t = raw[i];
    const std::string where =
        label + " tile (" + std::to_string(t.tile_ix) + ", " + std::to_string(t.tile_iy) + ")";
    if (t.tile_ix < 0 || t.tile_iy < 0 || t.tile_ix >= tiles_x || t.tile_iy >= tiles_y) {
      errors[i] = common::CorruptError(where + " lies outside the grid");
      return;
    }
    TileSpec spec;
    spec.tile_ix = t.tile_ix;
    spec.tile_iy = t.tile_iy;
    spec.x0 = t.tile_ix * tile_size;
    spec.y0 = t.tile_iy * tile_size;
    spec.cells_x = std::min(tile_size, full.size_x - spec.x0);
    spec.cells_y = std::min(tile_size, full.size_y - spec.y0);
    const int64_t expected = int64_t{spec.cells_x} * spec.cells_y * sizeof(float);
    if (t.raw_size != expected) {
      errors[i] =
          common::CorruptError(where + " has " + std::to_string(t.raw_size) + " bytes for " +
                               std::to_string(spec.cells_x * spec.cells_y) + " cells");
      return;
    }
    thread_local std::vector<float> cells;
    cells.resize(static_cast<size_t>(spec.cells_x) * spec.cells_y);
    Status s = DecodeBlobTo(t.codec, t.data.data(), t.data.size(), t.raw_size, t.raw_crc32,
                            reinterpret_cast<uint8_t*>(cells.data()));
    if (!s.ok()) {
      errors[i] = common::CorruptError(where + ": " + s.message());
      return;
    }
    // Tiles never overlap, so threads write disjoint cells.
    PasteTile(spec, cells.data(), box.min_ix, box.min_iy, layer);
  });
  for (const Status& e : errors) {
    if (!e.ok()) return e;
  }
  return Status::Ok();
}

Result<std::map<std::string, int64_t>> SqliteMapStore::LayerIds(
    const MapRef& ref, const VersionRow& row, std::vector<std::string>* wanted) const {
  std::map<std::string, int64_t> layer_ids;
  sqlite::Statement st = db_->Prepare("SELECT name, id FROM layers WHERE map_version_id = ?");
  st.Bind(1, row.id);
  while (st.Step()) layer_ids[st.Text(0)] = st.Int(1);
  if (!st.status().ok()) return st.status();
  if (wanted->empty()) {
    for (const auto& [name, id] : layer_ids) wanted->push_back(name);
  }
  for (const std::string& name : *wanted) {
    if (!layer_ids.count(name)) {
      return common::NotFoundError(LayerNotFoundMessage(ref, row.version, name, layer_ids));
    }
  }
  return layer_ids;
}

Result<common::GridMap> SqliteMapStore::LoadLayers(const MapRef& ref,
                                                   const LayerQuery& query) const {
  std::lock_guard<std::mutex> lock(mutex_);
  auto row = Resolve(ref);
  if (!row.ok()) return row.status();
  std::vector<std::string> wanted = query.layers;
  auto ids = LayerIds(ref, *row, &wanted);
  if (!ids.ok()) return ids.status();
  const std::map<std::string, int64_t>& layer_ids = *ids;
  const CellBox box = query.region ? ClipBox(*query.region, row->geometry)
                                   : CellBox{0, 0, row->geometry.size_x, row->geometry.size_y};
  if (box.empty()) return common::InvalidArgumentError("the region does not overlap the map");
  common::GridMap map(SubGeometry(row->geometry, box));
  const int ts = row->tile_size;
  sqlite::Statement st =
      db_->Prepare(std::string("SELECT ") + kTileColumns +
                   " FROM layer_tiles t JOIN blobs b ON b.id = t.blob_id WHERE t.layer_id = ? AND "
                   "t.tile_iy BETWEEN ? AND ? AND t.tile_ix BETWEEN ? AND ?");
  for (const std::string& name : wanted) {
    st.Reset();
    st.Bind(1, layer_ids.at(name)).Bind(2, box.min_iy / ts).Bind(3, (box.max_iy - 1) / ts);
    st.Bind(4, box.min_ix / ts).Bind(5, (box.max_ix - 1) / ts);
    Status read = ReadTiles(&st,
                            "layer '" + name + "' of map '" + row->site + "/" + row->name +
                                "' version " + std::to_string(row->version),
                            ts, row->geometry, box, &map.AddLayer(name));
    if (!read.ok()) return read;
  }
  return map;
}

Status SqliteMapStore::ReadStoredTiles(sqlite::Statement* stmt, const std::string& label,
                                       const VersionRow& row, StoredLayer* layer) const {
  const int ts = row.tile_size;
  const common::GridGeometry& full = row.geometry;
  const int tiles_x = (full.size_x + ts - 1) / ts;
  const int tiles_y = (full.size_y + ts - 1) / ts;
  layer->tile_size = ts;
  while (stmt->Step()) {
    StoredTile t;
    t.tile_ix = static_cast<int>(stmt->Int(0));
    t.tile_iy = static_cast<int>(stmt->Int(1));
    t.codec = static_cast<int>(stmt->Int(2));
    const int64_t raw_size = stmt->Int(3);
    t.raw_crc32 = static_cast<uint32_t>(stmt->Int(4));
    t.data = stmt->Blob(5);
    if (!stmt->IsNull(6)) t.stored_crc32 = static_cast<uint32_t>(stmt->Int(6));
    const std::string where =
        label + " tile (" + std::to_string(t.tile_ix) + ", " + std::to_string(t.tile_iy) + ")";
    if (t.tile_ix < 0 || t.tile_iy < 0 || t.tile_ix >= tiles_x || t.tile_iy >= tiles_y) {
      return common::CorruptError(where + " lies outside the grid");
    }
    t.cells_x = std::min(ts, full.size_x - t.tile_ix * ts);
    t.cells_y = std::min(ts, full.size_y - t.tile_iy * ts);
    if (raw_size != int64_t{t.cells_x} * t.cells_y * static_cast<int64_t>(sizeof(float))) {
      return common::CorruptError(where + " has " + std::to_string(raw_size) + " bytes for " +
                                  std::to_string(t.cells_x * t.cells_y) + " cells");
    }
    layer->tiles.push_back(std::move(t));
  }
  return stmt->status();
}

Status SqliteMapStore::CheckStoredLayers(const std::vector<StoredLayer>& layers,
                                         const std::string& label) const {
  std::vector<std::pair<size_t, size_t>> all;  // (layer, tile) of every tile
  for (size_t l = 0; l < layers.size(); ++l) {
    for (size_t t = 0; t < layers[l].tiles.size(); ++t) all.emplace_back(l, t);
  }
  // The blobs are checked (decoded, not kept) as LoadLayers checks them.
  std::vector<Status> errors(all.size());
  ParallelFor(all.size(), options_.compression_threads, [&](size_t i) {
    const StoredTile& t = layers[all[i].first].tiles[all[i].second];
    Status s = CheckStoredTile(t);
    if (!s.ok()) {
      errors[i] = common::CorruptError("layer '" + layers[all[i].first].name + "' of " + label +
                                       " tile (" + std::to_string(t.tile_ix) + ", " +
                                       std::to_string(t.tile_iy) + "): " + s.message());
    }
  });
  for (const Status& e : errors) {
    if (!e.ok()) return e;
  }
  return Status::Ok();
}

Result<std::vector<StoredLayer>> SqliteMapStore::LoadStoredTiles(
    const MapRef& ref, const std::vector<std::string>& layers, int /*tile_size*/) const {
  std::lock_guard<std::mutex> lock(mutex_);
  auto row = Resolve(ref);
  if (!row.ok()) return row.status();
  std::vector<std::string> wanted = layers;
  auto ids = LayerIds(ref, *row, &wanted);
  if (!ids.ok()) return ids.status();
  const std::map<std::string, int64_t>& layer_ids = *ids;
  const std::string label =
      "map '" + row->site + "/" + row->name + "' version " + std::to_string(row->version);
  sqlite::Statement st = db_->Prepare(std::string("SELECT ") + kTileColumns +
                                      " FROM layer_tiles t JOIN blobs b ON b.id = t.blob_id "
                                      "WHERE t.layer_id = ? ORDER BY t.tile_iy, t.tile_ix");
  std::vector<StoredLayer> out;
  for (const std::string& name : wanted) {
    StoredLayer layer;
    layer.name = name;
    st.Reset();
    st.Bind(1, layer_ids.at(name));
    Status read = ReadStoredTiles(&st, "layer '" + name + "' of " + label, *row, &layer);
    if (!read.ok()) return read;
    out.push_back(std::move(layer));
  }
  Status checked = CheckStoredLayers(out, label);
  if (!checked.ok()) return checked;
  return out;
}

Result<common::ObstacleRegistry> SqliteMapStore::LoadObstacles(const MapRef& ref) const {
  std::lock_guard<std::mutex> lock(mutex_);
  auto row = Resolve(ref);
  if (!row.ok()) return row.status();
  common::ObstacleRegistry registry;
  registry.map_version = row->version;
  sqlite::Statement st = db_->Prepare(
      "SELECT obstacle_id, kind, centroid_x_m, centroid_y_m, slope_rad, height_m, width_m, "
      "length_m, depth_m, area_m2, num_cells, outline FROM obstacles WHERE map_version_id = ? "
      "ORDER BY obstacle_id");
  st.Bind(1, row->id);
  std::map<int32_t, size_t> index;
  while (st.Step()) {
    common::Obstacle o;
    o.id = static_cast<int32_t>(st.Int(0));
    o.kind = static_cast<common::ObstacleKind>(st.Int(1));
    o.centroid_m = {st.Double(2), st.Double(3)};
    o.slope_rad = st.Double(4);
    o.height_m = st.Double(5);
    o.width_m = st.Double(6);
    o.length_m = st.Double(7);
    o.depth_m = st.Double(8);
    o.area_m2 = st.Double(9);
    o.num_cells = static_cast<int32_t>(st.Int(10));
    auto outline = ParsePolygon(st.Blob(11));
    if (!outline.ok()) {
      return common::CorruptError("obstacle " + std::to_string(o.id) + ": " +
                                  outline.status().message());
    }
    o.outline_m = std::move(outline).value();
    index[o.id] = registry.obstacles.size();
    registry.obstacles.push_back(std::move(o));
  }
  if (!st.status().ok()) return st.status();
  sqlite::Statement vd = db_->Prepare(
      "SELECT obstacle_id, profile, profile_hash, crossable, reason FROM obstacle_verdicts "
      "WHERE map_version_id = ? ORDER BY obstacle_id, profile");
  vd.Bind(1, row->id);
  while (vd.Step()) {
    auto it = index.find(static_cast<int32_t>(vd.Int(0)));
    if (it == index.end()) continue;
    common::ObstacleVerdict v;
    v.profile = vd.Text(1);
    v.profile_hash = vd.Text(2);
    v.crossable = vd.Int(3) != 0;
    v.reason = vd.Text(4);
    registry.obstacles[it->second].verdicts.push_back(std::move(v));
  }
  if (!vd.status().ok()) return vd.status();
  return registry;
}

Result<OctomapData> SqliteMapStore::LoadOctomap(const MapRef& ref) const {
  std::lock_guard<std::mutex> lock(mutex_);
  auto row = Resolve(ref);
  if (!row.ok()) return row.status();
  sqlite::Statement st = db_->Prepare(
      "SELECT o.binary, o.resolution_m, b.codec, b.raw_size, b.raw_crc32, b.data FROM octomaps o "
      "JOIN blobs b ON b.id = o.blob_id WHERE o.map_version_id = ?");
  st.Bind(1, row->id);
  if (!st.Step()) {
    if (!st.status().ok()) return st.status();
    return common::NotFoundError("map '" + row->site + "/" + row->name + "' version " +
                                 std::to_string(row->version) + " has no OctoMap");
  }
  OctomapData data;
  data.binary = st.Int(0) != 0;
  data.resolution_m = st.Double(1);
  auto bytes = DecodeBlob(static_cast<Codec>(st.Int(2)), st.Blob(5), st.Int(3),
                          static_cast<uint32_t>(st.Int(4)));
  if (!bytes.ok()) return common::CorruptError("OctoMap blob: " + bytes.status().message());
  data.bytes = std::move(bytes).value();
  return data;
}

Status SqliteMapStore::DeleteMap(const MapRef& ref, const WriteContext& ctx) {
  std::lock_guard<std::mutex> lock(mutex_);
  auto row = Resolve(ref);
  if (!row.ok()) return row.status();
  const int64_t now = WallUtime();
  int changed = 0;
  Status s = WriteTransaction([&]() -> Status {
    sqlite::Statement st = db_->Prepare(
        ref.version == 0
            ? "UPDATE map_versions SET deleted_utime = ? WHERE map_id = ? AND deleted_utime IS NULL"
            : "UPDATE map_versions SET deleted_utime = ? WHERE id = ? AND deleted_utime IS NULL");
    st.Bind(1, now).Bind(2, ref.version == 0 ? row->map_id : row->id);
    Status r = st.Run();
    if (!r.ok()) return r;
    changed = db_->Changes();
    return Audit(ctx, ctx.utime != 0 ? ctx.utime : now, "delete", row->site, row->name, ref.version,
                 ref.version == 0 ? std::to_string(changed) + " versions" : "one version");
  });
  if (!s.ok()) return WriteError(s, "deleting map '" + ref.site + "/" + ref.name + "'");
  return Status::Ok();
}

Status SqliteMapStore::PutProfile(const common::RobotProfile& profile, const WriteContext& ctx) {
  Status s = ValidateProfile(profile);
  if (!s.ok()) return s;
  const std::string hash = profile.ContentHash();
  const std::string yaml = profile.ToYaml();
  std::lock_guard<std::mutex> lock(mutex_);
  {
    sqlite::Statement newest =
        db_->Prepare("SELECT content_hash FROM profiles WHERE name = ? ORDER BY id DESC LIMIT 1");
    newest.Bind(1, profile.name);
    if (newest.Step() && newest.Text(0) == hash) return Status::Ok();  // nothing to change
    if (!newest.status().ok()) return newest.status();
  }
  const int64_t now = WallUtime();
  s = WriteTransaction([&]() -> Status {
    // Going back to an earlier content makes that content the newest again.
    sqlite::Statement drop =
        db_->Prepare("DELETE FROM profiles WHERE name = ? AND content_hash = ?");
    drop.Bind(1, profile.name).Bind(2, hash);
    Status r = drop.Run();
    if (!r.ok()) return r;
    sqlite::Statement insert = db_->Prepare(
        "INSERT INTO profiles(name, content_hash, yaml, created_utime) VALUES(?, ?, ?, ?)");
    insert.Bind(1, profile.name).Bind(2, hash).Bind(3, yaml).Bind(4, now);
    if (!(r = insert.Run()).ok()) return r;
    return Audit(ctx, ctx.utime != 0 ? ctx.utime : now, "put_profile", "", "", 0,
                 profile.name + " " + hash);
  });
  if (!s.ok()) return WriteError(s, "storing profile '" + profile.name + "'");
  return Status::Ok();
}

Result<std::string> SqliteMapStore::GetProfileHash(const std::string& name) const {
  Status s = ValidateName("profile name", name);
  if (!s.ok()) return s;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    sqlite::Statement st =
        db_->Prepare("SELECT content_hash FROM profiles WHERE name = ? ORDER BY id DESC LIMIT 1");
    st.Bind(1, name);
    if (st.Step()) return st.Text(0);
    if (!st.status().ok()) return st.status();
  }
  return GetProfile(name).status();  // the not-found message names the known profiles
}

Result<StoredProfile> SqliteMapStore::GetProfile(const std::string& name) const {
  Status s = ValidateName("profile name", name);
  if (!s.ok()) return s;
  std::lock_guard<std::mutex> lock(mutex_);
  sqlite::Statement st = db_->Prepare(
      "SELECT yaml, content_hash, created_utime FROM profiles WHERE name = ? "
      "ORDER BY id DESC LIMIT 1");
  st.Bind(1, name);
  if (!st.Step()) {
    if (!st.status().ok()) return st.status();
    std::vector<std::string> known;
    sqlite::Statement all = db_->Prepare("SELECT DISTINCT name FROM profiles ORDER BY name");
    while (all.Step()) known.push_back(all.Text(0));
    return common::NotFoundError(ProfileNotFoundMessage(name, known));
  }
  StoredProfile out;
  try {
    out.profile = common::LoadRobotProfileString(st.Text(0), "stored profile " + name);
  } catch (const std::exception& e) {
    return common::CorruptError(std::string("stored profile '") + name +
                                "' does not load: " + e.what());
  }
  out.content_hash = st.Text(1);
  out.updated_utime = st.Int(2);
  return out;
}

Result<std::vector<StoredProfile>> SqliteMapStore::ListProfiles() const {
  std::vector<std::string> names;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    sqlite::Statement all = db_->Prepare("SELECT DISTINCT name FROM profiles ORDER BY name");
    while (all.Step()) names.push_back(all.Text(0));
    if (!all.status().ok()) return all.status();
  }
  std::vector<StoredProfile> out;
  for (const std::string& name : names) {
    auto p = GetProfile(name);
    if (!p.ok()) return p.status();
    out.push_back(std::move(p).value());
  }
  return out;
}

struct SqliteMapStore::DerivedHeader {
  int64_t id{0};
  std::string profile_name;
  int64_t created_utime{0};
  common::ObstacleRegistry registry;
  std::set<std::string> layers;
};

Result<std::optional<SqliteMapStore::DerivedHeader>> SqliteMapStore::FindDerivedHeader(
    const VersionRow& row, const std::string& profile_hash, const std::string& code_version) const {
  sqlite::Statement st = db_->Prepare(
      "SELECT d.id, d.profile_name, d.created_utime, b.codec, b.raw_size, b.raw_crc32, b.data "
      "FROM derived d JOIN blobs b ON b.id = d.registry_blob_id "
      "WHERE d.map_version_id = ? AND d.profile_hash = ? AND d.code_version = ?");
  st.Bind(1, row.id).Bind(2, profile_hash).Bind(3, code_version);
  if (!st.Step()) {
    if (!st.status().ok()) return st.status();
    return std::optional<DerivedHeader>();
  }
  DerivedHeader out;
  out.id = st.Int(0);
  out.profile_name = st.Text(1);
  out.created_utime = st.Int(2);
  auto registry_bytes = DecodeBlob(static_cast<Codec>(st.Int(3)), st.Blob(6), st.Int(4),
                                   static_cast<uint32_t>(st.Int(5)));
  if (!registry_bytes.ok()) {
    return common::CorruptError("derived registry: " + registry_bytes.status().message());
  }
  auto registry = ParseRegistry(*registry_bytes);
  if (!registry.ok()) return registry.status();
  out.registry = std::move(registry).value();
  sqlite::Statement ln = db_->Prepare("SELECT name FROM derived_layers WHERE derived_id = ?");
  ln.Bind(1, out.id);
  while (ln.Step()) out.layers.insert(ln.Text(0));
  if (!ln.status().ok()) return ln.status();
  return std::optional<DerivedHeader>(std::move(out));
}

Result<std::optional<std::pair<SqliteMapStore::VersionRow, SqliteMapStore::DerivedHeader>>>
SqliteMapStore::ResolveDerived(const MapRef& ref, const std::string& profile_hash,
                               const std::string& code_version) const {
  using Found = std::optional<std::pair<VersionRow, DerivedHeader>>;
  auto row = Resolve(ref);
  if (!row.ok()) return row.status();
  auto header = FindDerivedHeader(*row, profile_hash, code_version);
  if (!header.ok()) return header.status();
  std::optional<DerivedHeader> found = std::move(header).value();
  if (!found) return Found();
  return Found(std::make_pair(std::move(row).value(), std::move(*found)));
}

namespace {

// The wanted cached layers (all when none is named), or kNotFound naming the first missing one.
Result<std::vector<std::string>> CachedLayersWanted(const std::set<std::string>& cached,
                                                    const std::vector<std::string>& wanted_in,
                                                    const std::string& profile_name) {
  std::vector<std::string> wanted = wanted_in;
  if (wanted.empty()) wanted.assign(cached.begin(), cached.end());
  for (const std::string& name : wanted) {
    if (!cached.count(name)) {
      return common::NotFoundError("the cached layers of profile '" + profile_name +
                                   "' have no layer '" + name + "'");
    }
  }
  return wanted;
}

}  // namespace

Result<std::optional<DerivedProfile>> SqliteMapStore::FindDerived(const MapRef& ref,
                                                                  const std::string& profile_hash,
                                                                  const std::string& code_version,
                                                                  const LayerQuery& query) const {
  std::lock_guard<std::mutex> lock(mutex_);
  auto resolved = ResolveDerived(ref, profile_hash, code_version);
  if (!resolved.ok()) return resolved.status();
  auto found = std::move(resolved).value();
  if (!found) return std::optional<DerivedProfile>();
  const VersionRow* row = &found->first;
  DerivedHeader& h = found->second;
  DerivedProfile out;
  out.profile_name = h.profile_name;
  out.profile_hash = profile_hash;
  out.code_version = code_version;
  out.created_utime = h.created_utime;
  out.registry = std::move(h.registry);
  auto wanted = CachedLayersWanted(h.layers, query.layers, out.profile_name);
  if (!wanted.ok()) return wanted.status();
  const CellBox box = query.region ? ClipBox(*query.region, row->geometry)
                                   : CellBox{0, 0, row->geometry.size_x, row->geometry.size_y};
  if (box.empty()) return common::InvalidArgumentError("the region does not overlap the map");
  out.layers = common::GridMap(SubGeometry(row->geometry, box));
  const int ts = row->tile_size;
  sqlite::Statement tiles = db_->Prepare(
      std::string("SELECT ") + kTileColumns +
      " FROM derived_tiles t JOIN blobs b ON b.id = t.blob_id WHERE t.derived_id = ? AND "
      "t.layer = ? AND t.tile_iy BETWEEN ? AND ? AND t.tile_ix BETWEEN ? AND ?");
  for (const std::string& name : *wanted) {
    tiles.Reset();
    tiles.Bind(1, h.id).Bind(2, name).Bind(3, box.min_iy / ts).Bind(4, (box.max_iy - 1) / ts);
    tiles.Bind(5, box.min_ix / ts).Bind(6, (box.max_ix - 1) / ts);
    Status read = ReadTiles(&tiles, "derived layer '" + name + "'", ts, row->geometry, box,
                            &out.layers.AddLayer(name));
    if (!read.ok()) return read;
  }
  return std::optional<DerivedProfile>(std::move(out));
}

Result<std::optional<StoredDerived>> SqliteMapStore::FindDerivedTiles(
    const MapRef& ref, const std::string& profile_hash, const std::string& code_version,
    const std::vector<std::string>& layers, int /*tile_size*/) const {
  std::lock_guard<std::mutex> lock(mutex_);
  auto resolved = ResolveDerived(ref, profile_hash, code_version);
  if (!resolved.ok()) return resolved.status();
  auto found = std::move(resolved).value();
  if (!found) return std::optional<StoredDerived>();
  const VersionRow* row = &found->first;
  DerivedHeader& h = found->second;
  StoredDerived out;
  out.profile_name = h.profile_name;
  out.registry = std::move(h.registry);
  auto wanted = CachedLayersWanted(h.layers, layers, out.profile_name);
  if (!wanted.ok()) return wanted.status();
  const std::string label = "the cache of profile '" + out.profile_name + "' for map '" +
                            row->site + "/" + row->name + "' version " +
                            std::to_string(row->version);
  sqlite::Statement tiles = db_->Prepare(
      std::string("SELECT ") + kTileColumns +
      " FROM derived_tiles t JOIN blobs b ON b.id = t.blob_id WHERE t.derived_id = ? AND "
      "t.layer = ? ORDER BY t.tile_iy, t.tile_ix");
  for (const std::string& name : *wanted) {
    StoredLayer layer;
    layer.name = name;
    tiles.Reset();
    tiles.Bind(1, h.id).Bind(2, name);
    Status read = ReadStoredTiles(&tiles, "derived layer '" + name + "' of " + label, *row, &layer);
    if (!read.ok()) return read;
    out.layers.push_back(std::move(layer));
  }
  Status checked = CheckStoredLayers(out.layers, label);
  if (!checked.ok()) return checked;
  return std::optional<StoredDerived>(std::move(out));
}

Result<std::vector<DerivedInfo>> SqliteMapStore::ListDerived(const MapRef& ref) const {
  std::lock_guard<std::mutex> lock(mutex_);
  auto row = Resolve(ref);
  if (!row.ok()) return row.status();
  sqlite::Statement st = db_->Prepare(
      "SELECT d.id, d.profile_name, d.profile_hash, d.code_version, d.created_utime FROM derived d "
      "WHERE d.map_version_id = ? ORDER BY d.profile_name, d.id");
  st.Bind(1, row->id);
  std::vector<DerivedInfo> out;
  std::vector<int64_t> ids;
  while (st.Step()) {
    DerivedInfo d;
    ids.push_back(st.Int(0));
    d.profile_name = st.Text(1);
    d.profile_hash = st.Text(2);
    d.code_version = st.Text(3);
    d.created_utime = st.Int(4);
    out.push_back(std::move(d));
  }
  if (!st.status().ok()) return st.status();
  sqlite::Statement ln =
      db_->Prepare("SELECT name FROM derived_layers WHERE derived_id = ? ORDER BY name");
  for (size_t i = 0; i < out.size(); ++i) {
    ln.Reset();
    ln.Bind(1, ids[i]);
    while (ln.Step()) out[i].layers.push_back(ln.Text(0));
  }
  return out;
}

Status SqliteMapStore::PutDerived(const MapRef& ref, const DerivedProfile& derived,
                                  const WriteContext& ctx) {
  Status s = ValidateDerived(derived);
  if (!s.ok()) return s;
  VersionRow row;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    auto r = Resolve(ref);
    if (!r.ok()) return r.status();
    row = *r;
  }
  if (derived.layers.geometry() != row.geometry) {
    return common::InvalidArgumentError("derived layers do not have the geometry of map '" +
                                        row.site + "/" + row.name + "'");
  }
  // Encode outside the lock, as in SaveMap.
  const int ts = row.tile_size;
  const std::vector<std::string> names = derived.layers.layer_names();
  const std::vector<TileSpec> specs = TilesOf(row.geometry, ts);
  std::vector<EncodedBlob> blobs(names.size() * specs.size());
  std::vector<char> present(blobs.size(), 0);
  try {
    ParallelFor(blobs.size(), options_.compression_threads, [&](size_t i) {
      const std::vector<float> cells =
          ExtractTile(derived.layers.at(names[i / specs.size()]), specs[i % specs.size()]);
      if (AllUnknown(cells)) return;
      blobs[i] = EncodeBlob(cells.data(), cells.size() * sizeof(float),
                            FloatCodec(cells.data(), cells.size()), options_.zstd_level);
      present[i] = 1;
    });
  } catch (const std::exception& e) {
    return common::InternalError(e.what());
  }
  const std::string registry_bytes = SerializeRegistry(derived.registry);
  const EncodedBlob registry_blob =
      EncodeBlob(registry_bytes.data(), registry_bytes.size(), Codec::kZstd, options_.zstd_level);
  std::vector<EncodedBlob> stored;
  std::vector<size_t> index;
  for (size_t i = 0; i < blobs.size(); ++i) {
    if (present[i]) {
      stored.push_back(std::move(blobs[i]));
      index.push_back(i);
    }
  }

  std::lock_guard<std::mutex> lock(mutex_);
  const int64_t now = WallUtime();
  s = WriteTransaction([&]() -> Status {
    sqlite::Statement exists = db_->Prepare(
        "SELECT id FROM derived WHERE map_version_id = ? AND profile_hash = ? AND "
        "code_version = ?");
    exists.Bind(1, row.id).Bind(2, derived.profile_hash).Bind(3, derived.code_version);
    if (exists.Step()) return Status::Ok();  // the first derivation stays
    std::vector<int64_t> registry_id;
    Status r = WriteBlobs({registry_blob}, &registry_id);
    if (!r.ok()) return r;
    sqlite::Statement d = db_->Prepare(
        "INSERT INTO derived(map_version_id, profile_hash, code_version, profile_name, "
        "created_utime, size_x, size_y, registry_blob_id) VALUES(?, ?, ?, ?, ?, ?, ?, ?)");
    d.Bind(1, row.id).Bind(2, derived.profile_hash).Bind(3, derived.code_version);
    d.Bind(4, derived.profile_name)
        .Bind(5, derived.created_utime != 0 ? derived.created_utime : now);
    d.Bind(6, row.geometry.size_x).Bind(7, row.geometry.size_y).Bind(8, registry_id[0]);
    if (!(r = d.Run()).ok()) return r;
    const int64_t derived_id = db_->LastInsertRowId();
    sqlite::Statement ln =
        db_->Prepare("INSERT INTO derived_layers(derived_id, name) VALUES(?, ?)");
    for (const std::string& name : names) {
      ln.Reset();
      ln.Bind(1, derived_id).Bind(2, name);
      if (!(r = ln.Run()).ok()) return r;
    }
    std::vector<int64_t> ids;
    if (!(r = WriteBlobs(stored, &ids)).ok()) return r;
    sqlite::Statement t = db_->Prepare(
        "INSERT INTO derived_tiles(derived_id, layer, tile_ix, tile_iy, blob_id) "
        "VALUES(?, ?, ?, ?, ?)");
    for (size_t k = 0; k < stored.size(); ++k) {
      const TileSpec& spec = specs[index[k] % specs.size()];
      t.Reset();
      t.Bind(1, derived_id).Bind(2, names[index[k] / specs.size()]).Bind(3, spec.tile_ix);
      t.Bind(4, spec.tile_iy).Bind(5, ids[k]);
      if (!(r = t.Run()).ok()) return r;
    }
    return Audit(ctx, ctx.utime != 0 ? ctx.utime : now, "derive", row.site, row.name, row.version,
                 "profile " + derived.profile_name + " (" + derived.profile_hash + "), code " +
                     derived.code_version);
  });
  if (!s.ok()) return WriteError(s, "caching layers of profile '" + derived.profile_name + "'");
  return Status::Ok();
}

Status SqliteMapStore::PutPlaces(const std::string& site, const std::vector<Place>& places,
                                 const WriteContext& ctx) {
  Status s = ValidateName("site name", site);
  if (!s.ok()) return s;
  for (const Place& p : places) {
    if (!(s = ValidatePlace(p)).ok()) return s;
  }
  std::lock_guard<std::mutex> lock(mutex_);
  const int64_t now = WallUtime();
  s = WriteTransaction([&]() -> Status {
    auto site_id = SiteId(site, true, now);
    if (!site_id.ok()) return site_id.status();
    sqlite::Statement st = db_->Prepare(
        "INSERT INTO places(site_id, name, polygon, updated_utime) VALUES(?, ?, ?, ?) "
        "ON CONFLICT(site_id, name) DO UPDATE SET polygon = excluded.polygon, "
        "updated_utime = excluded.updated_utime");
    std::string names;
    for (const Place& p : places) {
      const std::string polygon = SerializePolygon(p.polygon_m);
      st.Reset();
      st.Bind(1, *site_id).Bind(2, p.name).BindBlob(3, polygon.data(), polygon.size()).Bind(4, now);
      Status r = st.Run();
      if (!r.ok()) return r;
      names += (names.empty() ? "" : ", ") + p.name;
    }
    return Audit(ctx, ctx.utime != 0 ? ctx.utime : now, "put_place", site, "", 0, names);
  });
  if (!s.ok()) return WriteError(s, "storing places of site '" + site + "'");
  return Status::Ok();
}

Result<std::vector<Place>> SqliteMapStore::ListPlaces(const std::string& site) const {
  Status s = ValidateName("site name", site);
  if (!s.ok()) return s;
  std::lock_guard<std::mutex> lock(mutex_);
  sqlite::Statement find = db_->Prepare("SELECT id FROM sites WHERE name = ?");
  find.Bind(1, site);
  if (!find.Step()) {
    if (!find.status().ok()) return find.status();
    return common::NotFoundError("no site '" + site + "'");
  }
  sqlite::Statement st =
      db_->Prepare("SELECT name, polygon FROM places WHERE site_id = ? ORDER BY name");
  st.Bind(1, find.Int(0));
  std::vector<Place> out;
  while (st.Step()) {
    Place p;
    p.name = st.Text(0);
    auto polygon = ParsePolygon(st.Blob(1));
    if (!polygon.ok())
      return common::CorruptError("place '" + p.name + "': " + polygon.status().message());
    p.polygon_m = std::move(polygon).value();
    out.push_back(std::move(p));
  }
  if (!st.status().ok()) return st.status();
  return out;
}

Result<std::vector<std::string>> SqliteMapStore::ListSites() const {
  std::lock_guard<std::mutex> lock(mutex_);
  sqlite::Statement st = db_->Prepare("SELECT name FROM sites ORDER BY name");
  std::vector<std::string> out;
  while (st.Step()) out.push_back(st.Text(0));
  if (!st.status().ok()) return st.status();
  return out;
}

namespace {

AuditEntry ReadAudit(const sqlite::Statement& st) {
  AuditEntry e;
  e.id = st.Int(0);
  e.utime = st.Int(1);
  e.actor = st.Text(2);
  e.op = st.Text(3);
  e.site = st.Text(4);
  e.map = st.Text(5);
  e.version = st.Int(6);
  e.request_id = st.Int(7);
  e.detail = st.Text(8);
  return e;
}

constexpr char kAuditSelect[] =
    "SELECT id, utime, actor, op, site, map, version, request_id, detail FROM audit_log ";

}  // namespace

Result<std::vector<AuditEntry>> SqliteMapStore::ListAudit(int limit) const {
  std::lock_guard<std::mutex> lock(mutex_);
  sqlite::Statement st = db_->Prepare(std::string(kAuditSelect) + "ORDER BY id DESC LIMIT ?");
  st.Bind(1, std::max(0, limit));
  std::vector<AuditEntry> out;
  while (st.Step()) out.push_back(ReadAudit(st));
  if (!st.status().ok()) return st.status();
  return out;
}

Result<std::optional<AuditEntry>> SqliteMapStore::FindRequest(const std::string& actor,
                                                              int64_t request_id) const {
  std::lock_guard<std::mutex> lock(mutex_);
  sqlite::Statement st = db_->Prepare(
      std::string(kAuditSelect) + "WHERE actor = ? AND request_id = ? ORDER BY id DESC LIMIT 1");
  st.Bind(1, actor).Bind(2, request_id);
  if (st.Step()) return std::optional<AuditEntry>(ReadAudit(st));
  if (!st.status().ok()) return st.status();
  return std::optional<AuditEntry>();
}

Result<CheckReport> SqliteMapStore::Check(const ProgressFn& progress) const {
  std::lock_guard<std::mutex> lock(mutex_);
  CheckReport report;
  auto problem = [&](const std::string& p) {
    report.ok = false;
    if (report.problems.size() < 200) report.problems.push_back(p);
  };
  if (progress) progress(0.0, "integrity_check");
  {
    sqlite::Statement st = db_->Prepare("PRAGMA integrity_check");
    while (st.Step()) {
      const std::string line = st.Text(0);
      if (line != "ok") problem("integrity_check: " + line);
    }
    if (!st.status().ok()) {
      if (st.status().code() == common::StatusCode::kCorrupt) {
        problem("integrity_check: " + st.status().message());
        return report;
      }
      return st.status();
    }
  }
  {
    sqlite::Statement st = db_->Prepare("PRAGMA foreign_key_check");
    while (st.Step()) {
      problem("foreign key: row " + std::to_string(st.Int(1)) + " of table " + st.Text(0) +
              " refers to a missing row of " + st.Text(2));
    }
    if (!st.status().ok()) return st.status();
  }
  auto app = db_->QueryInt("PRAGMA application_id");
  auto version = db_->QueryInt("PRAGMA user_version");
  if (!app.ok() || *app != schema::kApplicationId) problem("application_id is not cairn's");
  if (!version.ok() || *version != schema::kCurrentVersion) {
    problem("user_version is not " + std::to_string(schema::kCurrentVersion));
  }
  // Tiles must lie in their grid and hold exactly their cells.
  {
    sqlite::Statement st = db_->Prepare(
        "SELECT s.name, m.name, v.version, l.name, t.tile_ix, t.tile_iy, v.size_x, v.size_y, "
        "v.tile_size, b.raw_size FROM layer_tiles t JOIN layers l ON l.id = t.layer_id "
        "JOIN map_versions v ON v.id = l.map_version_id JOIN maps m ON m.id = v.map_id "
        "JOIN sites s ON s.id = m.site_id JOIN blobs b ON b.id = t.blob_id");
    while (st.Step()) {
      const int tx = static_cast<int>(st.Int(4)), ty = static_cast<int>(st.Int(5));
      const int sx = static_cast<int>(st.Int(6)), sy = static_cast<int>(st.Int(7));
      const int ts = static_cast<int>(st.Int(8));
      const int64_t cells_x = std::min(ts, sx - tx * ts), cells_y = std::min(ts, sy - ty * ts);
      if (tx < 0 || ty < 0 || cells_x <= 0 || cells_y <= 0 ||
          st.Int(9) != cells_x * cells_y * static_cast<int64_t>(sizeof(float))) {
        problem("map " + st.Text(0) + "/" + st.Text(1) + " v" + std::to_string(st.Int(2)) +
                " layer " + st.Text(3) + ": tile (" + std::to_string(tx) + ", " +
                std::to_string(ty) + ") does not fit the grid");
      }
    }
    if (!st.status().ok()) return st.status();
  }
  auto maps = db_->QueryInt("SELECT count(*) FROM map_versions");
  report.maps_checked = maps.ok() ? *maps : 0;
  // Every blob decodes to its size and checksum.
  auto total = db_->QueryInt("SELECT count(*) FROM blobs");
  const int64_t n = total.ok() ? *total : 0;
  sqlite::Statement st =
      db_->Prepare("SELECT id, codec, raw_size, raw_crc32, data, stored_crc32 FROM blobs");
  while (st.Step()) {
    const std::string data = st.Blob(4);
    const uint32_t raw_crc32 = static_cast<uint32_t>(st.Int(3));
    auto decoded = DecodeBlob(static_cast<Codec>(st.Int(1)), data, st.Int(2), raw_crc32,
                              /*verify_crc=*/true);
    if (!decoded.ok()) {
      problem("blob " + std::to_string(st.Int(0)) + ": " + decoded.status().message());
    } else if (!st.IsNull(5) &&
               StoredBlobCrc32(static_cast<int>(st.Int(1)), st.Int(2), raw_crc32, data.data(),
                               data.size()) != static_cast<uint32_t>(st.Int(5))) {
      problem("blob " + std::to_string(st.Int(0)) +
              ": decodes, but its bytes or header differ from what was stored (stored_crc32)");
    }
    ++report.blobs_checked;
    if (progress && (report.blobs_checked % 64 == 0)) {
      progress(n > 0 ? static_cast<double>(report.blobs_checked) / n : 1.0, "blobs");
    }
  }
  if (!st.status().ok()) {
    if (st.status().code() == common::StatusCode::kCorrupt) {
      problem(st.status().message());
    } else {
      return st.status();
    }
  }
  if (progress) progress(1.0, "done");
  return report;
}

bool SqliteMapStore::CheckpointIfIdle(double idle_s) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!dirty_ || options_.read_only) return false;
  if (WallUtime() - last_write_utime_ < static_cast<int64_t>(idle_s * 1e6)) return false;
  dirty_ = false;
  return db_->Exec("PRAGMA wal_checkpoint(PASSIVE)").ok();
}

Result<int64_t> SqliteMapStore::Vacuum(const ProgressFn& progress) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (options_.read_only) return common::InvalidArgumentError("the store is open read-only");
  auto size_of = [&]() -> int64_t {
    std::error_code ec;
    int64_t size = 0;
    for (const char* suffix : {"", "-wal"}) {
      const auto s = fs::file_size(path_ + suffix, ec);
      if (!ec) size += static_cast<int64_t>(s);
    }
    return size;
  };
  const int64_t before = size_of();
  if (progress) progress(0.1, "unreferenced blobs");
  Status s = WriteTransaction([&]() -> Status {
    return db_->Exec(
        "DELETE FROM blobs WHERE NOT EXISTS (SELECT 1 FROM layer_tiles t WHERE t.blob_id = "
        "blobs.id) AND NOT EXISTS (SELECT 1 FROM derived_tiles t WHERE t.blob_id = blobs.id) "
        "AND NOT EXISTS (SELECT 1 FROM octomaps o WHERE o.blob_id = blobs.id) AND NOT EXISTS "
        "(SELECT 1 FROM derived d WHERE d.registry_blob_id = blobs.id)");
  });
  if (!s.ok()) return WriteError(s, "vacuum");
  if (progress) progress(0.4, "vacuum");
  if (!(s = db_->Exec("VACUUM")).ok()) return WriteError(s, "vacuum");
  if (progress) progress(0.9, "checkpoint");
  db_->Exec("PRAGMA wal_checkpoint(TRUNCATE)");
  if (progress) progress(1.0, "done");
  return before - size_of();
}

Result<std::map<std::string, std::string>> SqliteMapStore::BaseBlobBytes(const MapRef& ref) const {
  std::lock_guard<std::mutex> lock(mutex_);
  auto row = Resolve(ref);
  if (!row.ok()) return row.status();
  sqlite::Statement st = db_->Prepare(
      "SELECT l.name, t.tile_ix, t.tile_iy, b.data FROM layers l JOIN layer_tiles t ON "
      "t.layer_id = l.id JOIN blobs b ON b.id = t.blob_id WHERE l.map_version_id = ?");
  st.Bind(1, row->id);
  std::map<std::string, std::string> out;
  while (st.Step()) {
    out[st.Text(0) + "/" + std::to_string(st.Int(1)) + "/" + std::to_string(st.Int(2))] =
        st.Blob(3);
  }
  if (!st.status().ok()) return st.status();
  return out;
}

Result<int64_t> SqliteMapStore::BaseBytes(const MapRef& ref) const {
  std::lock_guard<std::mutex> lock(mutex_);
  auto row = Resolve(ref);
  if (!row.ok()) return row.status();
  sqlite::Statement st = db_->Prepare(
      "SELECT COALESCE(SUM(length(b.data)), 0) FROM layers l JOIN layer_tiles t ON "
      "t.layer_id = l.id JOIN blobs b ON b.id = t.blob_id WHERE l.map_version_id = ?");
  st.Bind(1, row->id);
  if (!st.Step()) return st.status();
  return st.Int(0);
}

}  // namespace cairn::mapstore
