#pragma once

#include <cmath>
#include <vector>

#include "services/explore/info_map.h"

/// Helpers for the exploration core's tests: info maps with chosen C_nc per cell.
namespace cairn::explore::testing {

/// Ten points at the centre of `cell` (ground height z_m): round(10 * cnc) of them navigable
/// (F = 1) and the rest obstacle (B = 1), so that C_nc = round(10 * cnc) / 10; every point has
/// quality `quality` and an upward normal.
inline std::vector<ScoredPoint> CellPoints(const InfoMap& map, int64_t cell, double cnc,
                                           float quality = 0.5f, float z_m = 0.f) {
  std::vector<ScoredPoint> points;
  const common::Vector2 xy = map.geometry().CenterOf(map.Cell(cell));
  const int navigable = static_cast<int>(std::lround(10.0 * cnc));
  for (int k = 0; k < 10; ++k) {
    ScoredPoint p;
    p.position_m = {static_cast<float>(xy.x()), static_cast<float>(xy.y()), z_m};
    p.normal = {0.f, 0.f, 1.f};
    p.navigability = k < navigable ? 1.f : 0.f;
    p.obstacle = k < navigable ? 0.f : 1.f;
    p.quality = quality;
    points.push_back(p);
  }
  return points;
}

/// Sets every cell of the map to `cnc`.
inline void FillMap(InfoMap* map, double cnc, float quality = 0.5f) {
  std::vector<ScoredPoint> all;
  for (int64_t i = 0; i < map->num_cells(); ++i) {
    const auto points = CellPoints(*map, i, cnc, quality);
    all.insert(all.end(), points.begin(), points.end());
  }
  map->AddPoints(all);
}

inline void SetCell(InfoMap* map, int64_t cell, double cnc, float quality = 0.5f) {
  map->AddPoints(CellPoints(*map, cell, cnc, quality));
}

}  // namespace cairn::explore::testing
