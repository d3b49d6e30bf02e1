// SqliteMapStore's catalogue: robot profiles, places and sites, the audit log, and the
// integrity check of the whole file.

#include <algorithm>
#include <regex>
#include <set>

#include "mapstore/names.h"
#include "mapstore/schema.h"
#include "mapstore/sqlite_map_store.h"
#include "mapstore/sqlite_store_rows.h"
#include "mapstore/store_util.h"

namespace cairn::mapstore {

using common::Result;
using common::Status;

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

// A problem found by Check (the first 200 are kept).
void AddProblem(CheckReport* report, const std::string& problem) {
  report->ok = false;
  if (report->problems.size() < 200) report->problems.push_back(problem);
}

}  // namespace

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

Status SqliteMapStore::PutPlaces(const std::string& site, const std::vector<Place>& places,
                                 const WriteContext& ctx) {
  Status s = ValidatePlaces(site, places);
  if (!s.ok()) return s;
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

Status SqliteMapStore::CheckPragmas(CheckReport* report, bool* go_on) const {
  *go_on = true;
  sqlite::Statement integrity = db_->Prepare("PRAGMA integrity_check");
  while (integrity.Step()) {
    const std::string line = integrity.Text(0);
    if (line == "ok") continue;
    // SQLite names pages ("Tree 7 page 312 cell 0: ...", "Page 312: ..."): say whose they are,
    // by the tree's root page (sqlite_master) or else by the page itself (dbstat).
    static const std::regex kTree("Tree ([0-9]+)");
    static const std::regex kPage("[Pp]age ([0-9]+)");
    std::smatch m;
    std::string owner;
    if (std::regex_search(line, m, kTree)) owner = RootOwner(std::stoll(m[1].str()));
    if (owner.empty() && std::regex_search(line, m, kPage)) {
      owner = PageOwner(std::stoll(m[1].str()));
    }
    AddProblem(report, "integrity_check: " + line + (owner.empty() ? "" : " [" + owner + "]"));
  }
  if (!integrity.status().ok()) {
    if (integrity.status().code() != common::StatusCode::kCorrupt) return integrity.status();
    AddProblem(report, "integrity_check: " + integrity.status().message());
    // The integrity check stops at a page it cannot read; the blobs are still worth reading one
    // by one (each one that fails is named with its maps) unless not even the schema reads.
    if (!db_->QueryInt("SELECT count(*) FROM sqlite_master").ok()) {
      *go_on = false;
      return Status::Ok();
    }
  }
  sqlite::Statement keys = db_->Prepare("PRAGMA foreign_key_check");
  while (keys.Step()) {
    AddProblem(report, "foreign key: row " + std::to_string(keys.Int(1)) + " of table " +
                           keys.Text(0) + " refers to a missing row of " + keys.Text(2));
  }
  if (!keys.status().ok()) {
    if (keys.status().code() != common::StatusCode::kCorrupt) return keys.status();
    AddProblem(report, "foreign_key_check: " + keys.status().message());
  }
  auto app = db_->QueryInt("PRAGMA application_id");
  auto version = db_->QueryInt("PRAGMA user_version");
  if (!app.ok() || *app != schema::kApplicationId) {
    AddProblem(report, "application_id is not cairn's");
  }
  if (!version.ok() || *version != schema::kCurrentVersion) {
    AddProblem(report, "user_version is not " + std::to_string(schema::kCurrentVersion));
  }
  return Status::Ok();
}

Status SqliteMapStore::CheckTilePlaces(CheckReport* report) const {
  // Tiles must lie in their version's grid and hold exactly their cells.
  sqlite::Statement versions = db_->Prepare(kVersionSelect);
  std::vector<VersionRow> rows;
  while (versions.Step()) rows.push_back(ReadVersionRow(versions));
  if (!versions.status().ok()) return versions.status();
  report->maps_checked = static_cast<int64_t>(rows.size());
  sqlite::Statement st = db_->Prepare(
      "SELECT l.name, t.tile_ix, t.tile_iy, b.raw_size FROM layer_tiles t JOIN layers l ON "
      "l.id = t.layer_id JOIN blobs b ON b.id = t.blob_id WHERE l.map_version_id = ?");
  for (const VersionRow& row : rows) {
    st.Reset();
    st.Bind(1, row.id);
    const int ts = row.tile_size;
    while (st.Step()) {
      const int tx = static_cast<int>(st.Int(1)), ty = static_cast<int>(st.Int(2));
      const int64_t cells_x = std::min(ts, row.geometry.size_x - tx * ts);
      const int64_t cells_y = std::min(ts, row.geometry.size_y - ty * ts);
      if (tx < 0 || ty < 0 || cells_x <= 0 || cells_y <= 0 ||
          st.Int(3) != cells_x * cells_y * static_cast<int64_t>(sizeof(float))) {
        AddProblem(report, "map " + row.site + "/" + row.name + " v" + std::to_string(row.version) +
                               " layer " + st.Text(0) + ": tile (" + std::to_string(tx) + ", " +
                               std::to_string(ty) + ") does not fit the grid");
      }
    }
    if (!st.status().ok()) return st.status();
  }
  return Status::Ok();
}

std::string SqliteMapStore::RootOwner(int64_t root_page) const {
  try {
    sqlite::Statement st =
        db_->Prepare("SELECT type, name, tbl_name FROM sqlite_master WHERE rootpage = ?");
    st.Bind(1, root_page);
    if (!st.Step()) return "";
    if (st.Text(0) == "index") return "index " + st.Text(1) + " of table " + st.Text(2);
    return "table " + st.Text(1);
  } catch (const std::exception&) {
    return "";
  }
}

std::string SqliteMapStore::PageOwner(int64_t page) const {
  // dbstat reads the b-trees itself, so on a damaged file it may fail: then nothing is said.
  try {
    sqlite::Statement st = db_->Prepare(
        "SELECT d.name, coalesce(m.type, 'table'), coalesce(m.tbl_name, d.name) FROM dbstat d "
        "LEFT JOIN sqlite_master m ON m.name = d.name WHERE d.pageno = ? LIMIT 1");
    st.Bind(1, page);
    if (!st.Step()) return "";
    const std::string type = st.Text(1);
    const std::string what =
        type == "index" ? "index " + st.Text(0) + " of table " + st.Text(2) : "table " + st.Text(0);
    return "page " + std::to_string(page) + " belongs to " + what;
  } catch (const std::exception&) {
    return "";
  }
}

std::vector<std::string> SqliteMapStore::BlobUsers(int64_t blob_id) const {
  std::vector<std::string> users;
  const auto version_of = [](const sqlite::Statement& st, int first) {
    return "map " + st.Text(first) + "/" + st.Text(first + 1) + " v" +
           std::to_string(st.Int(first + 2));
  };
  sqlite::Statement base = db_->Prepare(
      "SELECT s.name, m.name, v.version, l.name, t.tile_ix, t.tile_iy FROM layer_tiles t "
      "JOIN layers l ON l.id = t.layer_id JOIN map_versions v ON v.id = l.map_version_id JOIN "
      "maps m ON m.id = v.map_id JOIN sites s ON s.id = m.site_id WHERE t.blob_id = ? "
      "ORDER BY s.name, m.name, v.version, l.name");
  base.Bind(1, blob_id);
  while (base.Step()) {
    users.push_back(version_of(base, 0) + " layer " + base.Text(3) + " tile (" +
                    std::to_string(base.Int(4)) + ", " + std::to_string(base.Int(5)) + ")");
  }
  sqlite::Statement derived = db_->Prepare(
      "SELECT s.name, m.name, v.version, d.profile_name, t.layer, t.tile_ix, t.tile_iy FROM "
      "derived_tiles t JOIN derived d ON d.id = t.derived_id JOIN map_versions v ON v.id = "
      "d.map_version_id JOIN maps m ON m.id = v.map_id JOIN sites s ON s.id = m.site_id WHERE "
      "t.blob_id = ?");
  derived.Bind(1, blob_id);
  while (derived.Step()) {
    users.push_back(version_of(derived, 0) + " profile " + derived.Text(3) + " cached layer " +
                    derived.Text(4) + " tile (" + std::to_string(derived.Int(5)) + ", " +
                    std::to_string(derived.Int(6)) + ")");
  }
  sqlite::Statement registry = db_->Prepare(
      "SELECT s.name, m.name, v.version, d.profile_name FROM derived d JOIN map_versions v ON "
      "v.id = d.map_version_id JOIN maps m ON m.id = v.map_id JOIN sites s ON s.id = m.site_id "
      "WHERE d.registry_blob_id = ?");
  registry.Bind(1, blob_id);
  while (registry.Step()) {
    users.push_back(version_of(registry, 0) + " profile " + registry.Text(3) +
                    " cached obstacle verdicts");
  }
  sqlite::Statement octomap = db_->Prepare(
      "SELECT s.name, m.name, v.version FROM octomaps o JOIN map_versions v ON v.id = "
      "o.map_version_id JOIN maps m ON m.id = v.map_id JOIN sites s ON s.id = m.site_id WHERE "
      "o.blob_id = ?");
  octomap.Bind(1, blob_id);
  while (octomap.Step()) users.push_back(version_of(octomap, 0) + " OctoMap");
  return users;
}

Status SqliteMapStore::CheckBlobs(CheckReport* report, const ProgressFn& progress) const {
  // Every blob decodes to its size and checksum. Each is read by its id (found in the blobs
  // table and in every table that refers to one), so a damaged page costs only the blobs on it,
  // and each bad one is named with the maps, layers and tiles it holds.
  std::set<int64_t> ids;
  for (const char* sql :
       {"SELECT id FROM blobs", "SELECT blob_id FROM layer_tiles", "SELECT blob_id FROM octomaps",
        "SELECT blob_id FROM derived_tiles", "SELECT registry_blob_id FROM derived"}) {
    sqlite::Statement st = db_->Prepare(sql);
    while (st.Step()) ids.insert(st.Int(0));
    if (!st.status().ok()) {
      if (st.status().code() != common::StatusCode::kCorrupt) return st.status();
      AddProblem(report, std::string("listing blobs (") + sql + "): " + st.status().message());
    }
  }
  const auto named = [&](int64_t id) {
    std::vector<std::string> users = BlobUsers(id);
    std::string out = "blob " + std::to_string(id);
    if (users.empty()) return out + " (unreferenced)";
    out += " (";
    for (size_t i = 0; i < users.size() && i < 4; ++i) out += (i > 0 ? "; " : "") + users[i];
    if (users.size() > 4) out += "; and " + std::to_string(users.size() - 4) + " more";
    return out + ")";
  };
  const int64_t n = static_cast<int64_t>(ids.size());
  sqlite::Statement st =
      db_->Prepare("SELECT codec, raw_size, raw_crc32, data, stored_crc32 FROM blobs WHERE id = ?");
  for (const int64_t id : ids) {
    st.Reset();
    st.Bind(1, id);
    if (!st.Step()) {
      if (!st.status().ok()) {
        if (st.status().code() != common::StatusCode::kCorrupt &&
            st.status().code() != common::StatusCode::kInternal) {
          return st.status();
        }
        AddProblem(report, named(id) + ": cannot be read: " + st.status().message());
      } else {
        AddProblem(report, named(id) + ": is referred to but missing");
      }
    } else {
      const std::string data = st.Blob(3);
      const uint32_t raw_crc32 = static_cast<uint32_t>(st.Int(2));
      auto decoded = DecodeBlob(static_cast<Codec>(st.Int(0)), data, st.Int(1), raw_crc32,
                                /*verify_crc=*/true);
      if (!decoded.ok()) {
        AddProblem(report, named(id) + ": " + decoded.status().message());
      } else if (!st.IsNull(4) &&
                 StoredBlobCrc32(static_cast<int>(st.Int(0)), st.Int(1), raw_crc32, data.data(),
                                 data.size()) != static_cast<uint32_t>(st.Int(4))) {
        AddProblem(report, named(id) +
                               ": decodes, but its bytes or header differ from what was stored "
                               "(stored_crc32)");
      }
    }
    ++report->blobs_checked;
    if (progress && (report->blobs_checked % 64 == 0)) {
      progress(n > 0 ? static_cast<double>(report->blobs_checked) / n : 1.0, "blobs");
    }
  }
  return Status::Ok();
}

Result<CheckReport> SqliteMapStore::Check(const ProgressFn& progress) const {
  std::lock_guard<std::mutex> lock(mutex_);
  CheckReport report;
  if (progress) progress(0.0, "integrity_check");
  bool go_on = true;
  Status s = CheckPragmas(&report, &go_on);
  if (!s.ok()) return s;
  if (!go_on) return report;
  // A damaged page makes a query fail part-way: say so and go on to the blobs.
  if (!(s = CheckTilePlaces(&report)).ok()) {
    if (s.code() != common::StatusCode::kCorrupt) return s;
    AddProblem(&report, "tile places: " + s.message());
  }
  if (!(s = CheckBlobs(&report, progress)).ok()) return s;
  if (progress) progress(1.0, "done");
  return report;
}

}  // namespace cairn::mapstore
