#include "mapstore/sqlite_map_store.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <map>
#include <set>
#include <thread>

#include <fcntl.h>
#include <sqlite3.h>
#include <unistd.h>

#include "common/check.h"
#include "mapstore/names.h"
#include "mapstore/schema.h"
#include "mapstore/sqlite_store_rows.h"
#include "mapstore/store_util.h"

// The SQLite store: opening (and creating or migrating) a database, write transactions, version
// rows, listing, deleting, checkpoints and vacuum. Saves are in sqlite_save.cc, reads of layers
// and obstacles in sqlite_layers.cc, the derived cache in sqlite_derived.cc, profiles, places,
// the audit log and the integrity check in sqlite_catalog.cc.

namespace cairn::mapstore {

namespace fs = std::filesystem;
using common::Result;
using common::Status;

namespace {

std::string JournalMode(sqlite::Database* db, const std::string& mode) {
  sqlite::Statement st = db->Prepare("PRAGMA journal_mode = " + mode);
  return st.Step() ? st.Text(0) : "";
}

// The header a database identifies itself by.
struct Header {
  int64_t application_id{0};
  int64_t user_version{0};
  int64_t tables{0};
  bool empty() const { return application_id == 0 && user_version == 0 && tables == 0; }
};

// Why this process cannot write `path` and the WAL beside it, or "" when it can. Opening the
// file for writing changes nothing in it (not even its mtime).
std::string WriteBlocker(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDWR | O_CLOEXEC);
  if (fd < 0) {
    return std::string("the file is not writable (") + std::strerror(errno) + ")";
  }
  ::close(fd);
  std::error_code ec;
  if (fs::exists(path + "-wal", ec)) return "";
  fs::path dir = fs::path(path).parent_path();
  if (dir.empty()) dir = ".";
  if (::access(dir.c_str(), W_OK) != 0) {
    return "its folder '" + dir.string() + "' is not writable (" + std::strerror(errno) +
           "), so SQLite cannot make its write-ahead log there";
  }
  return "";
}

// A WAL database is read through a shared-memory index file beside it (-shm). When neither it
// nor a WAL is there and the folder does not let this process make one (a read-only mount, a
// folder of mode 0555), SQLite can only read the file as immutable: no lock, no index.
bool NeedsImmutable(const std::string& path) {
  std::error_code ec;
  if (fs::exists(path + "-wal", ec) || fs::exists(path + "-shm", ec)) return false;
  fs::path dir = fs::path(path).parent_path();
  if (dir.empty()) dir = ".";
  return ::access(dir.c_str(), W_OK) != 0;
}

}  // namespace

const char* SynchronousName(Synchronous mode) {
  return mode == Synchronous::kFull ? "full" : "normal";
}

std::optional<Synchronous> ParseSynchronous(const std::string& text) {
  std::string lower;
  for (char c : text) lower += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (lower == "normal") return Synchronous::kNormal;
  if (lower == "full") return Synchronous::kFull;
  return std::nullopt;
}

Status SqliteMapStore::WriteError(const Status& s, const std::string& what) const {
  if (s.code() == common::StatusCode::kResourceExhausted) {
    const std::string quota = options_.max_page_count > 0
                                  ? " (or the database quota of " +
                                        std::to_string(options_.max_page_count) +
                                        " pages is reached)"
                                  : "";
    return common::ResourceExhaustedError(
        what + ": disk full: '" + path_ + "' cannot grow, the disk holding it is full" + quota +
        "; nothing of this change was written and everything committed before is intact (" +
        s.message() + ")");
  }
  if (s.code() == common::StatusCode::kUnavailable) {
    return common::UnavailableError(what + ": '" + path_ + "' stayed locked by another writer (" +
                                    s.message() + ")");
  }
  if (s.message().find(path_) != std::string::npos) {
    return Status(s.code(), what + ": " + s.message());
  }
  if (s.code() == common::StatusCode::kPermissionDenied) {
    return Status(s.code(), what + ": '" + path_ + "' cannot be written (" + s.message() +
                                "); nothing of this change was written");
  }
  return Status(s.code(), what + " in '" + path_ + "': " + s.message());
}

Status SqliteMapStore::Located(const Status& s) const {
  if (s.ok() || s.message().find(path_) != std::string::npos) return s;
  if (s.code() == common::StatusCode::kCorrupt) {
    return common::CorruptError(s.message() + " (database '" + path_ + "'; `cairn-map check --db " +
                                path_ + "` lists every damaged map)");
  }
  if (s.code() == common::StatusCode::kInternal) {
    return common::InternalError(s.message() + " (database '" + path_ + "')");
  }
  return s;
}

Result<int64_t> SqliteMapStore::SynchronousLevel() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return db_->QueryInt("PRAGMA synchronous");
}

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
  // A file this process cannot write is served read-only, saying why writes fail.
  SqliteOptions effective = options;
  std::string refusal;
  if (!memory && !options.read_only && fs::exists(path)) {
    const std::string blocker = WriteBlocker(path);
    if (!blocker.empty()) {
      refusal = "'" + path + "' is read-only for this process: " + blocker;
      effective.read_only = true;
    }
  }
  const bool immutable = !memory && effective.read_only && fs::exists(path) && NeedsImmutable(path);
  auto db =
      sqlite::Database::Open(path, effective.read_only, effective.create_if_missing, immutable);
  if (!db.ok()) return db.status();
  std::unique_ptr<SqliteMapStore> store(new SqliteMapStore(path, effective, std::move(db).value()));
  store->write_refusal_ = refusal;
  Status s = store->Initialise();
  if (!s.ok()) {
    if (refusal.empty()) return s;
    return Status(s.code(), s.message() + " (opened read-only: " + refusal + ")");
  }
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
  const Header header{*app, *version, *tables};
  if (!header.empty() && header.application_id != schema::kApplicationId) {
    char buf[64];
    std::snprintf(buf, sizeof(buf), "application_id 0x%08llx, expected 0x%08llx",
                  static_cast<unsigned long long>(header.application_id),
                  static_cast<unsigned long long>(schema::kApplicationId));
    return not_cairn(buf);
  }
  if (header.user_version > schema::kCurrentVersion) {
    return common::InvalidArgumentError(
        "'" + path_ + "' has schema version " + std::to_string(header.user_version) +
        ", newer than this build's " + std::to_string(schema::kCurrentVersion) +
        "; use a newer cairn");
  }
  s = options_.read_only ? InitialiseReadOnly(header.empty(), header.user_version)
                         : InitialiseWritable(header.empty(), header.user_version);
  return s.ok() ? VerifySchema() : s;
}

