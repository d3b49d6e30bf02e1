#include "services/mapping/lcm/terrain_publisher.h"

#include <algorithm>
#include <cmath>

#include "common/layers.h"

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
  if (tiler_ == nullptr) return std::nullopt;
  std::optional<cairn::lcmt_grid_manifest> m = tiler_->Manifest(layer);
  if (m) WithPublishedGrid(&*m);
  return m;
}

void TerrainPublisher::WithPublishedGrid(cairn::lcmt_grid_manifest* m) const {
  if (geometry_.size_x > 0) return;
  // Between a Reset and the next Update the layers have no grid (the map is empty).
  m->resolution_m = geometry_.resolution_m;
  m->origin_x_m = geometry_.origin.x_m;
  m->origin_y_m = geometry_.origin.y_m;
  m->origin_yaw_rad = geometry_.origin.yaw_rad;
  m->layer_size_x = geometry_.size_x;
  m->layer_size_y = geometry_.size_y;
}

TerrainPublisher::Batch TerrainPublisher::Reset(int64_t utime) {
  // Layer versions keep growing (receivers ignore older manifests); tiles and geometry go.
  Batch batch;
  if (tiler_ != nullptr) batch.manifests = tiler_->ClearAll(utime);
  geometry_ = common::GridGeometry();
  return batch;
}

int64_t TerrainPublisher::version(const std::string& layer) const {
  return tiler_ == nullptr ? 0 : tiler_->version(layer);
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
  if (tiler_ == nullptr || T != tile_size_) {
    tiler_ = std::make_unique<runtime::LayerTiler>(robot_, map_name_, T, version_base_);
    geometry_ = common::GridGeometry();
  }
  const common::GridGeometry extent = Extent(map);
  if (extent != geometry_ || T != tile_size_) {
    geometry_ = extent;
    tile_size_ = T;
    const double tile_m = T * map.params().resolution_m;
    origin_tx_ = static_cast<int>(std::lround(extent.origin.x_m / tile_m));
    origin_ty_ = static_cast<int>(std::lround(extent.origin.y_m / tile_m));
    batch.geometry_changed = true;
    force_all = true;  // receivers reset a layer whose grid changed: everything again
  }
  const auto map_tiles = map.Tiles();
  const std::vector<std::string> derived = map.DerivedLayers();
  std::vector<runtime::LayerTiler::SourceTile> sources;
  sources.reserve(map_tiles.size());
  for (const std::string& layer : layers) {
    // The map's tiles of this layer, with the change counter of their base or derived layers.
    const bool base = IsBaseLayer(layer);
    sources.clear();
    for (const auto& [tx, ty] : map_tiles) {
      const common::GridMap* tile_layers = map.TileLayers(tx, ty);
      runtime::LayerTiler::SourceTile source;
      source.tile_ix = tx - origin_tx_;
      source.tile_iy = ty - origin_ty_;
      source.source_version = base ? map.TileBaseVersion(tx, ty) : map.TileDerivedVersion(tx, ty);
      if (tile_layers != nullptr && tile_layers->HasLayer(layer)) {
        source.cells = tile_layers->at(layer).data();
      }
      sources.push_back(source);
    }
    // A layer the map stopped holding (a removed profile) or holds again gets a new version
    // even without tiles, so receivers hear of it.
    const bool present = base || std::find(derived.begin(), derived.end(), layer) != derived.end();
    auto was = present_.find(layer);
    const bool toggled = was != present_.end() && was->second != present;
    present_[layer] = present;
    auto out = tiler_->UpdateTiles(layer, geometry_, sources, utime, force_all || toggled);
    for (auto& t : out.tiles) batch.tiles.push_back(std::move(t));
    if (out.changed) batch.manifests.push_back(std::move(out.manifest));
  }
  return batch;
}

TerrainPublisher::Batch TerrainPublisher::Resend(
    const cairn::lcmt_tile_resend_request& request) const {
  Batch batch;
  if (tiler_ == nullptr || !tiler_->Has(request.layer)) return batch;
  auto out = tiler_->Resend(request);
  batch.tiles = std::move(out.tiles);
  WithPublishedGrid(&out.manifest);
  batch.manifests.push_back(std::move(out.manifest));
  return batch;
}

}  // namespace cairn::mapping
