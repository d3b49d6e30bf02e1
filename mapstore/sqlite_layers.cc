// SqliteMapStore's reads of a version's content: layers (decoded, or as stored tiles), obstacles,
// the OctoMap, and the raw blobs of a version.

#include <algorithm>
#include <map>

#include "mapstore/sqlite_map_store.h"
#include "mapstore/sqlite_store_rows.h"
#include "mapstore/store_util.h"

namespace cairn::mapstore {

using common::Result;
using common::Status;

SqliteMapStore::TileRow SqliteMapStore::ReadTileRow(const sqlite::Statement& st) {
  TileRow t;
  t.tile_ix = static_cast<int>(st.Int(0));
  t.tile_iy = static_cast<int>(st.Int(1));
  t.codec = static_cast<Codec>(st.Int(2));
  t.raw_size = st.Int(3);
  t.raw_crc32 = static_cast<uint32_t>(st.Int(4));
  t.data = st.Blob(5);
  if (!st.IsNull(6)) t.stored_crc32 = static_cast<uint32_t>(st.Int(6));
  return t;
}

Status SqliteMapStore::ReadTiles(sqlite::Statement* stmt, const std::string& label, int tile_size,
                                 const common::GridGeometry& full, const CellBox& box,
                                 common::Layer* layer) const {
  std::vector<TileRow> raw;
  while (stmt->Step()) raw.push_back(ReadTileRow(*stmt));
  if (!stmt->status().ok()) {
    return Located(Status(stmt->status().code(), label + ": " + stmt->status().message()));
  }
  const int tiles_x = (full.size_x + tile_size - 1) / tile_size;
  const int tiles_y = (full.size_y + tile_size - 1) / tile_size;
  std::vector<Status> errors(raw.size());
  ParallelFor(raw.size(), options_.compression_threads, [&](size_t i) {
    const TileRow& t = raw[i];
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
    if (!e.ok()) return Located(e);
  }
  return Status::Ok();
}

Result<std::map<std::string, int64_t>> SqliteMapStore::LayerIds(
    const MapRef& ref, const VersionRow& row, std::vector<std::string>* wanted) const {
  std::map<std::string, int64_t> layer_ids;
  sqlite::Statement st = db_->Prepare("SELECT name, id FROM layers WHERE map_version_id = ?");
  st.Bind(1, row.id);
  while (st.Step()) layer_ids[st.Text(0)] = st.Int(1);
  if (!st.status().ok()) return Located(st.status());
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
  if (!row.ok()) return Located(row.status());
  std::vector<std::string> wanted = query.layers;
  auto ids = LayerIds(ref, *row, &wanted);
  if (!ids.ok()) return Located(ids.status());
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
    if (!read.ok()) return Located(read);
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
    TileRow row = ReadTileRow(*stmt);
    StoredTile t;
    t.tile_ix = row.tile_ix;
    t.tile_iy = row.tile_iy;
    t.codec = static_cast<int>(row.codec);
    const int64_t raw_size = row.raw_size;
    t.raw_crc32 = row.raw_crc32;
    t.data = std::move(row.data);
    t.stored_crc32 = row.stored_crc32;
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
  if (stmt->status().ok()) return Status::Ok();
  return Located(Status(stmt->status().code(), label + ": " + stmt->status().message()));
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
    if (!e.ok()) return Located(e);
  }
  return Status::Ok();
}

Result<std::vector<StoredLayer>> SqliteMapStore::LoadStoredTiles(
    const MapRef& ref, const std::vector<std::string>& layers, int /*tile_size*/) const {
  std::lock_guard<std::mutex> lock(mutex_);
  auto row = Resolve(ref);
  if (!row.ok()) return Located(row.status());
  std::vector<std::string> wanted = layers;
  auto ids = LayerIds(ref, *row, &wanted);
  if (!ids.ok()) return Located(ids.status());
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
    if (!read.ok()) return Located(read);
    out.push_back(std::move(layer));
  }
  Status checked = CheckStoredLayers(out, label);
  if (!checked.ok()) return Located(checked);
  return out;
}

