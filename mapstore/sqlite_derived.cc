// SqliteMapStore's derived cache: profile layers and verdicts of a map version, keyed by the
// profile's content hash and the mapping code version.

#include <set>

#include "mapstore/sqlite_map_store.h"
#include "mapstore/sqlite_store_rows.h"
#include "mapstore/store_util.h"

namespace cairn::mapstore {

using common::Result;
using common::Status;

namespace {

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

Result<std::optional<SqliteMapStore::DerivedHeader>> SqliteMapStore::FindDerivedHeader(
    const VersionRow& row, const std::string& profile_hash, const std::string& code_version) const {
  sqlite::Statement st = db_->Prepare(
      "SELECT d.id, d.profile_name, d.created_utime, b.codec, b.raw_size, b.raw_crc32, b.data "
      "FROM derived d JOIN blobs b ON b.id = d.registry_blob_id "
      "WHERE d.map_version_id = ? AND d.profile_hash = ? AND d.code_version = ?");
  st.Bind(1, row.id).Bind(2, profile_hash).Bind(3, code_version);
  if (!st.Step()) {
    if (!st.status().ok()) return Located(st.status());
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
  if (!registry.ok()) return Located(registry.status());
  out.registry = std::move(registry).value();
  sqlite::Statement ln = db_->Prepare("SELECT name FROM derived_layers WHERE derived_id = ?");
  ln.Bind(1, out.id);
  while (ln.Step()) out.layers.insert(ln.Text(0));
  if (!ln.status().ok()) return Located(ln.status());
  return std::optional<DerivedHeader>(std::move(out));
}

Result<std::optional<std::pair<SqliteMapStore::VersionRow, SqliteMapStore::DerivedHeader>>>
SqliteMapStore::ResolveDerived(const MapRef& ref, const std::string& profile_hash,
                               const std::string& code_version) const {
  using Found = std::optional<std::pair<VersionRow, DerivedHeader>>;
  auto row = Resolve(ref);
  if (!row.ok()) return Located(row.status());
  auto header = FindDerivedHeader(*row, profile_hash, code_version);
  if (!header.ok()) return Located(header.status());
  std::optional<DerivedHeader> found = std::move(header).value();
  if (!found) return Found();
  return Found(std::make_pair(std::move(row).value(), std::move(*found)));
}

Result<std::optional<DerivedProfile>> SqliteMapStore::FindDerived(const MapRef& ref,
                                                                  const std::string& profile_hash,
                                                                  const std::string& code_version,
                                                                  const LayerQuery& query) const {
  std::lock_guard<std::mutex> lock(mutex_);
  auto resolved = ResolveDerived(ref, profile_hash, code_version);
  if (!resolved.ok()) return Located(resolved.status());
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
  if (!wanted.ok()) return Located(wanted.status());
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
    if (!read.ok()) return Located(read);
  }
  return std::optional<DerivedProfile>(std::move(out));
}

Result<std::optional<StoredDerived>> SqliteMapStore::FindDerivedTiles(
    const MapRef& ref, const std::string& profile_hash, const std::string& code_version,
    const std::vector<std::string>& layers, int /*tile_size*/) const {
  std::lock_guard<std::mutex> lock(mutex_);
  auto resolved = ResolveDerived(ref, profile_hash, code_version);
  if (!resolved.ok()) return Located(resolved.status());
  auto found = std::move(resolved).value();
  if (!found) return std::optional<StoredDerived>();
  const VersionRow* row = &found->first;
  DerivedHeader& h = found->second;
  StoredDerived out;
  out.profile_name = h.profile_name;
  out.registry = std::move(h.registry);
  auto wanted = CachedLayersWanted(h.layers, layers, out.profile_name);
  if (!wanted.ok()) return Located(wanted.status());
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
    if (!read.ok()) return Located(read);
    out.layers.push_back(std::move(layer));
  }
  Status checked = CheckStoredLayers(out.layers, label);
  if (!checked.ok()) return Located(checked);
  return std::optional<StoredDerived>(std::move(out));
}

Result<std::vector<DerivedInfo>> SqliteMapStore::ListDerived(const MapRef& ref) const {
  std::lock_guard<std::mutex> lock(mutex_);
  auto row = Resolve(ref);
  if (!row.ok()) return Located(row.status());
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
  if (!st.status().ok()) return Located(st.status());
  sqlite::Statement ln =
      db_->Prepare("SELECT name FROM derived_layers WHERE derived_id = ? ORDER BY name");
  for (size_t i = 0; i < out.size(); ++i) {
    ln.Reset();
    ln.Bind(1, ids[i]);
    while (ln.Step()) out[i].layers.push_back(ln.Text(0));
  }
  return out;
}

Status SqliteMapStore::InsertDerived(const VersionRow& row, const DerivedProfile& derived,
                                     const EncodedTiles& tiles, const EncodedBlob& registry,
                                     int64_t now) {
  std::vector<int64_t> registry_id;
  Status r = WriteBlobs({registry}, &registry_id);
  if (!r.ok()) return r;
  sqlite::Statement d = db_->Prepare(
      "INSERT INTO derived(map_version_id, profile_hash, code_version, profile_name, "
      "created_utime, size_x, size_y, registry_blob_id) VALUES(?, ?, ?, ?, ?, ?, ?, ?)");
  d.Bind(1, row.id).Bind(2, derived.profile_hash).Bind(3, derived.code_version);
  d.Bind(4, derived.profile_name).Bind(5, derived.created_utime != 0 ? derived.created_utime : now);
  d.Bind(6, row.geometry.size_x).Bind(7, row.geometry.size_y).Bind(8, registry_id[0]);
  if (!(r = d.Run()).ok()) return r;
  const int64_t derived_id = db_->LastInsertRowId();
  sqlite::Statement ln = db_->Prepare("INSERT INTO derived_layers(derived_id, name) VALUES(?, ?)");
  for (const std::string& name : tiles.layer_names) {
    ln.Reset();
    ln.Bind(1, derived_id).Bind(2, name);
    if (!(r = ln.Run()).ok()) return r;
  }
  std::vector<int64_t> ids;
  if (!(r = WriteBlobs(tiles.blobs, &ids)).ok()) return r;
  sqlite::Statement t = db_->Prepare(
      "INSERT INTO derived_tiles(derived_id, layer, tile_ix, tile_iy, blob_id) "
      "VALUES(?, ?, ?, ?, ?)");
  for (size_t k = 0; k < tiles.blobs.size(); ++k) {
    const auto [layer, spec_index] = tiles.place[k];
    const TileSpec& spec = tiles.specs[spec_index];
    t.Reset();
    t.Bind(1, derived_id).Bind(2, tiles.layer_names[layer]).Bind(3, spec.tile_ix);
    t.Bind(4, spec.tile_iy).Bind(5, ids[k]);
    if (!(r = t.Run()).ok()) return r;
  }
  return Status::Ok();
}

Status SqliteMapStore::PutDerived(const MapRef& ref, const DerivedProfile& derived,
                                  const WriteContext& ctx) {
  Status s = ValidateDerived(derived);
  if (!s.ok()) return s;
  VersionRow row;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    auto r = Resolve(ref);
    if (!r.ok()) return Located(r.status());
    row = *r;
  }
  if (derived.layers.geometry() != row.geometry) {
    return common::InvalidArgumentError("derived layers do not have the geometry of map '" +
                                        row.site + "/" + row.name + "'");
  }
  // Encode outside the lock, as in SaveMap.
  EncodedTiles tiles;
  try {
    tiles = EncodeLayers(derived.layers, row.tile_size, {}, false);
  } catch (const std::exception& e) {
    return common::InternalError(e.what());
  }
  const std::string registry_bytes = SerializeRegistry(derived.registry);
  const EncodedBlob registry_blob =
      EncodeBlob(registry_bytes.data(), registry_bytes.size(), Codec::kZstd, options_.zstd_level);

  std::lock_guard<std::mutex> lock(mutex_);
  const int64_t now = WallUtime();
  s = WriteTransaction([&]() -> Status {
    sqlite::Statement exists = db_->Prepare(
        "SELECT id FROM derived WHERE map_version_id = ? AND profile_hash = ? AND "
        "code_version = ?");
    exists.Bind(1, row.id).Bind(2, derived.profile_hash).Bind(3, derived.code_version);
    if (exists.Step()) return Status::Ok();  // the first derivation stays
    const Status r = InsertDerived(row, derived, tiles, registry_blob, now);
    if (!r.ok()) return r;
    return Audit(ctx, ctx.utime != 0 ? ctx.utime : now, "derive", row.site, row.name, row.version,
                 "profile " + derived.profile_name + " (" + derived.profile_hash + "), code " +
                     derived.code_version);
  });
  if (!s.ok()) return WriteError(s, "caching layers of profile '" + derived.profile_name + "'");
  return Status::Ok();
}

}  // namespace cairn::mapstore
