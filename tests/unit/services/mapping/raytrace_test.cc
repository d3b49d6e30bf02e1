#include "services/mapping/raytrace.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <set>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

namespace cairn::mapping {
namespace {

using common::CellIndex;

std::vector<int> Xs(const std::vector<CellIndex>& cells) {
  std::vector<int> out;
  for (const auto& c : cells) out.push_back(c.ix);
  return out;
}

// Whether the segment crosses the open square (ix, ix+1) x (iy, iy+1) over a positive length
// (Liang-Barsky clipping), the brute-force definition of "a cell the segment passes through".
bool CrossesInterior(double x0, double y0, double x1, double y1, int ix, int iy) {
  double t0 = 0.0, t1 = 1.0;
  const double dx = x1 - x0, dy = y1 - y0;
  auto clip = [&](double p, double q) {
    if (p == 0.0) return q > 0.0;
    const double r = q / p;
    if (p < 0.0) {
      if (r > t1) return false;
      t0 = std::max(t0, r);
    } else {
      if (r < t0) return false;
      t1 = std::min(t1, r);
    }
    return true;
  };
  if (!clip(-dx, x0 - ix) || !clip(dx, ix + 1 - x0) || !clip(-dy, y0 - iy) ||
      !clip(dy, iy + 1 - y0)) {
    return false;
  }
  return t1 - t0 > 1e-12;
}

TEST(BresenhamTest, Seed003LineCellsRowsAndEndpoints) {
  // Seed 003 test 11: (0,0) -> (3,7) in (row, col) is 8 cells, rows [0,0,1,1,2,2,3,3].
  const std::vector<CellIndex> cells = BresenhamCellList({0, 0}, {3, 7});
  ASSERT_EQ(cells.size(), 8u);
  EXPECT_EQ(cells.front(), (CellIndex{0, 0}));
  EXPECT_EQ(cells.back(), (CellIndex{3, 7}));
  EXPECT_EQ(Xs(cells), (std::vector<int>{0, 0, 1, 1, 2, 2, 3, 3}));
  std::set<std::pair<int, int>> unique;
  for (size_t i = 0; i < cells.size(); ++i) {
    unique.insert({cells[i].ix, cells[i].iy});
    if (i > 0) {  // 8-connected
      EXPECT_LE(std::abs(cells[i].ix - cells[i - 1].ix), 1);
      EXPECT_LE(std::abs(cells[i].iy - cells[i - 1].iy), 1);
    }
  }
  EXPECT_EQ(unique.size(), cells.size());
}

TEST(BresenhamTest, Seed003DescendingLineHasBothEndpoints) {
  // Seed 003 test 12: (400,400) -> (397,407) has n = 8 with both endpoints.
  const std::vector<CellIndex> cells = BresenhamCellList({400, 400}, {397, 407});
  ASSERT_EQ(cells.size(), 8u);
  EXPECT_EQ(cells.front(), (CellIndex{400, 400}));
  EXPECT_EQ(cells.back(), (CellIndex{397, 407}));
}

TEST(TraverseCellsTest, CentreToCentreVisitsEveryCrossedCellOnce) {
  // The same (0,0) -> (3,7) line through cell centres crosses 3 x-borders and 7 y-borders:
  // the exact traversal has 11 cells (Bresenham's 8 skip the grazed ones).
  const std::vector<CellIndex> cells = TraverseCellList(0.5, 0.5, 3.5, 7.5);
  ASSERT_EQ(cells.size(), 11u);
  EXPECT_EQ(cells.front(), (CellIndex{0, 0}));
  EXPECT_EQ(cells.back(), (CellIndex{3, 7}));
}

TEST(TraverseCellsTest, FloorNotTruncationForNegativeCoordinates) {
  // Truncation toward zero would put -0.5 in cell 0; floor puts it in cell -1.
  const std::vector<CellIndex> cells = TraverseCellList(-0.5, 0.5, -2.5, 0.5);
  EXPECT_EQ(Xs(cells), (std::vector<int>{-1, -2, -3}));
  const std::vector<CellIndex> across = TraverseCellList(-1.5, -0.5, 1.5, -0.5);
  EXPECT_EQ(Xs(across), (std::vector<int>{-2, -1, 0, 1}));
  for (const auto& c : across) EXPECT_EQ(c.iy, -1);
}

TEST(TraverseCellsTest, EndpointsOnBordersFollowTheFloorRule) {
  // Ends exactly on a border: the end cell is floor(3.0) = 3 and is visited.
  EXPECT_EQ(Xs(TraverseCellList(0.5, 0.5, 3.0, 0.5)), (std::vector<int>{0, 1, 2, 3}));
  // Starts exactly on a border going down: the start cell is floor(2.0) = 2.
  EXPECT_EQ(Xs(TraverseCellList(2.0, 0.5, 0.5, 0.5)), (std::vector<int>{2, 1, 0}));
  // Start and end in one cell: one cell.
  EXPECT_EQ(TraverseCellList(0.1, 0.1, 0.9, 0.8).size(), 1u);
  // Non-finite input visits nothing.
  EXPECT_TRUE(TraverseCellList(0.0, 0.0, NAN, 1.0).empty());
  EXPECT_TRUE(TraverseCellList(0.0, INFINITY, 1.0, 1.0).empty());
}

TEST(TraverseCellsTest, ThroughCornersStepsXFirst) {
  const std::vector<CellIndex> cells = TraverseCellList(0.5, 0.5, 2.5, 2.5);
  const std::vector<CellIndex> expected{{0, 0}, {1, 0}, {1, 1}, {2, 1}, {2, 2}};
  EXPECT_EQ(cells, expected);
}

TEST(TraverseCellsTest, MatchesBruteForceOnRandomSegments) {
  std::mt19937 rng(20240611);
  std::uniform_real_distribution<double> coord(-20.0, 20.0);
  for (int trial = 0; trial < 3000; ++trial) {
    const double x0 = coord(rng), y0 = coord(rng);
    // Mix long, short and axis-parallel segments.
    double x1 = coord(rng), y1 = coord(rng);
    if (trial % 7 == 0) y1 = y0;
    if (trial % 11 == 0) x1 = x0;
    if (trial % 5 == 0) {
      x1 = x0 + (x1 - x0) * 0.05;
      y1 = y0 + (y1 - y0) * 0.05;
    }
    const std::vector<CellIndex> cells = TraverseCellList(x0, y0, x1, y1);
    ASSERT_FALSE(cells.empty());
    const CellIndex first{static_cast<int>(std::floor(x0)), static_cast<int>(std::floor(y0))};
    const CellIndex last{static_cast<int>(std::floor(x1)), static_cast<int>(std::floor(y1))};
    EXPECT_EQ(cells.front(), first);
    EXPECT_EQ(cells.back(), last);
    EXPECT_EQ(cells.size(),
              static_cast<size_t>(1 + std::abs(last.ix - first.ix) + std::abs(last.iy - first.iy)));
    std::set<std::pair<int, int>> visited;
    for (size_t i = 0; i < cells.size(); ++i) {
      EXPECT_TRUE(visited.insert({cells[i].ix, cells[i].iy}).second) << "doubled cell";
      if (i > 0) {  // 4-connected
        EXPECT_EQ(std::abs(cells[i].ix - cells[i - 1].ix) + std::abs(cells[i].iy - cells[i - 1].iy),
                  1);
      }
    }
    // Every cell whose interior the segment crosses is visited (no missed cells), and every
    // visited cell is crossed or holds an endpoint.
    std::set<std::pair<int, int>> expected{{first.ix, first.iy}, {last.ix, last.iy}};
    for (int ix = std::min(first.ix, last.ix); ix <= std::max(first.ix, last.ix); ++ix) {
      for (int iy = std::min(first.iy, last.iy); iy <= std::max(first.iy, last.iy); ++iy) {
        if (CrossesInterior(x0, y0, x1, y1, ix, iy)) expected.insert({ix, iy});
      }
    }
    ASSERT_EQ(visited, expected) << "segment (" << x0 << ", " << y0 << ") -> (" << x1 << ", " << y1
                                 << ")";
  }
}

}  // namespace
}  // namespace cairn::mapping
