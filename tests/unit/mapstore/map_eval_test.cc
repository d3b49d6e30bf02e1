#include "mapstore/map_eval.h"

#include <cmath>
#include <stdexcept>
#include <utility>

#include <gtest/gtest.h>

#include "common/layers.h"

namespace cairn::mapstore {
namespace {

// 20 x 20 cells of 0.1 m from (0, 0).
common::GridGeometry Square() {
  common::GridGeometry g;
  g.resolution_m = 0.1;
  g.size_x = 20;
  g.size_y = 20;
  return g;
}

// A room: 1-cell walls on the border, 18 x 18 free cells inside; ground at 0.
common::GridMap RoomTruth() {
  common::GridMap t(Square());
  common::Layer& occ = t.AddLayer(kTruthOccupied, 0.f);
  t.AddLayer(kTruthGround, 0.f);
  for (int k = 0; k < 20; ++k) occ(k, 0) = occ(k, 19) = occ(0, k) = occ(19, k) = 1.f;
  return t;
}

MapEvalParams At(double x, double y) {
  MapEvalParams p;
  p.start_m = common::Vector2(x, y);
  return p;
}

TEST(MapEvalTest, PerfectMapOfARoom) {
  const common::GridMap truth = RoomTruth();
  common::GridMap map(Square());
  common::Layer& occ = map.AddLayer(layers::kOccupancy, 0.f);
  for (int iy = 0; iy < 20; ++iy) {
    for (int ix = 0; ix < 20; ++ix) occ(ix, iy) = truth.at(kTruthOccupied)(ix, iy) * 100.f;
  }
  const MapEvalReport r = EvaluateMap(map, truth, At(1.0, 1.0));
  EXPECT_EQ(r.truth_cells, 400);
  EXPECT_EQ(r.truth_occupied_cells, 76);
  EXPECT_EQ(r.truth_free_cells, 324);
  EXPECT_EQ(r.map_occupied_cells, 76);
  EXPECT_EQ(r.map_free_cells, 324);
  EXPECT_EQ(r.map_unknown_cells, 0);
  EXPECT_DOUBLE_EQ(r.occupied_precision, 1.0);
  EXPECT_DOUBLE_EQ(r.occupied_recall, 1.0);
  EXPECT_DOUBLE_EQ(r.occupied_recall_visible, 1.0);
  EXPECT_DOUBLE_EQ(r.free_precision, 1.0);
  EXPECT_DOUBLE_EQ(r.occupied_iou, 1.0);
  EXPECT_EQ(r.reachable_cells, 324);
  EXPECT_DOUBLE_EQ(r.coverage, 1.0);
  // Every wall cell is 1 cell thick across; the four corners (runs of 20 both ways, above the
  // cap of 10) are not measured.
  EXPECT_EQ(r.wall_cells_measured, 72);
  EXPECT_DOUBLE_EQ(r.mean_wall_thickness_cells, 1.0);
  EXPECT_NEAR(r.mean_wall_thickness_m, 0.1, 1e-12);
  MapEvalParams uncapped = At(1.0, 1.0);
  uncapped.max_wall_thickness_cells = 20;
  const MapEvalReport u = EvaluateMap(map, truth, uncapped);
  EXPECT_EQ(u.wall_cells_measured, 76);
  EXPECT_DOUBLE_EQ(u.mean_wall_thickness_cells, (72.0 + 4.0 * 20.0) / 76.0);
  EXPECT_EQ(r.double_wall_crossings, 0);
  // No elevation layer in the map.
  EXPECT_FALSE(r.elevation.has_value());
}

// Only the south wall mapped, one cell too far north (row 1); the other walls unknown; a 3 x 3
// hole, an uncertain cell (50) and a wrong free cell in the east wall.
TEST(MapEvalTest, ShiftedWallWithToleranceAndCoverage) {
  const common::GridMap truth = RoomTruth();
  common::GridMap map(Square());
  common::Layer& occ = map.AddLayer(layers::kOccupancy, common::kUnknown);
  for (int iy = 1; iy < 19; ++iy) {
    for (int ix = 1; ix < 19; ++ix) occ(ix, iy) = 10.f;
  }
  for (int ix = 0; ix < 20; ++ix) occ(ix, 1) = 90.f;
  for (int iy = 5; iy < 8; ++iy) {
    for (int ix = 5; ix < 8; ++ix) occ(ix, iy) = common::kUnknown;
  }
  occ(10, 10) = 50.f;
  occ(19, 10) = 0.f;

  const MapEvalReport r = EvaluateMap(map, truth, At(1.0, 1.0));
  EXPECT_EQ(r.map_occupied_cells, 20);
  // Interior rows 2..18 (17 x 18 = 306) minus the hole and the uncertain cell, plus (19, 10).
  EXPECT_EQ(r.map_free_cells, 306 - 9 - 1 + 1);
  EXPECT_EQ(r.map_unknown_cells, 400 - 20 - 297);
  // Row 1 is within a cell of the south wall.
  EXPECT_DOUBLE_EQ(r.occupied_precision, 1.0);
  // Recalled: the south wall (20) and the west and east walls' cells at rows 1 and 2 (4).
  EXPECT_DOUBLE_EQ(r.occupied_recall, 24.0 / 76.0);
  EXPECT_DOUBLE_EQ(r.occupied_recall_visible, 24.0 / 76.0);
  EXPECT_DOUBLE_EQ(r.free_precision, 296.0 / 297.0);
  // Map and truth share (0, 1) and (19, 1): 2 of 76 + 20 - 2.
  EXPECT_DOUBLE_EQ(r.occupied_iou, 2.0 / 94.0);
  EXPECT_EQ(r.reachable_cells, 324);
  EXPECT_EQ(r.reachable_known_cells, 324 - 10);
  EXPECT_DOUBLE_EQ(r.coverage, 314.0 / 324.0);

  // Without tolerance only the two cells on the side walls are right.
  MapEvalParams strict = At(1.0, 1.0);
  strict.tolerance_cells = 0;
  const MapEvalReport s = EvaluateMap(map, truth, strict);
  EXPECT_DOUBLE_EQ(s.occupied_precision, 2.0 / 20.0);
  EXPECT_DOUBLE_EQ(s.occupied_recall, 2.0 / 76.0);
}

// An open field with one true wall at column 10, rows 2..17 (16 cells).
common::GridMap FieldTruth(std::initializer_list<int> wall_columns) {
  common::GridMap t(Square());
  common::Layer& occ = t.AddLayer(kTruthOccupied, 0.f);
  t.AddLayer(kTruthGround, 0.f);
  for (int col : wall_columns) {
    for (int iy = 2; iy < 18; ++iy) occ(col, iy) = 1.f;
  }
  return t;
}

common::GridMap FieldMap(std::initializer_list<int> wall_columns) {
  common::GridMap m(Square());
  common::Layer& occ = m.AddLayer(layers::kOccupancy, 0.f);
  for (int col : wall_columns) {
    for (int iy = 2; iy < 18; ++iy) occ(col, iy) = 100.f;
  }
  return m;
}

TEST(MapEvalTest, DoubledWall) {
  // One wall mapped twice: columns 9 and 12 (2 free cells between): 16 rows cross both.
  const MapEvalReport r = EvaluateMap(FieldMap({9, 12}), FieldTruth({10}), At(0.05, 0.05));
  EXPECT_EQ(r.double_wall_crossings, 16);
  EXPECT_NEAR(r.double_wall_length_m, 1.6, 1e-12);
  EXPECT_DOUBLE_EQ(r.occupied_precision, 0.5);  // column 12 is two cells off
  EXPECT_DOUBLE_EQ(r.occupied_recall, 1.0);
  EXPECT_DOUBLE_EQ(r.occupied_iou, 0.0);
  EXPECT_EQ(r.wall_cells_measured, 16);
  EXPECT_DOUBLE_EQ(r.mean_wall_thickness_cells, 1.0);
  // The reachable area goes round the wall: every free cell.
  EXPECT_EQ(r.reachable_cells, 400 - 16);

  // Bands 7 cells apart are not a doubled wall; two true walls mapped as two are not either.
  EXPECT_EQ(EvaluateMap(FieldMap({9, 17}), FieldTruth({10}), At(0.05, 0.05)).double_wall_crossings,
            0);
  EXPECT_EQ(
      EvaluateMap(FieldMap({10, 13}), FieldTruth({10, 13}), At(0.05, 0.05)).double_wall_crossings,
      0);
  // The two faces of a thin wall (truth columns 10..13) seen from both sides, its inside
  // unseen: one wall, not two.
  EXPECT_EQ(EvaluateMap(FieldMap({10, 13}), FieldTruth({10, 11, 12, 13}), At(0.05, 0.05))
                .double_wall_crossings,
            0);
  // A second wall (column 14) ending at row 10, and a stray cell diagonally past its end,
  // (13, 11): row 11 crosses column 10 and the stray cell 2 cells apart over free truth, but
  // both lie on the truth within a cell. Moved a cell further off, (13, 12), it is a copy.
  {
    common::GridMap truth = FieldTruth({10});
    common::GridMap map = FieldMap({10});
    for (int iy = 2; iy <= 10; ++iy) {
      truth.at(kTruthOccupied)(14, iy) = 1.f;
      map.at(layers::kOccupancy)(14, iy) = 100.f;
    }
    map.at(layers::kOccupancy)(13, 11) = 100.f;
    const MapEvalReport stray = EvaluateMap(map, truth, At(0.05, 0.05));
    EXPECT_DOUBLE_EQ(stray.occupied_precision, 1.0);
    EXPECT_EQ(stray.double_wall_crossings, 0);
    map.at(layers::kOccupancy)(13, 11) = 0.f;
    map.at(layers::kOccupancy)(13, 12) = 100.f;
    EXPECT_EQ(EvaluateMap(map, truth, At(0.05, 0.05)).double_wall_crossings, 1);
  }
  // Gap limits are params.
  MapEvalParams wide = At(0.05, 0.05);
  wide.double_wall_max_gap_cells = 7;
  EXPECT_EQ(EvaluateMap(FieldMap({9, 17}), FieldTruth({10}), wide).double_wall_crossings, 16);
}

TEST(MapEvalTest, ThickWall) {
  const MapEvalReport r = EvaluateMap(FieldMap({9, 10, 11}), FieldTruth({10}), At(0.05, 0.05));
  EXPECT_EQ(r.wall_cells_measured, 48);
  EXPECT_DOUBLE_EQ(r.mean_wall_thickness_cells, 3.0);
  EXPECT_NEAR(r.mean_wall_thickness_m, 0.3, 1e-12);
  EXPECT_EQ(r.double_wall_crossings, 0);
  EXPECT_DOUBLE_EQ(r.occupied_precision, 1.0);
  EXPECT_DOUBLE_EQ(r.occupied_iou, 16.0 / 48.0);
}

TEST(MapEvalTest, ElevationErrorOnFreeCells) {
  common::GridMap map = FieldMap({10});
  common::Layer& z = map.AddLayer(layers::kElevation, 0.f);
  z(3, 3) = 0.3f;
  z(4, 4) = -0.1f;
  z(10, 5) = 0.9f;             // a wall cell: not compared
  z(6, 6) = common::kUnknown;  // unknown: not compared
  const MapEvalReport r = EvaluateMap(map, FieldTruth({10}), At(0.05, 0.05));
  ASSERT_TRUE(r.elevation.has_value());
  const double n = 400 - 16 - 1;
  EXPECT_EQ(r.elevation->cells, 383);
  EXPECT_NEAR(r.elevation->mean_abs_m, 0.4 / n, 1e-7);
  EXPECT_NEAR(r.elevation->rms_m, std::sqrt((0.09 + 0.01) / n), 1e-7);
  EXPECT_NEAR(r.elevation->max_abs_m, 0.3, 1e-7);
  // Away from the wall (columns 9..11 and rows 1..18 are within a cell of it): 400 cells less
  // those 54 and the unknown one; the two errors are there.
  ASSERT_TRUE(r.elevation_interior.has_value());
  EXPECT_EQ(r.elevation_interior->cells, 345);
  EXPECT_NEAR(r.elevation_interior->mean_abs_m, 0.4 / 345.0, 1e-7);
  EXPECT_NEAR(r.elevation_interior->max_abs_m, 0.3, 1e-7);
}

TEST(MapEvalTest, FreePrecisionAtAnObstaclesEdge) {
  // A true wall three cells thick (columns 9..11, rows 2..17) the map calls free throughout:
  // strictly 48 wrong cells; within a cell of free truth, only its middle column's inner
  // cells (column 10, rows 3..16) are wrong.
  common::GridMap map(Square());
  map.AddLayer(layers::kOccupancy, 0.f);
  const MapEvalReport r = EvaluateMap(map, FieldTruth({9, 10, 11}), At(0.05, 0.05));
  EXPECT_EQ(r.map_free_cells, 400);
  EXPECT_DOUBLE_EQ(r.free_precision, (400.0 - 48.0) / 400.0);
  EXPECT_DOUBLE_EQ(r.free_precision_tolerant, (400.0 - 14.0) / 400.0);
}

TEST(MapEvalTest, CostLayerAndThresholds) {
  const common::GridMap truth = FieldTruth({10});
  common::GridMap map(Square());
  common::Layer& cost = map.AddLayer(layers::CostLayer("pioneer3at"), 0.f);
  for (int iy = 2; iy < 18; ++iy) cost(10, iy) = layers::kCostLethal;
  cost(3, 3) = 99.f;  // graded: free
  cost(4, 4) = common::kUnknown;
  MapEvalParams p = At(0.05, 0.05);
  p.layer = layers::CostLayer("pioneer3at");
  const MapEvalReport r = EvaluateMap(map, truth, p);
  EXPECT_EQ(r.map_occupied_cells, 16);
  EXPECT_EQ(r.map_free_cells, 400 - 16 - 1);
  EXPECT_DOUBLE_EQ(r.occupied_iou, 1.0);
  EXPECT_DOUBLE_EQ(r.free_precision, 1.0);
  EXPECT_DOUBLE_EQ(r.coverage, 383.0 / 384.0);

  // The same values read as occupancy: 99 is occupied (> 65).
  common::GridMap occ_map(Square());
  common::Layer values = cost;
  occ_map.AddLayer(layers::kOccupancy, std::move(values));
  const MapEvalReport o = EvaluateMap(occ_map, truth, At(0.05, 0.05));
  EXPECT_EQ(o.map_occupied_cells, 17);
}

TEST(MapEvalTest, InformationMapNavigabilityAndARegion) {
  // The room judged from a C_nc layer: walls at 0.1 (occupied, below 0.4), the west half of the
  // floor at 0.9 (free, above 0.7), the east half at 0.5 (explored, neither) but one column
  // unexplored (NaN).
  const common::GridMap truth = RoomTruth();
  common::GridMap map(Square());
  common::Layer& cnc = map.AddLayer(kInfoNavigability, 0.f);
  common::Layer& region = map.AddLayer("explore/work_area", 1.f);
  for (int iy = 0; iy < 20; ++iy) {
    for (int ix = 0; ix < 20; ++ix) {
      const bool wall = truth.at(kTruthOccupied)(ix, iy) == 1.f;
      cnc(ix, iy) = wall ? 0.1f : ix < 10 ? 0.9f : ix == 15 ? NAN : 0.5f;
    }
  }
  MapEvalParams p = At(0.55, 0.55);
  p.layer = kInfoNavigability;
  const MapEvalReport r = EvaluateMap(map, truth, p);
  EXPECT_EQ(r.map_occupied_cells, 76);
  EXPECT_EQ(r.map_free_cells, 18 * 9);
  EXPECT_EQ(r.map_unknown_cells, 18);  // the NaN column inside the walls
  EXPECT_DOUBLE_EQ(r.occupied_precision, 1.0);
  EXPECT_DOUBLE_EQ(r.free_precision, 1.0);
  // Coverage counts the 0.5 cells as known: all but the NaN column.
  EXPECT_EQ(r.reachable_cells, 324);
  EXPECT_EQ(r.reachable_known_cells, 324 - 18);
  // A region of the west half only: the east half is left out of every figure.
  for (int iy = 0; iy < 20; ++iy) {
    for (int ix = 10; ix < 20; ++ix) region(ix, iy) = 0.f;
  }
  p.region_layer = "explore/work_area";
  const MapEvalReport west = EvaluateMap(map, truth, p);
  EXPECT_EQ(west.truth_cells, 200);
  EXPECT_EQ(west.reachable_cells, 18 * 9);
  EXPECT_DOUBLE_EQ(west.coverage, 1.0);
  p.region_layer = "nope";
  EXPECT_THROW(EvaluateMap(map, truth, p), std::invalid_argument);
  p.region_layer.clear();
  p.cnc_free_above = 0.3;
  EXPECT_THROW(EvaluateMap(map, truth, p), std::invalid_argument);
}

TEST(MapEvalTest, BadInputThrows) {
  const common::GridMap truth = RoomTruth();
  common::GridMap map(Square());
  map.AddLayer(layers::kOccupancy, 0.f);
  MapEvalParams no_start;
  EXPECT_THROW(EvaluateMap(map, truth, no_start), std::invalid_argument);
  EXPECT_THROW(EvaluateMap(map, truth, At(5.0, 1.0)), std::invalid_argument);   // outside
  EXPECT_THROW(EvaluateMap(map, truth, At(0.05, 1.0)), std::invalid_argument);  // in a wall
  MapEvalParams other = At(1.0, 1.0);
  other.layer = "cost/kobuki";
  try {
    EvaluateMap(map, truth, other);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("cost/kobuki"), std::string::npos) << e.what();
  }
  common::GridGeometry g = Square();
  g.resolution_m = 0.05;
  common::GridMap finer(g);
  finer.AddLayer(layers::kOccupancy, 0.f);
  EXPECT_THROW(EvaluateMap(finer, truth, At(0.5, 0.5)), std::invalid_argument);
  MapEvalParams bad = At(1.0, 1.0);
  bad.free_below = 80.0;
  EXPECT_THROW(bad.Validate(), std::invalid_argument);
}

TEST(MapEvalTest, JsonHasEveryFigureAndNullForUndefined) {
  const common::GridMap truth = RoomTruth();
  common::GridMap map(Square());
  map.AddLayer(layers::kOccupancy, common::kUnknown);  // nothing known
  const MapEvalReport r = EvaluateMap(map, truth, At(1.0, 1.0));
  EXPECT_TRUE(std::isnan(r.occupied_precision));
  EXPECT_DOUBLE_EQ(r.coverage, 0.0);
  const std::string json = MapEvalReportToJson(r);
  EXPECT_EQ(json.front(), '{');
  EXPECT_EQ(json.back(), '}');
  EXPECT_NE(json.find("\"occupied_precision\": null"), std::string::npos) << json;
  EXPECT_NE(json.find("\"occupied_recall\": 0"), std::string::npos) << json;
  EXPECT_NE(json.find("\"coverage\": 0"), std::string::npos) << json;
  EXPECT_NE(json.find("\"layer\": \"occupancy\""), std::string::npos) << json;
  EXPECT_NE(json.find("\"elevation\": null"), std::string::npos) << json;
}

}  // namespace
}  // namespace cairn::mapstore
