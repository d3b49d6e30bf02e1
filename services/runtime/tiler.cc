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

template <typename Msg>
common::GridGeometry GeometryOf(const Msg& m) {
  common::GridGeometry g;
  g.resolution_m = m.resolution_m;
  g.size_x = m.layer_size_x;
  g.size_y = m.layer_size_y;
  g.origin = {m.origin_x_m, m.origin_y_m, m.origin_yaw_rad};
  return g;
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

void LayerTiler::AppendTile(const std::string& layer, const LayerState& state, int ix, int iy,
                            const TileState& tile, Batch* batch) const {
  if (state.encoding == TileEncoding::kFloat) {
    cairn::lcmt_grid_tile m{};
    m.utime = state.utime;
    m.robot = robot_;
    m.map_name = map_name_;
    m.layer = layer;
    m.layer_version = state.version;
    m.tile_version = tile.tile_version;
    FillGeometry(state.geometry, tile_size_, &m);
    m.tile_ix = ix;
    m.tile_iy = iy;
    m.cells_x = tile.cells_x;
    m.cells_y = tile.cells_y;
    m.checksum = tile.checksum;
    m.encoding = tile.encoding;
    m.num_cells = static_cast<int32_t>(tile.data.size());
    m.data = tile.data;
    m.num_bytes = static_cast<int32_t>(tile.bytes.size());
    m.bytes = tile.bytes;
    batch->tiles.push_back(std::move(m));
  } else {
    cairn::lcmt_occupancy_tile m{};
    m.utime = state.utime;
    m.robot = robot_;
    m.map_name = map_name_;
    m.layer = layer;
    m.layer_version = state.version;
    m.tile_version = tile.tile_version;
    FillGeometry(state.geometry, tile_size_, &m);
    m.tile_ix = ix;
    m.tile_iy = iy;
    m.cells_x = tile.cells_x;
    m.cells_y = tile.cells_y;
    m.checksum = tile.checksum;
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

LayerAssembler::LayerState& LayerAssembler::StateFor(const std::string& layer,
                                                     const common::GridGeometry& geometry,
                                                     int tile_size) {
  LayerState& state = layers_[layer];
  if (state.geometry != geometry || state.tile_size != tile_size) {
    state = LayerState();
    state.geometry = geometry;
    state.tile_size = tile_size;
  }
  return state;
}

void LayerAssembler::Paste(LayerState* state, std::pair<int, int> key, int cells_x, int cells_y,
                           const float* data) {
  common::Layer& cells = state->cells;
  const int64_t x0 = int64_t{key.first} * state->tile_size;
  const int64_t y0 = int64_t{key.second} * state->tile_size;
  if (x0 < 0 || y0 < 0 || x0 >= cells.rows() || y0 >= cells.cols()) return;
  const int nx = static_cast<int>(std::min<int64_t>(cells_x, cells.rows() - x0));
  const int ny = static_cast<int>(std::min<int64_t>(cells_y, cells.cols() - y0));
  // Rows are contiguous (x fastest): one copy per tile row.
  for (int y = 0; y < ny; ++y) {
    std::copy(data + static_cast<size_t>(y) * cells_x, data + static_cast<size_t>(y) * cells_x + nx,
              &cells(x0, y0 + y));
  }
}

template <typename TileMsg>
LayerAssembler::LayerState* LayerAssembler::Admit(const TileMsg& tile, size_t size, uint32_t crc,
                                                  bool* older) {
  *older = false;
  if (static_cast<uint32_t>(tile.checksum) != crc || tile.cells_x < 0 ||
      size != static_cast<size_t>(tile.cells_x) * static_cast<size_t>(tile.cells_y) ||
      tile.tile_size <= 0 || tile.cells_x > tile.tile_size || tile.cells_y > tile.tile_size) {
    ++checksum_errors_;
    return nullptr;
  }
  const common::GridGeometry geometry = GeometryOf(tile);
  if (!(geometry.resolution_m > 0) || geometry.size_x < 0 || geometry.size_y < 0 ||
      int64_t{geometry.size_x} * geometry.size_y > kMaxLayerCells) {
    ++checksum_errors_;
    return nullptr;
  }
  LayerState& state = StateFor(tile.layer, geometry, tile.tile_size);
  state.robot = tile.robot;
  state.map_name = tile.map_name;
  auto held = state.tiles.find({tile.tile_ix, tile.tile_iy});
  *older = held != state.tiles.end() && tile.tile_version < held->second.tile_version;
  if (state.cells.size() == 0 && geometry.size_x > 0 && geometry.size_y > 0) {
    // Not filled: every cell is written by its tile, or made unknown by Layer / TakeLayer.
    state.cells.resize(geometry.size_x, geometry.size_y);
  }
  return &state;
}

template <typename TileMsg>
bool LayerAssembler::OnTileImpl(const TileMsg& tile, const float* data, size_t size, uint32_t crc) {
  bool older = false;
  LayerState* state = Admit(tile, size, crc, &older);
  if (state == nullptr) return false;
  if (older) return true;  // older than what we hold
  const std::pair<int, int> key{tile.tile_ix, tile.tile_iy};
  Held& held = state->tiles[key];
  held.tile_version = tile.tile_version;
  held.checksum = crc;
  held.cells_x = tile.cells_x;
  held.cells_y = tile.cells_y;
  Paste(state, key, tile.cells_x, tile.cells_y, data);
  return true;
}

std::optional<LayerAssembler::TileSlot> LayerAssembler::BeginTile(
    const cairn::lcmt_grid_tile& tile) {
  bool older = false;
  LayerState* state =
      Admit(tile, static_cast<size_t>(std::max(0, tile.cells_x)) * std::max(0, tile.cells_y),
            static_cast<uint32_t>(tile.checksum), &older);
  if (state == nullptr) return std::nullopt;
  TileSlot slot;
  if (older) return slot;
  common::Layer& cells = state->cells;
  const int64_t x0 = int64_t{tile.tile_ix} * state->tile_size;
  const int64_t y0 = int64_t{tile.tile_iy} * state->tile_size;
  if (x0 < 0 || y0 < 0 || x0 >= cells.rows() || y0 >= cells.cols()) {
    EndTile(tile, true);  // outside the layer: held, with nothing to write (as in OnTile)
    return slot;
  }
  slot.first = &cells(x0, y0);
  slot.row_stride = cells.rows();
  slot.cells_x = static_cast<int>(std::min<int64_t>(tile.cells_x, cells.rows() - x0));
  slot.cells_y = static_cast<int>(std::min<int64_t>(tile.cells_y, cells.cols() - y0));
  // The place is being rewritten: no tile is held there until EndTile.
  state->tiles.erase({tile.tile_ix, tile.tile_iy});
  return slot;
}

void LayerAssembler::EndTile(const cairn::lcmt_grid_tile& tile, bool decoded) {
  if (!decoded) return;  // BeginTile released the place: its cells read as unknown
  auto it = layers_.find(tile.layer);
  if (it == layers_.end()) return;
  Held& held = it->second.tiles[{tile.tile_ix, tile.tile_iy}];
  held.tile_version = tile.tile_version;
  held.checksum = static_cast<uint32_t>(tile.checksum);
  held.cells_x = tile.cells_x;
  held.cells_y = tile.cells_y;
}

void LayerAssembler::FillUnheld(const LayerState& state, common::Layer* cells) {
  if (cells->size() == 0 || state.tile_size <= 0) return;
  const int nx = static_cast<int>((cells->rows() + state.tile_size - 1) / state.tile_size);
  const int ny = static_cast<int>((cells->cols() + state.tile_size - 1) / state.tile_size);
  for (int ty = 0; ty < ny; ++ty) {
    for (int tx = 0; tx < nx; ++tx) {
      const int64_t x0 = int64_t{tx} * state.tile_size;
      const int64_t y0 = int64_t{ty} * state.tile_size;
      const int64_t w = std::min<int64_t>(state.tile_size, cells->rows() - x0);
      const int64_t h = std::min<int64_t>(state.tile_size, cells->cols() - y0);
      auto held = state.tiles.find({tx, ty});
      if (held == state.tiles.end()) {
        cells->block(x0, y0, w, h).setConstant(common::kUnknown);
        continue;
      }
      // A held tile smaller than its place leaves the rest of it unknown.
      const int64_t hx = std::min<int64_t>(held->second.cells_x, w);
      const int64_t hy = std::min<int64_t>(held->second.cells_y, h);
      if (hx < w) cells->block(x0 + hx, y0, w - hx, h).setConstant(common::kUnknown);
      if (hy < h) cells->block(x0, y0 + hy, hx, h - hy).setConstant(common::kUnknown);
    }
  }
}

bool LayerAssembler::OnTile(const cairn::lcmt_grid_tile& tile) {
  // Compressed tiles are decoded by their receiver (the map store's client) before they get here.
  if (tile.encoding != cairn::lcmt_grid_tile::ENCODING_FLOAT32 ||
      tile.data.size() != static_cast<size_t>(std::max(0, tile.num_cells))) {
    ++checksum_errors_;
    return false;
  }
  const uint32_t crc = common::Crc32(tile.data.data(), tile.data.size() * sizeof(float));
  return OnTileImpl(tile, tile.data.data(), tile.data.size(), crc);
}

bool LayerAssembler::OnDecodedTile(const cairn::lcmt_grid_tile& tile,
                                   const std::vector<float>& cells) {
  return OnTileImpl(tile, cells.data(), cells.size(), static_cast<uint32_t>(tile.checksum));
}

bool LayerAssembler::OnTile(const cairn::lcmt_occupancy_tile& tile) {
  if (tile.data.size() != static_cast<size_t>(std::max(0, tile.num_cells))) {
    ++checksum_errors_;
    return false;
  }
  const uint32_t crc = common::Crc32(tile.data.data(), tile.data.size());
  std::vector<float> data(tile.data.size());
  for (size_t i = 0; i < data.size(); ++i) {
    data[i] = tile.data[i] < 0 ? common::kUnknown : static_cast<float>(tile.data[i]);
  }
  return OnTileImpl(tile, data.data(), data.size(), crc);
}

void LayerAssembler::OnManifest(const cairn::lcmt_grid_manifest& m) {
  const size_t n = static_cast<size_t>(std::max(0, m.num_tiles));
  if (m.tile_ix.size() != n || m.tile_iy.size() != n || m.checksum.size() != n ||
      m.tile_version.size() != n) {
    return;
  }
  LayerState& state = StateFor(m.layer, GeometryOf(m), m.tile_size);
  if (state.has_manifest && m.layer_version < state.manifest_version) return;
  state.has_manifest = true;
  state.manifest_version = m.layer_version;
  state.robot = m.robot;
  state.map_name = m.map_name;
  state.expected.clear();
  for (size_t i = 0; i < n; ++i) {
    state.expected[{m.tile_ix[i], m.tile_iy[i]}] = static_cast<uint32_t>(m.checksum[i]);
  }
  // Tiles no longer in the manifest became all unknown.
  for (auto it = state.tiles.begin(); it != state.tiles.end();) {
    if (state.expected.count(it->first) == 0 && it->second.tile_version <= m.layer_version) {
      it = state.tiles.erase(it);
    } else {
      ++it;
    }
  }
}

std::vector<std::string> LayerAssembler::layers() const {
  std::vector<std::string> names;
  for (const auto& [name, state] : layers_) names.push_back(name);
  return names;
}

int64_t LayerAssembler::version(const std::string& layer) const {
  auto it = layers_.find(layer);
  return it == layers_.end() ? 0 : it->second.manifest_version;
}

std::vector<std::pair<int, int>> LayerAssembler::Missing(const std::string& layer) const {
  std::vector<std::pair<int, int>> missing;
  auto it = layers_.find(layer);
  if (it == layers_.end() || !it->second.has_manifest) return missing;
  for (const auto& [key, crc] : it->second.expected) {
    auto held = it->second.tiles.find(key);
    if (held == it->second.tiles.end() || held->second.checksum != crc) missing.push_back(key);
  }
  return missing;
}

bool LayerAssembler::Complete(const std::string& layer) const {
  auto it = layers_.find(layer);
  return it != layers_.end() && it->second.has_manifest && Missing(layer).empty();
}

std::optional<cairn::lcmt_tile_resend_request> LayerAssembler::MakeResendRequest(
    const std::string& layer, const std::string& requester, int64_t utime) const {
  auto it = layers_.find(layer);
  if (it == layers_.end() || !it->second.has_manifest) return std::nullopt;
  const auto missing = Missing(layer);
  if (missing.empty()) return std::nullopt;
  cairn::lcmt_tile_resend_request r{};
  r.utime = utime;
  r.requester = requester;
  r.robot = it->second.robot;
  r.map_name = it->second.map_name;
  r.layer = layer;
  r.layer_version = it->second.manifest_version;
  for (const auto& [ix, iy] : missing) {
    r.tile_ix.push_back(ix);
    r.tile_iy.push_back(iy);
  }
  r.num_tiles = static_cast<int32_t>(r.tile_ix.size());
  return r;
}

std::optional<uint32_t> LayerAssembler::HeldChecksum(const std::string& layer, int tile_ix,
                                                     int tile_iy) const {
  auto it = layers_.find(layer);
  if (it == layers_.end()) return std::nullopt;
  auto held = it->second.tiles.find({tile_ix, tile_iy});
  if (held == it->second.tiles.end()) return std::nullopt;
  return held->second.checksum;
}

std::optional<common::GridGeometry> LayerAssembler::Geometry(const std::string& layer) const {
  auto it = layers_.find(layer);
  if (it == layers_.end()) return std::nullopt;
  return it->second.geometry;
}

std::optional<common::GridMap> LayerAssembler::Layer(const std::string& layer) const {
  auto it = layers_.find(layer);
  if (it == layers_.end()) return std::nullopt;
  const LayerState& state = it->second;
  common::GridMap map(state.geometry);
  if (state.cells.size() == 0) {
    map.AddLayer(layer, common::kUnknown);  // no tile arrived: all unknown
  } else {
    common::Layer cells = state.cells;
    FillUnheld(state, &cells);
    map.AddLayer(layer, std::move(cells));
  }
  return map;
}

std::optional<common::GridMap> LayerAssembler::TakeLayer(const std::string& layer) {
  auto it = layers_.find(layer);
  if (it == layers_.end()) return std::nullopt;
  LayerState& state = it->second;
  common::GridMap map(state.geometry);
  if (state.cells.size() == 0) {
    map.AddLayer(layer, common::kUnknown);
  } else {
    FillUnheld(state, &state.cells);
    map.AddLayer(layer, std::move(state.cells));
  }
  layers_.erase(it);
  return map;
}

}  // namespace cairn::runtime
