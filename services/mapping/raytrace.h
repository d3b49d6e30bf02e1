#pragma once

#include <cmath>
#include <cstdlib>
#include <limits>
#include <vector>

#include "common/grid_map.h"
#include "common/types.h"

/// @file
/// Planar grid traversal shared by the 2-D occupancy grid and the dynamic layers.
///
/// Coordinates are continuous cell coordinates: cell (i, j) covers [i, i+1) x [j, j+1), so the
/// cell of a point is (floor(x), floor(y)) (never truncation toward zero, which would make the
/// cells on both sides of 0 collapse into one). GridGeometry::ContinuousIndexOf gives these
/// coordinates for a world position.

namespace cairn::mapping {

/// A planar ray in world coordinates (metres), from the sensor to where the beam ended.
struct PlanarRay {
  common::Vector2 origin_m{common::Vector2::Zero()};
  common::Vector2 end_m{common::Vector2::Zero()};
  /// True when the end is an obstacle return; false when the ray only proves free space (no
  /// return, or a reading clipped to a maximum range).
  bool hit{true};
};

/// Exact traversal (Amanatides & Woo): visits, in order from (x0, y0) to (x1, y1), every cell
/// the segment passes through, each exactly once. The first cell is floor(x0, y0) and the last
/// floor(x1, y1), always, so both endpoint cells are visited even when an endpoint lies exactly
/// on a cell border. Consecutive cells share an edge (4-connected), and the number of cells is
/// exactly 1 + |Δix| + |Δiy|. Where the segment passes exactly through a cell corner, the step
/// in x is taken first.
///
/// `visit(int ix, int iy)` returns true to continue, false to stop early. Returns the number of
/// cells visited. Non-finite coordinates visit nothing.
template <typename Visitor>
int TraverseCells(double x0, double y0, double x1, double y1, Visitor&& visit) {
  if (!std::isfinite(x0) || !std::isfinite(y0) || !std::isfinite(x1) || !std::isfinite(y1)) {
    return 0;
  }
  int ix = static_cast<int>(std::floor(x0));
  int iy = static_cast<int>(std::floor(y0));
  const int end_ix = static_cast<int>(std::floor(x1));
  const int end_iy = static_cast<int>(std::floor(y1));
  const double dx = x1 - x0;
  const double dy = y1 - y0;
  const int step_x = end_ix > ix ? 1 : (end_ix < ix ? -1 : 0);
  const int step_y = end_iy > iy ? 1 : (end_iy < iy ? -1 : 0);

  // Parameter t in [0, 1] along the segment at which the next x (y) border is crossed, and the
  // increment of t per cell.
  constexpr double kInf = std::numeric_limits<double>::infinity();
  double t_max_x = kInf, t_delta_x = kInf, t_max_y = kInf, t_delta_y = kInf;
  if (step_x > 0) {
    t_max_x = (ix + 1 - x0) / dx;
    t_delta_x = 1.0 / dx;
  } else if (step_x < 0) {
    t_max_x = (x0 - ix) / -dx;
    t_delta_x = 1.0 / -dx;
  }
  if (step_y > 0) {
    t_max_y = (iy + 1 - y0) / dy;
    t_delta_y = 1.0 / dy;
  } else if (step_y < 0) {
    t_max_y = (y0 - iy) / -dy;
    t_delta_y = 1.0 / -dy;
  }

  // Exactly |Δix| + |Δiy| steps. The step count, not the accumulated t, ends the walk, so
  // rounding can neither skip the end cell nor walk past it; once one axis has reached its end
  // cell only the other one may step.
  int remaining_x = std::abs(end_ix - ix);
  int remaining_y = std::abs(end_iy - iy);
  int visited = 1;
  if (!visit(ix, iy)) return visited;
  while (remaining_x > 0 || remaining_y > 0) {
    const bool step_in_x = remaining_y == 0 || (remaining_x > 0 && t_max_x <= t_max_y);
    if (step_in_x) {
      ix += step_x;
      t_max_x += t_delta_x;
      --remaining_x;
    } else {
      iy += step_y;
      t_max_y += t_delta_y;
      --remaining_y;
    }
    ++visited;
    if (!visit(ix, iy)) return visited;
  }
  return visited;
}

/// The cells of TraverseCells as a list (tests and tools).
std::vector<common::CellIndex> TraverseCellList(double x0, double y0, double x1, double y1);

/// Integer Bresenham line between two cells, both included: max(|Δix|, |Δiy|) + 1 cells,
/// 8-connected, the minor coordinate rounded to the nearest cell (ties round up). This is the
/// line the seed 003 mapper meant by "Bresenham"; it can skip cells the segment grazes.
template <typename Visitor>
int BresenhamCells(common::CellIndex from, common::CellIndex to, Visitor&& visit) {
  const int dx = std::abs(to.ix - from.ix), dy = std::abs(to.iy - from.iy);
  const int sx = to.ix >= from.ix ? 1 : -1, sy = to.iy >= from.iy ? 1 : -1;
  const bool x_major = dx >= dy;
  const int major = x_major ? dx : dy, minor = x_major ? dy : dx;
  // Minor offset at major step k is round(k * minor / major), ties up: floor((2k·minor +
  // major) / 2major), kept incrementally in integers.
  int x = from.ix, y = from.iy;
  int err = major;  // 2k·minor + major, modulo 2major
  for (int k = 0; k <= major; ++k) {
    if (!visit(x, y)) return k + 1;
    if (k == major) break;
    err += 2 * minor;
    if (x_major) {
      x += sx;
    } else {
      y += sy;
    }
    if (err >= 2 * major) {
      err -= 2 * major;
      if (x_major) {
        y += sy;
      } else {
        x += sx;
      }
    }
  }
  return major + 1;
}

/// The cells of BresenhamCells as a list.
std::vector<common::CellIndex> BresenhamCellList(common::CellIndex from, common::CellIndex to);

}  // namespace cairn::mapping
