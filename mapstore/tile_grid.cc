#include "mapstore/tile_grid.h"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace cairn::mapstore {

std::vector<TileSpec> TilesOf(const common::GridGeometry& geometry, int tile_size,
                              const std::optional<CellBox>& region) {
  std::vector<TileSpec> tiles;
  if (tile_size <= 0 || geometry.size_x <= 0 || geometry.size_y <= 0) return tiles;
  CellBox box{0, 0, geometry.size_x, geometry.size_y};
  if (region) box = ClipBox(*region, geometry);
  if (box.empty()) return tiles;
  const int tx0 = box.min_ix / tile_size, tx1 = (box.max_ix - 1) / tile_size;
  const int ty0 = box.min_iy / tile_size, ty1 = (box.max_iy - 1) / tile_size;
  for (int ty = ty0; ty <= ty1; ++ty) {
    for (int tx = tx0; tx <= tx1; ++tx) {
      TileSpec t;
      t.tile_ix = tx;
      t.tile_iy = ty;
      t.x0 = tx * tile_size;
      t.y0 = ty * tile_size;
      t.cells_x = std::min(tile_size, geometry.size_x - t.x0);
      t.cells_y = std::min(tile_size, geometry.size_y - t.y0);
      tiles.push_back(t);
    }
  }
  return tiles;
}

std::vector<float> ExtractTile(const common::Layer& layer, const TileSpec& tile) {
  std::vector<float> cells(static_cast<size_t>(tile.cells_x) * tile.cells_y);
  for (int y = 0; y < tile.cells_y; ++y) {
    std::memcpy(&cells[static_cast<size_t>(y) * tile.cells_x], &layer(tile.x0, tile.y0 + y),
                sizeof(float) * tile.cells_x);
  }
  return cells;
}

bool AllUnknown(const std::vector<float>& cells) {
  for (float v : cells) {
    if (!std::isnan(v)) return false;
  }
  return true;
}

void PasteTile(const TileSpec& tile, const float* cells, int offset_ix, int offset_iy,
               common::Layer* layer) {
  const int lx0 = std::max(tile.x0, offset_ix);
  const int lx1 =
      std::min<int>(tile.x0 + tile.cells_x, offset_ix + static_cast<int>(layer->rows()));
  if (lx1 <= lx0) return;
  for (int y = 0; y < tile.cells_y; ++y) {
    const int gy = tile.y0 + y;
    const int ly = gy - offset_iy;
    if (ly < 0 || ly >= layer->cols()) continue;
    std::memcpy(&(*layer)(lx0 - offset_ix, ly),
                cells + static_cast<size_t>(y) * tile.cells_x + (lx0 - tile.x0),
                sizeof(float) * (lx1 - lx0));
  }
}

CellBox ClipBox(const CellBox& box, const common::GridGeometry& geometry) {
  CellBox c;
  c.min_ix = std::max(0, box.min_ix);
  c.min_iy = std::max(0, box.min_iy);
  c.max_ix = std::min(geometry.size_x, box.max_ix);
  c.max_iy = std::min(geometry.size_y, box.max_iy);
  if (c.empty()) return CellBox{};
  return c;
}

common::GridGeometry SubGeometry(const common::GridGeometry& geometry, const CellBox& box) {
  common::GridGeometry g = geometry;
  g.size_x = box.max_ix - box.min_ix;
  g.size_y = box.max_iy - box.min_iy;
  g.origin = geometry.origin.Compose(
      {box.min_ix * geometry.resolution_m, box.min_iy * geometry.resolution_m, 0.0});
  g.origin.yaw_rad = geometry.origin.yaw_rad;
  return g;
}

}  // namespace cairn::mapstore