Result<common::ObstacleRegistry> SqliteMapStore::LoadObstacles(const MapRef& ref) const {
  std::lock_guard<std::mutex> lock(mutex_);
  auto row = Resolve(ref);
  if (!row.ok()) return Located(row.status());
  common::ObstacleRegistry registry;
  registry.map_version = row->version;
  sqlite::Statement st = db_->Prepare(
      "SELECT obstacle_id, kind, centroid_x_m, centroid_y_m, slope_rad, height_m, width_m, "
      "length_m, depth_m, area_m2, num_cells, outline, parts, downhill_heading_rad FROM obstacles "
      "WHERE map_version_id = ? "
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
    if (!st.IsNull(13)) o.downhill_heading_rad = st.Double(13);
    if (!st.IsNull(12)) {
      auto parts = ParseParts(st.Blob(12));
      if (!parts.ok()) {
        return common::CorruptError("obstacle " + std::to_string(o.id) + ": " +
                                    parts.status().message());
      }
      o.parts = std::move(parts).value();
    }
    if (o.kind < common::ObstacleKind::kRamp || o.kind > common::ObstacleKind::kTerrace ||
        o.parts.empty() != (o.kind != common::ObstacleKind::kTerrace)) {
      return common::CorruptError("obstacle " + std::to_string(o.id) + " of kind " +
                                  std::to_string(static_cast<int>(o.kind)) + " has " +
                                  std::to_string(o.parts.size()) + " parts");
    }
    index[o.id] = registry.obstacles.size();
    registry.obstacles.push_back(std::move(o));
  }
  if (!st.status().ok()) return Located(st.status());
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
  if (!vd.status().ok()) return Located(vd.status());
  return registry;
}

Result<OctomapData> SqliteMapStore::LoadOctomap(const MapRef& ref) const {
  std::lock_guard<std::mutex> lock(mutex_);
  auto row = Resolve(ref);
  if (!row.ok()) return Located(row.status());
  sqlite::Statement st = db_->Prepare(
      "SELECT o.binary, o.resolution_m, b.codec, b.raw_size, b.raw_crc32, b.data FROM octomaps o "
      "JOIN blobs b ON b.id = o.blob_id WHERE o.map_version_id = ?");
  st.Bind(1, row->id);
  if (!st.Step()) {
    if (!st.status().ok()) return Located(st.status());
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

Result<std::map<std::string, std::string>> SqliteMapStore::BaseBlobBytes(const MapRef& ref) const {
  std::lock_guard<std::mutex> lock(mutex_);
  auto row = Resolve(ref);
  if (!row.ok()) return Located(row.status());
  sqlite::Statement st = db_->Prepare(
      "SELECT l.name, t.tile_ix, t.tile_iy, b.data FROM layers l JOIN layer_tiles t ON "
      "t.layer_id = l.id JOIN blobs b ON b.id = t.blob_id WHERE l.map_version_id = ?");
  st.Bind(1, row->id);
  std::map<std::string, std::string> out;
  while (st.Step()) {
    out[st.Text(0) + "/" + std::to_string(st.Int(1)) + "/" + std::to_string(st.Int(2))] =
        st.Blob(3);
  }
  if (!st.status().ok()) return Located(st.status());
  return out;
}

Result<int64_t> SqliteMapStore::BaseBytes(const MapRef& ref) const {
  std::lock_guard<std::mutex> lock(mutex_);
  auto row = Resolve(ref);
  if (!row.ok()) return Located(row.status());
  sqlite::Statement st = db_->Prepare(
      "SELECT COALESCE(SUM(length(b.data)), 0) FROM layers l JOIN layer_tiles t ON "
      "t.layer_id = l.id JOIN blobs b ON b.id = t.blob_id WHERE l.map_version_id = ?");
  st.Bind(1, row->id);
  if (!st.Step()) return Located(st.status());
  return st.Int(0);
}

}  // namespace cairn::mapstore
