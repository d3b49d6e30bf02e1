#include "services/runtime/tiler.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>

#include "common/crc32.h"

namespace cairn::runtime {
namespace {

int8_t ToOccupancy(float v) {
  if (std::isnan(v)) return -1;
  return static_cast<int8_t>(std::clamp(std::lround(v), 0L, 100L));
}

template <typename Msg>
void FillGeometry(const common::GridGeometry& g, int tile_size, Msg* m) {
  m->resolution_m = g.resolution_m;
  m->origin_x_m = g.origin.x_m;
  m->origin_y_m = g.origin.y_m;
  m->origin_yaw_rad = g.origin.yaw_rad;
  m->layer_size_x = g.size_x;
  m->layer_size_y = g.size_y;
  m->tile_size = tile_size;
}

}  // namespace

LayerTiler::LayerTiler(std::string robot, std::string map_name, int tile_size_cells,
                       int64_t version_base)
    : robot_(std::move(robot)),
      map_name_(std::move(map_name)),
      tile_size_(tile_size_cells),
      version_base_(version_base) {
  if (version_base_ < 0) throw std::invalid_argument("the version base must not be negative");
  if (tile_size_ <= 0 ||
      static_cast<size_t>(tile_size_) * tile_size_ * 4 + 512 > kMaxMessageBytes) {
    throw std::invalid_argument("tile size " + std::to_string(tile_size_) +
                                " cells does not fit a 256 KB message");
  }
}

int64_t LayerTiler::StartVersionBase() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

int64_t LayerTiler::version(const std::string& layer) const {
  auto it = layers_.find(layer);
  return it == layers_.end() ? 0 : it->second.version;
}

LayerTiler::Batch LayerTiler::Update(const common::GridMap& map, const std::string& layer,
                                     TileEncoding encoding, int64_t utime, bool force_all) {
  const common::Layer& values = map.at(layer);
  LayerState& state = layers_[layer];
  const bool reset =
      state.version == 0 || state.geometry != map.geometry() || state.encoding != encoding;
  if (reset) {
    state.tiles.clear();
    state.geometry = map.geometry();
    state.encoding = encoding;
  }
  const int64_t next_version = (state.version == 0 ? version_base_ : state.version) + 1;
  const int nx = (map.size_x() + tile_size_ - 1) / tile_size_;
  const int ny = (map.size_y() + tile_size_ - 1) / tile_size_;
  std::vector<std::pair<int, int>> changed;
  std::map<std::pair<int, int>, TileState> next_tiles;
  for (int ty = 0; ty < ny; ++ty) {
    for (int tx = 0; tx < nx; ++tx) {
      TileState tile;
      tile.cells_x = std::min(tile_size_, map.size_x() - tx * tile_size_);
      tile.cells_y = std::min(tile_size_, map.size_y() - ty * tile_size_);
      const int n = tile.cells_x * tile.cells_y;
      bool any_known = false;
      if (encoding == TileEncoding::kFloat) {
        tile.data.resize(n);
        for (int y = 0; y < tile.cells_y; ++y) {
          const float* col = &values(tx * tile_size_, ty * tile_size_ + y);
          std::memcpy(&tile.data[y * tile.cells_x], col, sizeof(float) * tile.cells_x);
          for (int x = 0; x < tile.cells_x && !any_known; ++x) any_known = !std::isnan(col[x]);
        }
        tile.checksum = common::Crc32(tile.data.data(), tile.data.size() * sizeof(float));
      } else {
        tile.occupancy.resize(n);
        for (int y = 0; y < tile.cells_y; ++y) {
          for (int x = 0; x < tile.cells_x; ++x) {
            const int8_t v = ToOccupancy(values(tx * tile_size_ + x, ty * tile_size_ + y));
            tile.occupancy[y * tile.cells_x + x] = v;
            any_known |= v >= 0;
          }
        }
        tile.checksum = common::Crc32(tile.occupancy.data(), tile.occupancy.size());
      }
      if (!any_known) continue;  // absent from the manifest means all unknown
      const auto key = std::make_pair(tx, ty);
      auto old = state.tiles.find(key);
      if (force_all || old == state.tiles.end() || old->second.checksum != tile.checksum) {
        tile.tile_version = next_version;
        changed.push_back(key);
      } else {
        tile.tile_version = old->second.tile_version;
      }
      next_tiles.emplace(key, std::move(tile));
    }
  }
  // A tile that became all unknown also counts as a change (it leaves the manifest).
  bool removed = false;
  for (const auto& [key, tile] : state.tiles) removed |= next_tiles.count(key) == 0;
  Batch batch;
  batch.changed = reset || removed || !changed.empty();
  if (batch.changed) state.version = next_version;
  state.tiles = std::move(next_tiles);
  state.utime = utime;
  for (const auto& key : changed) {
    AppendTile(layer, state, key.first, key.second, state.tiles.at(key), &batch);
  }
  batch.manifest = MakeManifest(layer, state);
  return batch;
}

LayerTiler::Batch LayerTiler::Adopt(const std::string& layer, const common::GridGeometry& geometry,
                                    std::vector<EncodedTile> tiles, int64_t utime) {
  const int nx = (geometry.size_x + tile_size_ - 1) / tile_size_;
  const int ny = (geometry.size_y + tile_size_ - 1) / tile_size_;
  std::map<std::pair<int, int>, TileState> next_tiles;
  const int64_t previous = version(layer);
  const int64_t next_version = (previous == 0 ? version_base_ : previous) + 1;
  for (EncodedTile& t : tiles) {
    if (t.tile_ix < 0 || t.tile_iy < 0 || t.tile_ix >= nx || t.tile_iy >= ny ||
        t.cells_x != std::min(tile_size_, geometry.size_x - t.tile_ix * tile_size_) ||
        t.cells_y != std::min(tile_size_, geometry.size_y - t.tile_iy * tile_size_)) {
      throw std::invalid_argument("tile (" + std::to_string(t.tile_ix) + ", " +
                                  std::to_string(t.tile_iy) + ") of layer '" + layer +
                                  "' does not fit its grid");
    }
    TileState tile;
    tile.tile_version = next_version;
    tile.checksum = t.checksum;
    tile.cells_x = t.cells_x;
    tile.cells_y = t.cells_y;
    tile.encoding = t.encoding;
    tile.bytes = std::move(t.bytes);
    tile.data = std::move(t.data);
    if (tile.encoding == cairn::lcmt_grid_tile::ENCODING_FLOAT32 &&
        tile.data.size() != static_cast<size_t>(tile.cells_x) * tile.cells_y) {
      throw std::invalid_argument("float tile (" + std::to_string(t.tile_ix) + ", " +
                                  std::to_string(t.tile_iy) + ") of layer '" + layer +
                                  "' has the wrong number of cells");
    }
    next_tiles[{t.tile_ix, t.tile_iy}] = std::move(tile);
  }
  // Only a batch that fits its grid replaces what was published.
  LayerState& state = layers_[layer];
  state.geometry = geometry;
  state.encoding = TileEncoding::kFloat;
  state.version = next_version;
  state.utime = utime;
  state.tiles = std::move(next_tiles);
  Batch batch;
  batch.changed = true;
  for (const auto& [key, tile] : state.tiles) {
    AppendTile(layer, state, key.first, key.second, tile, &batch);
  }
  batch.manifest = MakeManifest(layer, state);
  return batch;
}

LayerTiler::Batch LayerTiler::UpdateTiles(const std::string& layer,
                                          const common::GridGeometry& geometry,
                                          const std::vector<SourceTile>& tiles, int64_t utime,
                                          bool force_all) {
  LayerState& state = layers_[layer];
  const bool reset =
      state.version == 0 || state.geometry != geometry || state.encoding != TileEncoding::kFloat;
  if (reset) {
    state.tiles.clear();
    state.geometry = geometry;
    state.encoding = TileEncoding::kFloat;
  }
  const int nx = (geometry.size_x + tile_size_ - 1) / tile_size_;
  const int ny = (geometry.size_y + tile_size_ - 1) / tile_size_;
  const size_t n = static_cast<size_t>(tile_size_) * tile_size_;
  bool changed = false;
  std::map<std::pair<int, int>, TileState> next_tiles;
  for (const SourceTile& source : tiles) {
    if (source.tile_ix < 0 || source.tile_iy < 0 || source.tile_ix >= nx || source.tile_iy >= ny) {
      throw std::invalid_argument("tile (" + std::to_string(source.tile_ix) + ", " +
                                  std::to_string(source.tile_iy) + ") of layer '" + layer +
                                  "' lies outside its grid");
    }
    const std::pair<int, int> key{source.tile_ix, source.tile_iy};
    auto old = state.tiles.find(key);
    if (!force_all && old != state.tiles.end() &&
        old->second.source_version == source.source_version) {
      next_tiles.emplace(key, std::move(old->second));  // untouched since last read
      continue;
    }
    if (source.cells == nullptr) continue;
    bool any_known = false;
    for (size_t i = 0; i < n && !any_known; ++i) any_known = !std::isnan(source.cells[i]);
    if (!any_known) {
      changed |= old != state.tiles.end();  // became all unknown: leaves the manifest
      continue;
    }
    TileState tile;
    tile.source_version = source.source_version;
    tile.cells_x = tile.cells_y = tile_size_;
    tile.data.assign(source.cells, source.cells + n);
    tile.checksum = common::Crc32(tile.data.data(), n * sizeof(float));
    if (force_all || old == state.tiles.end() || old->second.checksum != tile.checksum) {
      tile.tile_version = -1;  // set below, once the layer version is known
      changed = true;
    } else {
      tile.tile_version = old->second.tile_version;
    }
    next_tiles.emplace(key, std::move(tile));
  }
  // Tiles that went (not listed any more).
  for (const auto& [key, tile] : state.tiles) changed |= next_tiles.count(key) == 0;
  state.tiles = std::move(next_tiles);
  Batch batch;
  batch.changed = changed || reset || force_all;
  if (batch.changed) {
    state.version = (state.version == 0 ? version_base_ : state.version) + 1;
    state.utime = utime;
    for (auto& [key, tile] : state.tiles) {
      if (tile.tile_version != -1) continue;
      tile.tile_version = state.version;
      AppendTile(layer, state, key.first, key.second, tile, &batch);
    }
  }
  batch.manifest = MakeManifest(layer, state);
  return batch;
}

std::vector<cairn::lcmt_grid_manifest> LayerTiler::ClearAll(int64_t utime) {
  std::vector<cairn::lcmt_grid_manifest> manifests;
  for (auto& [name, state] : layers_) {
    state.tiles.clear();
    state.version = (state.version == 0 ? version_base_ : state.version) + 1;
    state.utime = utime;
    manifests.push_back(MakeManifest(name, state));
  }
  return manifests;
}

std::optional<cairn::lcmt_grid_manifest> LayerTiler::Manifest(const std::string& layer) const {
  auto it = layers_.find(layer);
  if (it == layers_.end()) return std::nullopt;
  return MakeManifest(layer, it->second);
}

namespace {

// The fields every tile message shares: where the tile sits, its versions and checksum.
template <typename TileMsg>
void FillTileHeader(const std::string& robot, const std::string& map_name, const std::string& layer,
                    int64_t utime, int64_t layer_version, const common::GridGeometry& geometry,
                    int tile_size, int ix, int iy, int64_t tile_version, int cells_x, int cells_y,
                    uint32_t checksum, TileMsg* m) {
  m->utime = utime;
  m->robot = robot;
  m->map_name = map_name;
  m->layer = layer;
  m->layer_version = layer_version;
  m->tile_version = tile_version;
  FillGeometry(geometry, tile_size, m);
  m->tile_ix = ix;
  m->tile_iy = iy;
  m->cells_x = cells_x;
  m->cells_y = cells_y;
  m->checksum = checksum;
}

}  // namespace

void LayerTiler::AppendTile(const std::string& layer, const LayerState& state, int ix, int iy,
                            const TileState& tile, Batch* batch) const {
  auto header = [&](auto* m) {
    FillTileHeader(robot_, map_name_, layer, state.utime, state.version, state.geometry, tile_size_,
                   ix, iy, tile.tile_version, tile.cells_x, tile.cells_y, tile.checksum, m);
  };
  if (state.encoding == TileEncoding::kFloat) {
    cairn::lcmt_grid_tile m{};
    header(&m);
    m.encoding = tile.encoding;
    m.num_cells = static_cast<int32_t>(tile.data.size());
    m.data = tile.data;
    m.num_bytes = static_cast<int32_t>(tile.bytes.size());
    m.bytes = tile.bytes;
    batch->tiles.push_back(std::move(m));
  } else {
    cairn::lcmt_occupancy_tile m{};
    header(&m);
    m.num_cells = static_cast<int32_t>(tile.occupancy.size());
    m.data = tile.occupancy;
    batch->occupancy_tiles.push_back(std::move(m));
  }
}

cairn::lcmt_grid_manifest LayerTiler::MakeManifest(const std::string& layer,
                                                   const LayerState& state) const {
  cairn::lcmt_grid_manifest m{};
  m.utime = state.utime;
  m.robot = robot_;
  m.map_name = map_name_;
  m.layer = layer;
  m.layer_version = state.version;
  FillGeometry(state.geometry, tile_size_, &m);
  for (const auto& [key, tile] : state.tiles) {
    m.tile_ix.push_back(key.first);
    m.tile_iy.push_back(key.second);
    m.tile_version.push_back(tile.tile_version);
    m.checksum.push_back(tile.checksum);
  }
  m.num_tiles = static_cast<int32_t>(m.tile_ix.size());
  return m;
}

LayerTiler::Batch LayerTiler::Resend(const cairn::lcmt_tile_resend_request& request) const {
  Batch batch;
  auto it = layers_.find(request.layer);
  if (it == layers_.end()) return batch;
  const LayerState& state = it->second;
  if (request.num_tiles <= 0) {
    for (const auto& [key, tile] : state.tiles) {
      AppendTile(request.layer, state, key.first, key.second, tile, &batch);
    }
  } else {
    const int n =
        std::min<int>(request.num_tiles, std::min(request.tile_ix.size(), request.tile_iy.size()));
    for (int i = 0; i < n; ++i) {
      auto t = state.tiles.find({request.tile_ix[i], request.tile_iy[i]});
      if (t != state.tiles.end()) {
        AppendTile(request.layer, state, t->first.first, t->first.second, t->second, &batch);
      }
    }
  }
  batch.manifest = MakeManifest(request.layer, state);
  batch.changed = !batch.tiles.empty() || !batch.occupancy_tiles.empty();
  return batch;
}

}  // namespace cairn::runtime
