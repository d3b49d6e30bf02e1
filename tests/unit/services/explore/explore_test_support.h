#pragma once

#include <cmath>
#include <vector>

#include "services/explore/info_map.h"
#include "services/explore/work_area.h"

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

/// A bridge over a canyon, 6 x 6 m at 0.3 m cells: the canyon's floor (z 0) runs along y for
/// x in 1.8..4.2 between rims at z 3, and a deck (top z 3, flush with the rims) crosses it along x
/// for y in 2.4..3.6. Seen as a robot would: the rims and the deck's top from scanners 1 m above
/// them (z 4), the floor, the deck's underside (z 2.7, facing down, obstacle-like) and the
/// canyon's walls under the deck (steep, z 0.3..2.55) from a scanner on the floor (z 1). The
/// scans from above come first, so a cell under the deck meets the floor after the deck.
inline InfoMap BridgeMap(const InfoMapParams& params) {
  InfoMap map(RectangleWorkArea({0.0, 0.0}, {6.0, 6.0}), params);
  auto point = [](double x, double y, double z, float nz, float f, float b) {
    ScoredPoint p;
    p.position_m = {static_cast<float>(x), static_cast<float>(y), static_cast<float>(z)};
    p.normal = nz == 0.f ? Eigen::Vector3f(1.f, 0.f, 0.f) : Eigen::Vector3f(0.f, 0.f, nz);
    p.navigability = f;
    p.obstacle = b;
    p.quality = 0.5f;
    return p;
  };
  std::vector<ScoredPoint> from_above, from_floor;
  for (int64_t i = 0; i < map.num_cells(); ++i) {
    const common::Vector2 xy = map.geometry().CenterOf(map.Cell(i));
    const double x = xy.x(), y = xy.y();
    const bool canyon = x > 1.8 && x < 4.2;
    const bool deck = y > 2.4 && y < 3.6;
    for (int k = 0; k < 4; ++k) {
      if (!canyon || deck) from_above.push_back(point(x, y, 3.0, 1.f, 1.f, 0.f));
      if (canyon) from_floor.push_back(point(x, y, 0.0, 1.f, 1.f, 0.f));
      if (canyon && deck) from_floor.push_back(point(x, y, 2.7, -1.f, 0.f, 0.9f));
    }
    // The canyon's walls under the deck, in its edge cells.
    if (deck && (std::abs(x - 1.95) < 0.01 || std::abs(x - 4.05) < 0.01)) {
      for (double z = 0.3; z < 2.6; z += 0.25) from_floor.push_back(point(x, y, z, 0.f, 0.f, 1.f));
    }
  }
  map.AddPoints(from_above, 4.f);
  map.AddPoints(from_floor, 1.f);
  return map;
}

}  // namespace cairn::explore::testing