namespace {

// The columns of every table of the current schema, as schema::Create makes them.
const std::map<std::string, std::set<std::string>>& ExpectedColumns() {
  static const std::map<std::string, std::set<std::string>> columns = [] {
    std::map<std::string, std::set<std::string>> out;
    auto db = sqlite::Database::Open(":memory:", false, true);
    CAIRN_DEMAND(db.ok() && schema::Create(db->get()).ok());
    std::vector<std::string> tables;
    auto list = (*db)->Prepare("SELECT name FROM sqlite_master WHERE type = 'table'");
    while (list.Step()) tables.push_back(list.Text(0));
    for (const std::string& table : tables) {
      auto info = (*db)->Prepare("SELECT name FROM pragma_table_info(?1)");
      info.Bind(1, table);
      while (info.Step()) out[table].insert(info.Text(0));
    }
    return out;
  }();
  return columns;
}

}  // namespace

// A file whose header says it is a cairn database of this schema, but whose tables are not the
// schema's (a damaged or hand-made file), would fail later in every query: refuse it now.
Status SqliteMapStore::VerifySchema() {
  try {
    for (const auto& [table, expected] : ExpectedColumns()) {
      std::set<std::string> found;
      auto info = db_->Prepare("SELECT name FROM pragma_table_info(?1)");
      info.Bind(1, table);
      while (info.Step()) found.insert(info.Text(0));
      if (!info.status().ok()) return info.status();
      if (found.empty()) {
        return common::CorruptError("'" + path_ +
                                    "' is not a usable cairn map database: no table " + table);
      }
      for (const std::string& column : expected) {
        if (found.count(column) == 0) {
          return common::CorruptError("'" + path_ + "' is not a usable cairn map database: table " +
                                      table + " has no column " + column);
        }
      }
    }
  } catch (const std::exception& e) {
    return common::CorruptError("'" + path_ + "' is not a usable cairn map database: " + e.what());
  }
  return Status::Ok();
}

Status SqliteMapStore::InitialiseReadOnly(bool empty, int64_t version) {
  if (empty) return common::InvalidArgumentError("'" + path_ + "' is an empty database");
  if (version < schema::kCurrentVersion) {
    return common::InvalidArgumentError(
        "'" + path_ + "' has schema version " + std::to_string(version) +
        "; open it for writing once (for example `cairn-map migrate --db " + path_ +
        "`) to migrate it to version " + std::to_string(schema::kCurrentVersion));
  }
  schema_version_ = static_cast<int>(version);
  return db_->Exec("PRAGMA query_only = 1; PRAGMA foreign_keys = ON; PRAGMA cache_size = -" +
                   std::to_string(options_.cache_size_kib));
}

Status SqliteMapStore::InitialiseWritable(bool empty, int64_t version) {
  // WAL first (page size only matters for a new file), then create or migrate inside one
  // IMMEDIATE transaction that re-reads the version, in case another process got there first.
  const bool memory = path_ == ":memory:";
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
  Status s = db_->Exec(std::string("PRAGMA foreign_keys = ON; PRAGMA synchronous = ") +
                       (options_.synchronous == Synchronous::kFull ? "FULL" : "NORMAL") +
                       "; PRAGMA cache_size = -" + std::to_string(options_.cache_size_kib));
  if (s.ok() && !memory) {
    s = db_->Exec("PRAGMA wal_autocheckpoint = " +
                  std::to_string(options_.wal_autocheckpoint_pages));
  }
  if (s.ok() && options_.max_page_count > 0) {
    s = db_->Exec("PRAGMA max_page_count = " + std::to_string(options_.max_page_count));
  }
  if (!s.ok()) return s;
  if (version < schema::kCurrentVersion) {
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
  if (!write_refusal_.empty()) {
    return common::PermissionDeniedError(write_refusal_ +
                                         "; nothing was written (loads, lists and exports still "
                                         "work)");
  }
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

SqliteMapStore::VersionRow SqliteMapStore::ReadVersionRow(const sqlite::Statement& st) {
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
  return row;
}

Status SqliteMapStore::NoVersion(const MapRef& ref) const {
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
  if (!st.Step()) return st.status().ok() ? NoVersion(ref) : st.status();
  VersionRow row = ReadVersionRow(st);
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
  while (st.Step()) rows.push_back(ReadVersionRow(st));
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

bool SqliteMapStore::CheckpointIfIdle(double idle_s) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!dirty_ || options_.read_only) return false;
  if (WallUtime() - last_write_utime_ < static_cast<int64_t>(idle_s * 1e6)) return false;
  dirty_ = false;
  return db_->Exec("PRAGMA wal_checkpoint(PASSIVE)").ok();
}

Result<int64_t> SqliteMapStore::Vacuum(const ProgressFn& progress) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!write_refusal_.empty()) return common::PermissionDeniedError(write_refusal_);
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

}  // namespace cairn::mapstore
