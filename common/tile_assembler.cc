#include "common/tile_assembler.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <set>

namespace cairn::common {

namespace {

// A grid a layer may have: finite, a positive resolution, within the cell cap.
bool UsableGrid(const GridGeometry& g) {
  return std::isfinite(g.resolution_m) && g.resolution_m > 0 && std::isfinite(g.origin.x_m) &&
         std::isfinite(g.origin.y_m) && std::isfinite(g.origin.yaw_rad) && g.size_x >= 0 &&
         g.size_y >= 0 && int64_t{g.size_x} * g.size_y <= TileAssembler::kMaxLayerCells;
}

// A tile header that fits a tile and a usable grid.
bool Admissible(const TileHeader& h) {
  if (h.cells_x < 0 || h.cells_y < 0 || h.tile_size <= 0 || h.cells_x > h.tile_size ||
      h.cells_y > h.tile_size) {
    return false;
  }
  return h.tile_size <= TileAssembler::kMaxTileSize && UsableGrid(h.geometry);
}

// A tile whose header and cells agree, in a usable grid.
bool Admissible(const CheckedTile& tile) {
  const TileHeader& h = tile.header;
  return Admissible(h) &&
         tile.num_cells == static_cast<size_t>(h.cells_x) * static_cast<size_t>(h.cells_y) &&
         (tile.num_cells == 0 || tile.cells != nullptr);
}

// A manifest a sender could have made: a usable grid, each tile in it and listed once.
bool Admissible(const TileManifest& m) {
  if (!UsableGrid(m.geometry) || m.tile_size <= 0 || m.tile_size > TileAssembler::kMaxTileSize ||
      m.layer_version < 0) {
    return false;
  }
  const int64_t nx = (int64_t{m.geometry.size_x} + m.tile_size - 1) / m.tile_size;
  const int64_t ny = (int64_t{m.geometry.size_y} + m.tile_size - 1) / m.tile_size;
  if (static_cast<int64_t>(m.tiles.size()) > nx * ny) return false;
  std::set<std::pair<int, int>> seen;
  for (const TileManifest::Entry& e : m.tiles) {
    if (e.tile_ix < 0 || e.tile_iy < 0 || e.tile_ix >= nx || e.tile_iy >= ny ||
        e.tile_version < 0 || !seen.insert({e.tile_ix, e.tile_iy}).second) {
      return false;
    }
  }
  return true;
}

}  // namespace

int64_t TileAssembler::WallClockMs() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

bool TileAssembler::FromTheFuture(int64_t version, int64_t now_ms) const {
  return version > now_ms && version - now_ms > kVersionLeadMs;
}

TileAssembler::LayerState& TileAssembler::StateFor(const std::string& layer,
                                                   const GridGeometry& geometry, int tile_size) {
  LayerState& state = layers_[layer];
  if (state.geometry != geometry || state.tile_size != tile_size) {
    state = LayerState();
    state.geometry = geometry;
    state.tile_size = tile_size;
  }
  return state;
}

void TileAssembler::Paste(LayerState* state, std::pair<int, int> key, int cells_x, int cells_y,
                          const float* cells) {
  common::Layer& canvas = state->cells;
  const int64_t x0 = int64_t{key.first} * state->tile_size;
  const int64_t y0 = int64_t{key.second} * state->tile_size;
  if (x0 < 0 || y0 < 0 || x0 >= canvas.rows() || y0 >= canvas.cols()) return;
  const int nx = static_cast<int>(std::min<int64_t>(cells_x, canvas.rows() - x0));
  const int ny = static_cast<int>(std::min<int64_t>(cells_y, canvas.cols() - y0));
  // Rows are contiguous (x fastest): one copy per tile row.
  for (int y = 0; y < ny; ++y) {
    const float* row = cells + static_cast<size_t>(y) * cells_x;
    std::copy(row, row + nx, &canvas(x0, y0 + y));
  }
}

TileAssembler::LayerState* TileAssembler::Admit(const TileHeader& h, bool* older) {
  *older = false;
  LayerState& state = StateFor(h.layer, h.geometry, h.tile_size);
  state.robot = h.robot;
  state.map_name = h.map_name;
  auto held = state.tiles.find({h.tile_ix, h.tile_iy});
  // A held version ahead of the clock outranks nothing (see Versions).
  *older = held != state.tiles.end() && h.tile_version < held->second.tile_version &&
           held->second.tile_version <= clock_();
  if (state.cells.size() == 0 && h.geometry.size_x > 0 && h.geometry.size_y > 0) {
    // Not filled: every cell is written by its tile, or made unknown by Layer / TakeLayer.
    state.cells.resize(h.geometry.size_x, h.geometry.size_y);
  }
  return &state;
}

void TileAssembler::Hold(LayerState* state, const TileHeader& h) {
  Held& held = state->tiles[{h.tile_ix, h.tile_iy}];
  held.tile_version = h.tile_version;
  held.checksum = h.checksum;
  held.cells_x = h.cells_x;
  held.cells_y = h.cells_y;
}

bool TileAssembler::OnTile(const CheckedTile& tile) {
  if (!Admissible(tile) || tile.header.tile_version < 0 ||
      FromTheFuture(tile.header.tile_version, clock_())) {
    ++refused_tiles_;
    return false;
  }
  const TileHeader& h = tile.header;
  bool older = false;
  LayerState* state = Admit(h, &older);
  if (older) return true;  // older than what is held
  Hold(state, h);
  Paste(state, {h.tile_ix, h.tile_iy}, h.cells_x, h.cells_y, tile.cells);
  return true;
}

std::optional<TileAssembler::TileSlot> TileAssembler::BeginTile(const TileHeader& h) {
  if (!Admissible(h) || h.tile_version < 0 || FromTheFuture(h.tile_version, clock_())) {
    ++refused_tiles_;
    return std::nullopt;
  }
  bool older = false;
  LayerState* state = Admit(h, &older);
  TileSlot slot;
  if (older) return slot;
  common::Layer& cells = state->cells;
  const int64_t x0 = int64_t{h.tile_ix} * state->tile_size;
  const int64_t y0 = int64_t{h.tile_iy} * state->tile_size;
  if (x0 < 0 || y0 < 0 || x0 >= cells.rows() || y0 >= cells.cols()) {
    Hold(state, h);  // outside the layer: held, with nothing to write (as in OnTile)
    return slot;
  }
  slot.first = &cells(x0, y0);
  slot.row_stride = cells.rows();
  slot.cells_x = static_cast<int>(std::min<int64_t>(h.cells_x, cells.rows() - x0));
  slot.cells_y = static_cast<int>(std::min<int64_t>(h.cells_y, cells.cols() - y0));
  // The place is being rewritten: no tile is held there until EndTile.
  state->tiles.erase({h.tile_ix, h.tile_iy});
  return slot;
}

void TileAssembler::EndTile(const TileHeader& h, bool decoded) {
  if (!decoded) return;  // BeginTile released the place: its cells read as unknown
  auto it = layers_.find(h.layer);
  if (it == layers_.end()) return;
  Hold(&it->second, h);
}

bool TileAssembler::OnManifest(const TileManifest& m) {
  const int64_t now_ms = clock_();
  bool future = FromTheFuture(m.layer_version, now_ms);
  for (const TileManifest::Entry& e : m.tiles) future = future || FromTheFuture(e.tile_version, now_ms);
  if (!Admissible(m) || future) {
    ++refused_manifests_;
    return false;
  }
  LayerState& state = StateFor(m.layer, m.geometry, m.tile_size);
  // Older than the newest is ignored, unless the newest is ahead of the clock (see Versions).
  if (state.has_manifest && m.layer_version < state.manifest_version &&
      state.manifest_version <= now_ms) {
    return true;
  }
  state.has_manifest = true;
  state.manifest_version = m.layer_version;
  state.robot = m.robot;
  state.map_name = m.map_name;
  state.expected.clear();
  for (const TileManifest::Entry& e : m.tiles) state.expected[{e.tile_ix, e.tile_iy}] = e.checksum;
  // Tiles no longer in the manifest became all unknown.
  for (auto it = state.tiles.begin(); it != state.tiles.end();) {
    if (state.expected.count(it->first) == 0 &&
        (it->second.tile_version <= m.layer_version || it->second.tile_version > now_ms)) {
      it = state.tiles.erase(it);
    } else {
      ++it;
    }
  }
  return true;
}

std::vector<std::string> TileAssembler::layers() const {
  std::vector<std::string> names;
  for (const auto& [name, state] : layers_) names.push_back(name);
  return names;
}

int64_t TileAssembler::version(const std::string& layer) const {
  auto it = layers_.find(layer);
  return it == layers_.end() ? 0 : it->second.manifest_version;
}

std::vector<std::pair<int, int>> TileAssembler::Missing(const std::string& layer) const {
  std::vector<std::pair<int, int>> missing;
  auto it = layers_.find(layer);
  if (it == layers_.end() || !it->second.has_manifest) return missing;
  for (const auto& [key, crc] : it->second.expected) {
    auto held = it->second.tiles.find(key);
    if (held == it->second.tiles.end() || held->second.checksum != crc) missing.push_back(key);
  }
  return missing;
}

bool TileAssembler::Complete(const std::string& layer) const {
  auto it = layers_.find(layer);
  return it != layers_.end() && it->second.has_manifest && Missing(layer).empty();
}

std::optional<TileRequest> TileAssembler::MissingRequest(const std::string& layer) const {
  auto it = layers_.find(layer);
  if (it == layers_.end() || !it->second.has_manifest) return std::nullopt;
  std::vector<std::pair<int, int>> missing = Missing(layer);
  if (missing.empty()) return std::nullopt;
  TileRequest r;
  r.robot = it->second.robot;
  r.map_name = it->second.map_name;
  r.layer = layer;
  r.layer_version = it->second.manifest_version;
  r.tiles = std::move(missing);
  return r;
}

std::optional<uint32_t> TileAssembler::HeldChecksum(const std::string& layer, int tile_ix,
                                                    int tile_iy) const {
  auto it = layers_.find(layer);
  if (it == layers_.end()) return std::nullopt;
  auto held = it->second.tiles.find({tile_ix, tile_iy});
  if (held == it->second.tiles.end()) return std::nullopt;
  return held->second.checksum;
}

std::optional<GridGeometry> TileAssembler::Geometry(const std::string& layer) const {
  auto it = layers_.find(layer);
  if (it == layers_.end()) return std::nullopt;
  return it->second.geometry;
}

void TileAssembler::FillUnheld(const LayerState& state, common::Layer* cells) {
  if (cells->size() == 0 || state.tile_size <= 0) return;
  const int64_t ts = state.tile_size;
  const int nx = static_cast<int>((cells->rows() + ts - 1) / ts);
  const int ny = static_cast<int>((cells->cols() + ts - 1) / ts);
  for (int ty = 0; ty < ny; ++ty) {
    for (int tx = 0; tx < nx; ++tx) {
      const int64_t x0 = tx * ts, y0 = ty * ts;
      const int64_t w = std::min<int64_t>(ts, cells->rows() - x0);
      const int64_t h = std::min<int64_t>(ts, cells->cols() - y0);
      auto held = state.tiles.find({tx, ty});
      if (held == state.tiles.end()) {
        cells->block(x0, y0, w, h).setConstant(kUnknown);
        continue;
      }
      // A held tile smaller than its place leaves the rest of it unknown.
      const int64_t hx = std::min<int64_t>(held->second.cells_x, w);
      const int64_t hy = std::min<int64_t>(held->second.cells_y, h);
      if (hx < w) cells->block(x0 + hx, y0, w - hx, h).setConstant(kUnknown);
      if (hy < h) cells->block(x0, y0 + hy, hx, h - hy).setConstant(kUnknown);
    }
  }
}

GridMap TileAssembler::AsMap(const std::string& layer, const LayerState& state,
                             common::Layer cells) {
  GridMap map(state.geometry);
  if (cells.size() == 0) {
    map.AddLayer(layer, kUnknown);  // no tile arrived: all unknown
  } else {
    FillUnheld(state, &cells);
    map.AddLayer(layer, std::move(cells));
  }
  return map;
}

std::optional<GridMap> TileAssembler::Layer(const std::string& layer) const {
  auto it = layers_.find(layer);
  if (it == layers_.end()) return std::nullopt;
  return AsMap(layer, it->second, it->second.cells);
}

std::optional<GridMap> TileAssembler::TakeLayer(const std::string& layer) {
  auto it = layers_.find(layer);
  if (it == layers_.end()) return std::nullopt;
  GridMap map = AsMap(layer, it->second, std::move(it->second.cells));
  layers_.erase(it);
  return map;
}

}  // namespace cairn::common
