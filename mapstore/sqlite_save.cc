// SqliteMapStore::SaveMap in stages: the tiles are compressed and checksummed (or a caller's
// compressed tiles adopted) before the write lock; then one transaction inserts the version, its
// layers and tiles, its obstacles and its OctoMap, and the audit line.

#include <cmath>
#include <map>
#include <optional>

#include "common/crc32.h"
#include "mapstore/sqlite_map_store.h"
#include "mapstore/sqlite_store_rows.h"
#include "mapstore/store_util.h"

namespace cairn::mapstore {

using common::Result;
using common::Status;

namespace {

// For every tile of every layer (layer-major, as `specs` orders tiles), the caller's compressed
// blob of that tile when it has one for a layer of the store's tile size; else null.
std::vector<const StoredTile*> CallerBlobs(const MapSnapshot& snapshot,
                                           const std::vector<std::string>& layer_names,
                                           const std::vector<TileSpec>& specs, int tile_size) {
  std::vector<const StoredTile*> out(layer_names.size() * specs.size(), nullptr);
  std::map<std::string, const StoredLayer*> by_name;
  for (const StoredLayer& l : snapshot.encoded_layers) {
    if (l.tile_size == tile_size) by_name[l.name] = &l;
  }
  const int tiles_x = (snapshot.base.geometry().size_x + tile_size - 1) / tile_size;
  for (size_t l = 0; l < layer_names.size(); ++l) {
    auto it = by_name.find(layer_names[l]);
    if (it == by_name.end()) continue;
    for (const StoredTile& t : it->second->tiles) {
      const size_t k = static_cast<size_t>(t.tile_iy) * tiles_x + t.tile_ix;
      if (t.tile_ix >= 0 && t.tile_iy >= 0 && t.tile_ix < tiles_x && k < specs.size()) {
        out[l * specs.size() + k] = &t;
      }
    }
  }
  return out;
}

// A caller's blob the store may keep as its own: a zstd codec and the tile's size.
bool Adoptable(const StoredTile* e, const TileSpec& spec) {
  return e != nullptr &&
         (e->codec == static_cast<int>(Codec::kZstdShuffle4) ||
          e->codec == static_cast<int>(Codec::kZstdBytes)) &&
         e->cells_x == spec.cells_x && e->cells_y == spec.cells_y;
}

}  // namespace

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

SqliteMapStore::EncodedTiles SqliteMapStore::EncodeLayers(
    const common::GridMap& layers, int tile_size, const std::vector<const StoredTile*>& caller,
    bool caller_checked) const {
  EncodedTiles out;
  out.layer_names = layers.layer_names();
  out.specs = TilesOf(layers.geometry(), tile_size);
  const size_t n = out.layer_names.size() * out.specs.size();  // layer-major
  std::vector<EncodedBlob> blobs(n);
  std::vector<char> present(n, 0);
  ParallelFor(n, options_.compression_threads, [&](size_t i) {
    const TileSpec& spec = out.specs[i % out.specs.size()];
    const size_t bytes = static_cast<size_t>(spec.cells_x) * spec.cells_y * sizeof(float);
    const StoredTile* e = caller.empty() ? nullptr : caller[i];
    const bool adoptable = Adoptable(e, spec);
    auto adopt = [&] {
      auto blob = AdoptEncodedBlob(static_cast<Codec>(e->codec), e->data,
                                   static_cast<int64_t>(bytes), e->raw_crc32);
      if (!blob.ok()) return false;
      blobs[i] = std::move(blob).value();
      present[i] = 1;
      return true;
    };
    // A checked caller's tile stands for the cells (an all-unknown tile is stored too).
    if (adoptable && caller_checked && adopt()) return;
    const std::vector<float> cells =
        ExtractTile(layers.at(out.layer_names[i / out.specs.size()]), spec);
    if (AllUnknown(cells)) return;
    if (adoptable && e->raw_crc32 == common::Crc32(cells.data(), bytes) && adopt()) return;
    blobs[i] = EncodeBlob(cells.data(), bytes, FloatCodec(cells.data(), cells.size()),
                          options_.zstd_level);
    present[i] = 1;
  });
  for (size_t i = 0; i < n; ++i) {
    if (!present[i]) continue;
    out.blobs.push_back(std::move(blobs[i]));
    out.place.emplace_back(i / out.specs.size(), i % out.specs.size());
  }
  return out;
}

SqliteMapStore::EncodedTiles SqliteMapStore::EncodeSnapshot(const MapSnapshot& snapshot) const {
  const int tile_size = options_.tile_size_cells;
  const std::vector<std::string> names = snapshot.base.layer_names();
  EncodedTiles out = EncodeLayers(
      snapshot.base, tile_size,
      CallerBlobs(snapshot, names, TilesOf(snapshot.base.geometry(), tile_size), tile_size),
      snapshot.encoded_layers_checked);
  if (snapshot.octomap) {
    out.octomap = EncodeBlob(snapshot.octomap->bytes.data(), snapshot.octomap->bytes.size(),
                             Codec::kZstd, options_.zstd_level);
  }
  return out;
}

Result<std::pair<int64_t, int64_t>> SqliteMapStore::InsertVersion(const MapSnapshot& snapshot,
                                                                  int64_t now) {
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
  const int64_t version = map_find.Int(1) + 1;
  const Provenance& p = snapshot.provenance;
  const common::GridGeometry& g = snapshot.base.geometry();
  sqlite::Statement v = db_->Prepare(
      "INSERT INTO map_versions(map_id, version, source_robot, source_profile, "
      "source_profile_hash, code_version, parameters, created_utime, resolution_m, size_x, "
      "size_y, origin_x_m, origin_y_m, origin_yaw_rad, tile_size) "
      "VALUES(?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)");
  v.Bind(1, map_id).Bind(2, version).Bind(3, p.source_robot).Bind(4, p.source_profile);
  v.Bind(5, p.source_profile_hash).Bind(6, p.code_version).Bind(7, p.parameters);
  v.Bind(8, p.created_utime != 0 ? p.created_utime : now).Bind(9, g.resolution_m);
  v.Bind(10, g.size_x).Bind(11, g.size_y).Bind(12, g.origin.x_m).Bind(13, g.origin.y_m);
  v.Bind(14, g.origin.yaw_rad).Bind(15, options_.tile_size_cells);
  if (!(st = v.Run()).ok()) return st;
  return std::make_pair(version, db_->LastInsertRowId());
}

Status SqliteMapStore::InsertLayerTiles(int64_t version_id, const EncodedTiles& tiles) {
  std::vector<int64_t> layer_ids;
  sqlite::Statement layer_insert =
      db_->Prepare("INSERT INTO layers(map_version_id, name) VALUES(?, ?)");
  Status st;
  for (const std::string& name : tiles.layer_names) {
    layer_insert.Reset();
    layer_insert.Bind(1, version_id).Bind(2, name);
    if (!(st = layer_insert.Run()).ok()) return st;
    layer_ids.push_back(db_->LastInsertRowId());
  }
  std::vector<int64_t> blob_ids;
  if (!(st = WriteBlobs(tiles.blobs, &blob_ids)).ok()) return st;
  sqlite::Statement tile_insert = db_->Prepare(
      "INSERT INTO layer_tiles(layer_id, tile_ix, tile_iy, blob_id) VALUES(?, ?, ?, ?)");
  for (size_t k = 0; k < tiles.blobs.size(); ++k) {
    const auto [layer, spec_index] = tiles.place[k];
    const TileSpec& spec = tiles.specs[spec_index];
    tile_insert.Reset();
    tile_insert.Bind(1, layer_ids[layer]).Bind(2, spec.tile_ix).Bind(3, spec.tile_iy);
    tile_insert.Bind(4, blob_ids[k]);
    if (!(st = tile_insert.Run()).ok()) return st;
  }
  return Status::Ok();
}

Status SqliteMapStore::InsertObstacles(int64_t version_id,
                                       const common::ObstacleRegistry& registry) {
  sqlite::Statement ob = db_->Prepare(
      "INSERT INTO obstacles(map_version_id, obstacle_id, kind, centroid_x_m, centroid_y_m, "
      "slope_rad, height_m, width_m, length_m, depth_m, area_m2, num_cells, outline, parts, "
      "downhill_heading_rad) VALUES(?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)");
  sqlite::Statement vd = db_->Prepare(
      "INSERT INTO obstacle_verdicts(map_version_id, obstacle_id, profile, profile_hash, "
      "crossable, reason) VALUES(?, ?, ?, ?, ?, ?)");
  Status st;
  for (const common::Obstacle& o : registry.obstacles) {
    ob.Reset();
    const std::string outline = SerializePolygon(o.outline_m);
    ob.Bind(1, version_id).Bind(2, o.id).Bind(3, static_cast<int64_t>(o.kind));
    ob.Bind(4, o.centroid_m.x()).Bind(5, o.centroid_m.y()).Bind(6, o.slope_rad);
    ob.Bind(7, o.height_m).Bind(8, o.width_m).Bind(9, o.length_m).Bind(10, o.depth_m);
    ob.Bind(11, o.area_m2).Bind(12, o.num_cells).BindBlob(13, outline.data(), outline.size());
    const std::string parts = o.parts.empty() ? std::string() : SerializeParts(o.parts);
    if (o.parts.empty()) {
      ob.BindNull(14);
    } else {
      ob.BindBlob(14, parts.data(), parts.size());
    }
    if (std::isfinite(o.downhill_heading_rad)) {
      ob.Bind(15, o.downhill_heading_rad);
    } else {
      ob.BindNull(15);
    }
    if (!(st = ob.Run()).ok()) return st;
    for (const common::ObstacleVerdict& verdict : o.verdicts) {
      vd.Reset();
      vd.Bind(1, version_id).Bind(2, o.id).Bind(3, verdict.profile).Bind(4, verdict.profile_hash);
      vd.Bind(5, verdict.crossable ? 1 : 0).Bind(6, verdict.reason);
      if (!(st = vd.Run()).ok()) return st;
    }
  }
  return Status::Ok();
}

Status SqliteMapStore::InsertOctomap(int64_t version_id, const EncodedBlob& blob,
                                     const OctomapData& octomap) {
  std::vector<int64_t> id;
  Status st = WriteBlobs({blob}, &id);
  if (!st.ok()) return st;
  sqlite::Statement oc = db_->Prepare(
      "INSERT INTO octomaps(map_version_id, binary, resolution_m, blob_id) VALUES(?, ?, ?, ?)");
  oc.Bind(1, version_id).Bind(2, octomap.binary ? 1 : 0);
  oc.Bind(3, octomap.resolution_m).Bind(4, id[0]);
  return oc.Run();
}

Result<MapInfo> SqliteMapStore::SaveMap(const MapSnapshot& snapshot, const WriteContext& ctx) {
  Status s = ValidateSnapshot(snapshot);
  if (!s.ok()) return s;
  const std::string label = "saving map '" + snapshot.site + "/" + snapshot.name + "'";
  // Compress and checksum every tile before taking the write lock.
  std::optional<EncodedTiles> tiles;
  try {
    tiles = EncodeSnapshot(snapshot);
  } catch (const std::exception& e) {
    return common::InternalError(label + ": " + e.what());
  }

  std::lock_guard<std::mutex> lock(mutex_);
  const int64_t now = WallUtime();
  int64_t version = 0;
  s = WriteTransaction([&]() -> Status {
    auto inserted = InsertVersion(snapshot, now);
    if (!inserted.ok()) return inserted.status();
    version = inserted->first;
    const int64_t version_id = inserted->second;
    Status st = InsertLayerTiles(version_id, *tiles);
    if (st.ok()) st = InsertObstacles(version_id, snapshot.obstacles);
    if (st.ok() && tiles->octomap)
      st = InsertOctomap(version_id, *tiles->octomap, *snapshot.octomap);
    if (!st.ok()) return st;
    return Audit(ctx, ctx.utime != 0 ? ctx.utime : now, "save", snapshot.site, snapshot.name,
                 version,
                 std::to_string(tiles->layer_names.size()) + " layers, " +
                     std::to_string(tiles->blobs.size()) + " tiles, " +
                     std::to_string(snapshot.obstacles.obstacles.size()) + " obstacles" +
                     (snapshot.octomap ? ", octomap" : ""));
  });
  if (!s.ok()) return WriteError(s, label);
  auto row = Resolve({snapshot.site, snapshot.name, version});
  if (!row.ok()) return row.status();
  return InfoOf(*row);
}

}  // namespace cairn::mapstore
