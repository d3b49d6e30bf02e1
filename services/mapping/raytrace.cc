#include "services/mapping/raytrace.h"

namespace cairn::mapping {

std::vector<common::CellIndex> TraverseCellList(double x0, double y0, double x1, double y1) {
  std::vector<common::CellIndex> cells;
  TraverseCells(x0, y0, x1, y1, [&cells](int ix, int iy) {
    cells.push_back({ix, iy});
    return true;
  });
  return cells;
}

std::vector<common::CellIndex> BresenhamCellList(common::CellIndex from, common::CellIndex to) {
  std::vector<common::CellIndex> cells;
  BresenhamCells(from, to, [&cells](int ix, int iy) {
    cells.push_back({ix, iy});
    return true;
  });
  return cells;
}

}  // namespace cairn::mapping
