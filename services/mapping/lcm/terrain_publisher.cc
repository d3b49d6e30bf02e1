#include "services/mapping/lcm/terrain_publisher.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "common/crc32.h"
#include "common/layers.h"
#include "services/runtime/tiler.h"

namespace cairn::mapping {
namespace {

int FloorDiv(int a, int b) { return a >= 0 ? a / b : -((-a + b - 1) / b); }

bool IsBaseLayer(const std::string& layer) {
  for (const auto& b : TerrainMap::BaseLayers()) {
    if (b == layer) return true;
  }
  return false;
}

}  // namespace

TerrainPublisher::TerrainPublisher(std::string robot, std::string map_name, int extent_tiles,
                                   int64_t version_base)
    : robot_(std::move(robot)),
      map_name_(std::move(map_name)),
      extent_tiles_(std::max(1, extent_tiles)),
      version_base_(version_base) {}

std::optional<cairn::lcmt_grid_manifest> TerrainPublisher::Manifest(
    const std::string& layer) const {
  auto it = layers_.find(layer);
  if (it == layers_.end()) return std::nullopt;
  return MakeManifest(layer, it->second);
}

TerrainPublisher::Batch TerrainPublisher::Reset(int64_t utime) {
  // Layer versions keep growing (receivers ignore older manifests); tiles and geometry go.
  Batch batch;
  for (auto& [name, state] : layers_) {
    state.tiles.clear();
    ++state.version;
    state.utime = utime;
    batch.manifests.push_back(MakeManifest(name, state));
  }
  geometry_ = common::GridGeometry();
  return batch;
}

int64_t TerrainPublisher::version(const std::string& layer) const {
  auto it = layers_.find(layer);
  return it == layers_.end() ? 0 : it->second.version;
}

common::GridGeometry TerrainPublisher::Extent(const TerrainMap& map) const {
  // The map's bounds rounded out to blocks of extent_tiles tiles, joined with what was
  // published before (the published grid never shrinks).
  const common::GridGeometry b = map.Bounds();
  const int T = map.params().tile_size_cells;
  const double tile_m = T * map.params().resolution_m;
  int tx0 = static_cast<int>(std::lround(b.origin.x_m / tile_m));
  int ty0 = static_cast<int>(std::lround(b.origin.y_m / tile_m));
  int tx1 = tx0 + b.size_x / T, ty1 = ty0 + b.size_y / T;  // exclusive
  tx0 = FloorDiv(tx0, extent_tiles_) * extent_tiles_;
  ty0 = FloorDiv(ty0, extent_tiles_) * extent_tiles_;
  tx1 = (FloorDiv(tx1 - 1, extent_tiles_) + 1) * extent_tiles_;
  ty1 = (FloorDiv(ty1 - 1, extent_tiles_) + 1) * extent_tiles_;
  if (geometry_.size_x > 0 && tile_size_ == T) {
    tx0 = std::min(tx0, origin_tx_);
    ty0 = std::min(ty0, origin_ty_);
    tx1 = std::max(tx1, origin_tx_ + geometry_.size_x / T);
    ty1 = std::max(ty1, origin_ty_ + geometry_.size_y / T);
  }
  common::GridGeometry g;
  g.resolution_m = map.params().resolution_m;
  g.size_x = (tx1 - tx0) * T;
  g.size_y = (ty1 - ty0) * T;
  g.origin = {tx0 * tile_m, ty0 * tile_m, 0.0};
  return g;
}

TerrainPublisher::Batch TerrainPublisher::Update(const TerrainMap& map,
                                                 const std::vector<std::string>& layers,
                                                 int64_t utime, bool force_all) {
  Batch batch;
  if (map.empty()) return batch;
  const int T = map.params().tile_size_cells;
  const common::GridGeometry extent = Extent(map);
  if (extent != geometry_ || T != tile_size_) {
    geometry_ = extent;
    tile_size_ = T;
    const double tile_m = T * map.params().resolution_m;
    origin_tx_ = static_cast<int>(std::lround(extent.origin.x_m / tile_m));
    origin_ty_ = static_cast<int>(std::lround(extent.origin.y_m / tile_m));
    for (auto& [name, state] : layers_) state.tiles.clear();
    batch.geometry_changed = true;
    force_all = true;
  }
  const auto map_tiles = map.Tiles();
  const std::vector<std::string> derived = map.DerivedLayers();
  const size_t n = static_cast<size_t>(T) * T;
  for (const std::string& layer : layers) {
    LayerState& state = layers_[layer];
    const bool reset = state.version == 0;
    if (reset) state.version = version_base_;
    bool changed = false;
    std::map<std::pair<int, int>, TileState> next;
    const bool base = IsBaseLayer(layer);
    for (const auto& [tx, ty] : map_tiles) {
      const common::GridMap* tile_layers = map.TileLayers(tx, ty);
      const int64_t source = base ? map.TileBaseVersion(tx, ty) : map.TileDerivedVersion(tx, ty);
      const std::pair<int, int> key{tx - origin_tx_, ty - origin_ty_};
      auto old = state.tiles.find(key);
      if (!force_all && old != state.tiles.end() && old->second.source_version == source) {
        next.emplace(key, std::move(old->second));  // untouched since last read
        continue;
      }
      if (tile_layers == nullptr || !tile_layers->HasLayer(layer)) continue;
      const float* values = tile_layers->at(layer).data();
      bool any_known = false;
      for (size_t i = 0; i < n && !any_known; ++i) any_known = !std::isnan(values[i]);
      if (!any_known) {
        changed |= old != state.tiles.end();  // became all unknown: leaves the manifest
        continue;
      }
      TileState tile;
      tile.source_version = source;
      tile.data.assign(values, values + n);
      tile.checksum = common::Crc32(tile.data.data(), n * sizeof(float));
      if (force_all || old == state.tiles.end() || old->second.checksum != tile.checksum) {
        tile.tile_version = -1;  // set below, once the layer version is known
        changed = true;
      } else {
        tile.tile_version = old->second.tile_version;
      }
      next.emplace(key, std::move(tile));
    }
    // Tiles that vanished (never happens for a growing map, but a reset clears them).
    for (const auto& [key, tile] : state.tiles) changed |= next.count(key) == 0;
    const bool was_present = state.present;
    state.present = base || std::find(derived.begin(), derived.end(), layer) != derived.end();
    if (changed || reset || force_all || was_present != state.present) {
      ++state.version;
      state.utime = utime;
      for (auto& [key, tile] : next) {
        if (tile.tile_version == -1) {
          tile.tile_version = state.version;
          batch.tiles.push_back(MakeTile(layer, state, key, tile));
        }
      }
      state.tiles = std::move(next);
      batch.manifests.push_back(MakeManifest(layer, state));
    } else {
      state.tiles = std::move(next);
    }
  }
  return batch;
}

cairn::lcmt_grid_tile TerrainPublisher::MakeTile(const std::string& layer, const LayerState& state,
                                                 const std::pair<int, int>& key,
                                                 const TileState& tile) const {
  cairn::lcmt_grid_tile m{};
  m.utime = state.utime;
  m.robot = robot_;
  m.map_name = map_name_;
  m.layer = layer;
  m.layer_version = state.version;
  m.tile_version = tile.tile_version;
  m.resolution_m = geometry_.resolution_m;
  m.origin_x_m = geometry_.origin.x_m;
  m.origin_y_m = geometry_.origin.y_m;
  m.origin_yaw_rad = geometry_.origin.yaw_rad;
  m.layer_size_x = geometry_.size_x;
  m.layer_size_y = geometry_.size_y;
  m.tile_size = tile_size_;
  m.tile_ix = key.first;
  m.tile_iy = key.second;
  m.cells_x = tile_size_;
  m.cells_y = tile_size_;
  m.checksum = tile.checksum;
  m.num_cells = static_cast<int32_t>(tile.data.size());
  m.data = tile.data;
  return m;
}

cairn::lcmt_grid_manifest TerrainPublisher::MakeManifest(const std::string& layer,
                                                         const LayerState& state) const {
  cairn::lcmt_grid_manifest m{};
  m.utime = state.utime;
  m.robot = robot_;
  m.map_name = map_name_;
  m.layer = layer;
  m.layer_version = state.version;
  m.resolution_m = geometry_.resolution_m;
  m.origin_x_m = geometry_.origin.x_m;
  m.origin_y_m = geometry_.origin.y_m;
  m.origin_yaw_rad = geometry_.origin.yaw_rad;
  m.layer_size_x = geometry_.size_x;
  m.layer_size_y = geometry_.size_y;
  m.tile_size = tile_size_;
  for (const auto& [key, tile] : state.tiles) {
    m.tile_ix.push_back(key.first);
    m.tile_iy.push_back(key.second);
    m.tile_version.push_back(tile.tile_version);
    m.checksum.push_back(tile.checksum);
  }
  m.num_tiles = static_cast<int32_t>(m.tile_ix.size());
  return m;
}

TerrainPublisher::Batch TerrainPublisher::Resend(
    const cairn::lcmt_tile_resend_request& request) const {
  Batch batch;
  auto it = layers_.find(request.layer);
  if (it == layers_.end()) return batch;
  const LayerState& state = it->second;
  if (request.num_tiles <= 0) {
    for (const auto& [key, tile] : state.tiles)
      batch.tiles.push_back(MakeTile(request.layer, state, key, tile));
  } else {
    const size_t n = std::min<size_t>(static_cast<size_t>(request.num_tiles),
                                      std::min(request.tile_ix.size(), request.tile_iy.size()));
    for (size_t i = 0; i < n; ++i) {
      auto t = state.tiles.find({request.tile_ix[i], request.tile_iy[i]});
      if (t != state.tiles.end())
        batch.tiles.push_back(MakeTile(request.layer, state, t->first, t->second));
    }
  }
  batch.manifests.push_back(MakeManifest(request.layer, state));
  return batch;
}

}  // namespace cairn::mapping
