#pragma once

#include <optional>
#include <vector>

#include "common/grid_map.h"
#include "mapstore/map_store.h"

/// @file
/// How the map store cuts a layer into tiles (tile (ix, iy) covers cells [ix * tile_size, ...)),
/// and boxes of cells of a grid.

namespace cairn::mapstore {

/// One tile of a layer: tile (tile_ix, tile_iy) covers cells [x0, x0 + cells_x) x
/// [y0, y0 + cells_y).
struct TileSpec {
  int tile_ix{0};
  int tile_iy{0};
  int x0{0};
  int y0{0};
  int cells_x{0};
  int cells_y{0};
};

/// Every tile of a grid (or only those overlapping `region` when given), row by row.
std::vector<TileSpec> TilesOf(const common::GridGeometry& geometry, int tile_size,
                              const std::optional<CellBox>& region = std::nullopt);
/// Cells of one tile, x fastest (the product's order).
std::vector<float> ExtractTile(const common::Layer& layer, const TileSpec& tile);
/// True when every cell is NaN (such tiles are not stored: absent = unknown).
bool AllUnknown(const std::vector<float>& cells);
/// Writes tile cells into `layer`, whose cell (0, 0) is cell (offset_ix, offset_iy) of the full
/// grid; cells outside the layer are skipped.
void PasteTile(const TileSpec& tile, const float* cells, int offset_ix, int offset_iy,
               common::Layer* layer);

/// The box clipped to a grid; empty when they do not overlap.
CellBox ClipBox(const CellBox& box, const common::GridGeometry& geometry);
/// Geometry of a box of a grid (same resolution and yaw, origin at the box's minimum corner).
common::GridGeometry SubGeometry(const common::GridGeometry& geometry, const CellBox& box);

}  // namespace cairn::mapstore
