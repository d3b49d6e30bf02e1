#include "services/mapping/dynamic_layers.h"

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <png.h>

#include "common/layers.h"

namespace cairn::mapping {
namespace {

using common::CellIndex;

constexpr double kRes = 0.05;

// A 120 x 100 static map at 0.05 m whose origin is not (0, 0) (the seed ignored the origin):
// free everywhere except a wall column at ix = 110 and a few unknown cells.
common::GridMap StaticMap() {
  common::GridGeometry g;
  g.resolution_m = kRes;
  g.size_x = 120;
  g.size_y = 100;
  g.origin = {-7.76, -9.4, 0.0};
  common::GridMap map(g);
  common::Layer& layer = map.AddLayer(layers::kStaticMap, 0.f);
  for (int iy = 0; iy < g.size_y; ++iy) layer(110, iy) = 100.f;
  layer(5, 5) = NAN;
  layer(6, 5) = 37.f;
  return map;
}

// World centre of a cell of StaticMap().
common::Vector2 Centre(int ix, int iy) {
  return {-7.76 + (ix + 0.5) * kRes, -9.4 + (iy + 0.5) * kRes};
}

// One beam along +x from the centre of cell (ix, iy).
common::LaserScan Beam(int ix, int iy, double range_m) {
  common::LaserScan scan;
  const common::Vector2 c = Centre(ix, iy);
  scan.sensor_pose.position_m = {c.x(), c.y(), 0.3};
  scan.angle_min_rad = 0.0;
  scan.angle_increment_rad = 0.01;
  scan.range_max_m = 10.0;
  scan.ranges_m = {static_cast<float>(range_m)};
  return scan;
}

// A beam from 1 m (20 cells) before cell (ix, iy) ending in it: a hit there.
common::LaserScan HitAt(int ix, int iy) { return Beam(ix - 20, iy, 20 * kRes); }
// A beam crossing cell (ix, iy) and ending 10 cells beyond it: clears it.
common::LaserScan ClearThrough(int ix, int iy) { return Beam(ix - 20, iy, 30 * kRes); }

TEST(CostToOccupancyTest, Costmap2DPublisherTable) {
  const std::vector<std::pair<int, int>> points = {
      {0, 0},    {1, 1},    {11, 4},   {12, 5},   {36, 14},  {40, 16},   {204, 79}, {244, 94},
      {246, 95}, {247, 96}, {248, 96}, {252, 98}, {253, 99}, {254, 100}, {255, -1}};
  for (const auto& [cost, og] : points) {
    EXPECT_EQ(CostToOccupancy(static_cast<uint8_t>(cost)), og) << "cost " << cost;
  }
  for (int c = 0; c < 255; ++c) {
    const int og = CostToOccupancy(static_cast<uint8_t>(c));
    EXPECT_EQ(og > 95, c >= 247) << c;
    EXPECT_EQ(og < 5, c <= 11) << c;
    if (c > 0) {
      EXPECT_GE(og, CostToOccupancy(static_cast<uint8_t>(c - 1))) << c;
    }
  }
}

TEST(DynamicLayersTest, InitialLayers) {
  const common::GridMap static_map = StaticMap();
  DynamicLayers dut(static_map);
  for (uint8_t c : dut.short_term_costs()) ASSERT_EQ(c, kCostUnknown);
  EXPECT_EQ(dut.long_term_occupancy(), dut.static_occupancy());  // long == static
  EXPECT_EQ(dut.final_occupancy(), dut.static_occupancy());
  EXPECT_EQ(dut.StaticOccupancy({110, 3}), 100);
  EXPECT_EQ(dut.StaticOccupancy({5, 5}), -1);
  EXPECT_EQ(dut.StaticOccupancy({6, 5}), 37);
  EXPECT_EQ(dut.geometry(), static_map.geometry());
  EXPECT_DOUBLE_EQ(dut.update_period_s(), 0.2);
  const common::GridMap layers = dut.ToGridMap();
  EXPECT_TRUE(std::isnan(layers.at(layers::kShortTerm)(10, 10)));
  EXPECT_EQ(layers.at(layers::kLongTerm)(110, 10), 100.f);
  EXPECT_EQ(layers.at(layers::kFinal)(10, 10), 0.f);
}

TEST(DynamicLayersTest, FreeSpaceRayUsesTheMapOrigin) {
  DynamicLayers dut(StaticMap());
  // From the centre of (30, 40), 2.0 m along +x: cells 30..69 cleared, 70 first hit, 71 on
  // untouched. With the seed's round(x / res) and no origin the cells would be elsewhere.
  const DynamicUpdateStats stats = dut.Update({Beam(30, 40, 2.0)});
  EXPECT_EQ(stats.cells_marked, 1);
  EXPECT_EQ(stats.cells_cleared, 40);
  for (int ix = 30; ix <= 69; ++ix) EXPECT_EQ(dut.ShortTermCost({ix, 40}), kCostFree) << ix;
  EXPECT_EQ(dut.ShortTermCost({70, 40}), kCostFree);  // first hit on unknown: known, free
  EXPECT_EQ(dut.ShortTermCost({71, 40}), kCostUnknown);
  EXPECT_EQ(dut.ShortTermCost({50, 41}), kCostUnknown);
  EXPECT_EQ(dut.ShortTermOccupancy({50, 40}), 0);
}

TEST(DynamicLayersTest, MarkingRampOnUnknownCell) {
  // Seed 001 test 3: 0, 4, 8, ...; OG first > 95 at update 63, 98 at 64, 100 at 65.
  DynamicLayers dut(StaticMap());
  const CellIndex cell{60, 50};
  int first_above_95 = 0, first_98 = 0, first_100 = 0;
  for (int update = 1; update <= 100; ++update) {
    dut.Update({HitAt(60, 50)});
    const int c = dut.ShortTermCost(cell);
    if (update <= 62) {
      EXPECT_EQ(c, 4 * (update - 1)) << update;
    }
    EXPECT_LE(c, 254);
    const int og = dut.ShortTermOccupancy(cell);
    if (og > 95 && !first_above_95) first_above_95 = update;
    if (og >= 98 && !first_98) first_98 = update;
    if (og == 100 && !first_100) first_100 = update;
  }
  EXPECT_EQ(first_above_95, 63);
  EXPECT_EQ(first_98, 64);
  EXPECT_EQ(first_100, 65);
  EXPECT_EQ(dut.ShortTermCost(cell), 254);
}

TEST(DynamicLayersTest, MarkingRampOnFreeCell) {
  // Seed 001 test 4: OG 96 at update 62, 100 at update 64.
  DynamicLayers dut(StaticMap());
  const CellIndex cell{60, 50};
  dut.SetShortTermCost(cell, kCostFree);
  int first_above_95 = 0, first_100 = 0;
  for (int update = 1; update <= 80; ++update) {
    dut.Update({HitAt(60, 50)});
    const int og = dut.ShortTermOccupancy(cell);
    if (og > 95 && !first_above_95) first_above_95 = update;
    if (og == 100 && !first_100) first_100 = update;
  }
  EXPECT_EQ(first_above_95, 62);
  EXPECT_EQ(first_100, 64);
}

TEST(DynamicLayersTest, MaxRangeBeamOnlyClearsUpToMaxLength) {
  // Seed 001 test 5: r = 4.0 (>= 2.5) marks nothing and clears only up to 2.5 m (50 cells);
  // r exactly 2.5 marks nothing either.
  for (double r : {4.0, 2.5, static_cast<double>(INFINITY)}) {
    DynamicLayers dut(StaticMap());
    const DynamicUpdateStats stats = dut.Update({Beam(20, 40, r)});
    EXPECT_EQ(stats.cells_marked, 0) << r;
    EXPECT_EQ(stats.cells_cleared, 50) << r;
    EXPECT_EQ(dut.ShortTermCost({69, 40}), kCostFree) << r;
    EXPECT_EQ(dut.ShortTermCost({70, 40}), kCostUnknown) << r;
    EXPECT_EQ(dut.ShortTermCost({90, 40}), kCostUnknown) << r;
  }
}

TEST(DynamicLayersTest, ShortAndNaNReadingsChangeNothing) {
  // Seed 001 test 6: r = 0.20 (<= 0.23), r = 0.23 and NaN change no cell.
  for (double r : {0.20, 0.23, static_cast<double>(NAN), -1.0}) {
    DynamicLayers dut(StaticMap());
    const DynamicUpdateStats stats = dut.Update({Beam(20, 40, r)});
    EXPECT_EQ(stats.beams_ignored, 1) << r;
    for (uint8_t c : dut.short_term_costs()) ASSERT_EQ(c, kCostUnknown) << r;
  }
}

TEST(DynamicLayersTest, ObjectRemovedForgettingTiming) {
  // Seed 001 test 8: from OG 100 with one clearing ray per update: OG <= 95 after 8 updates,
  // OG 79 after 50, OG < 5 after 243, raw 0 after 254.
  DynamicLayers dut(StaticMap());
  const CellIndex cell{60, 50};
  dut.SetShortTermCost(cell, kCostLethal);
  int first_le_95 = 0, first_below_5 = 0, first_zero = 0;
  for (int update = 1; update <= 300; ++update) {
    const int before = dut.ShortTermOccupancy(cell);
    dut.Update({ClearThrough(60, 50)});
    const int og = dut.ShortTermOccupancy(cell);
    EXPECT_LE(og, before);  // monotonic
    if (update == 50) {
      EXPECT_EQ(og, 79);
    }
    if (og <= 95 && !first_le_95) first_le_95 = update;
    if (og < 5 && !first_below_5) first_below_5 = update;
    if (dut.ShortTermCost(cell) == 0 && !first_zero) first_zero = update;
  }
  EXPECT_EQ(first_le_95, 8);
  EXPECT_EQ(first_below_5, 243);
  EXPECT_EQ(first_zero, 254);
}

TEST(DynamicLayersTest, ShadowAndOutOfRangeCellsKeepTheirValues) {
  // Seed 001 test 9: an obstacle at 1 m hides the cells behind it; cells beyond 2.5 m are
  // out of range.
  DynamicLayers dut(StaticMap());
  dut.SetShortTermCost({35, 40}, 120);  // behind the obstacle in cell 30
  dut.SetShortTermCost({70, 41}, 90);   // 3 m away on the second beam
  common::LaserScan scan = Beam(10, 40, 1.0);
  common::LaserScan far = Beam(10, 41, INFINITY);
  for (int i = 0; i < 20; ++i) dut.Update({scan, far});
  EXPECT_EQ(dut.ShortTermCost({35, 40}), 120);
  EXPECT_EQ(dut.ShortTermCost({70, 41}), 90);
  EXPECT_EQ(dut.ShortTermCost({59, 41}), kCostFree);  // within 2.5 m: cleared
}

TEST(DynamicLayersTest, ConfigurableIncrementsChangeTheTiming) {
  // Seed 001 test 10: cost_dec = 4 forgets in <= 61 updates; cost_inc = 8 learns in <= 32.
  DynamicLayersParams params;
  params.cost_dec = 4;
  DynamicLayers forget(StaticMap(), params);
  forget.SetShortTermCost({60, 50}, kCostLethal);
  int updates = 0;
  while (forget.ShortTermOccupancy({60, 50}) >= 5 && updates < 400) {
    forget.Update({ClearThrough(60, 50)});
    ++updates;
  }
  EXPECT_EQ(updates, 61);
  params = DynamicLayersParams();
  params.cost_inc = 8;
  DynamicLayers learn(StaticMap(), params);
  updates = 0;
  while (learn.ShortTermOccupancy({60, 50}) <= 95 && updates < 400) {
    learn.Update({HitAt(60, 50)});
    ++updates;
  }
  EXPECT_EQ(updates, 32);
}

TEST(DynamicLayersTest, EachCellOncePerUpdate) {
  // Two scans of one step hit the same cell and clear the same cells: one increment, one
  // decrement (the seed incremented once per scan received between steps).
  DynamicLayers dut(StaticMap());
  dut.SetShortTermCost({60, 50}, 100);
  dut.SetShortTermCost({50, 50}, 100);
  dut.Update({HitAt(60, 50), HitAt(60, 50), Beam(30, 50, 2.0)});
  EXPECT_EQ(dut.ShortTermCost({60, 50}), 104);  // marked: not also cleared by the long beam
  EXPECT_EQ(dut.ShortTermCost({50, 50}), 99);
}

TEST(DynamicLayersTest, BoundsAreExact) {
  // A hit in the last column is marked; one just past it is outside (the seed's `<= size`
  // wrote it into the next row).
  DynamicLayers dut(StaticMap());
  DynamicUpdateStats stats = dut.Update({Beam(100, 10, 19 * kRes)});
  EXPECT_EQ(stats.cells_marked, 1);
  EXPECT_EQ(dut.ShortTermCost({119, 10}), kCostFree);
  stats = dut.Update({Beam(100, 20, 20 * kRes)});
  EXPECT_EQ(stats.cells_marked, 0);
  EXPECT_EQ(stats.marks_outside, 1);
  EXPECT_EQ(dut.ShortTermCost({0, 21}), kCostUnknown);
}

// ---- Long term ------------------------------------------------------------------------------

TEST(DynamicLayersTest, LongTermAdoptsInTheSameUpdate) {
  // Seed 001 test 12: the long-term cell equals 96 in the update where the short-term cell
  // reaches OG 96, then follows it to 98 and 100.
  DynamicLayers dut(StaticMap());
  const CellIndex cell{60, 50};
  for (int update = 1; update <= 65; ++update) {
    dut.Update({HitAt(60, 50)});
    if (update < 63) {
      EXPECT_EQ(dut.LongTermOccupancy(cell), 0) << update;
    }
  }
  // Updates 63, 64, 65 gave 96, 98, 100.
  EXPECT_EQ(dut.LongTermOccupancy(cell), 100);
  DynamicLayers again(StaticMap());
  for (int update = 1; update <= 63; ++update) again.Update({HitAt(60, 50)});
  EXPECT_EQ(again.ShortTermOccupancy(cell), 96);
  EXPECT_EQ(again.LongTermOccupancy(cell), 96);
  again.Update({HitAt(60, 50)});
  EXPECT_EQ(again.LongTermOccupancy(cell), 98);
}

TEST(DynamicLayersTest, LongTermRemovalBand) {
  // Seed 001 test 13: long 100, dec 1. Short OG 4 -> long 99; 5, 50, 95 or -1 -> unchanged.
  const std::vector<std::pair<uint8_t, int>> cases = {
      {11, 99}, {12, 100}, {128, 100}, {246, 100}, {kCostUnknown, 100}};
  for (const auto& [cost, expected] : cases) {
    DynamicLayers dut(StaticMap());
    dut.SetLongTermOccupancy({60, 50}, 100);
    dut.SetShortTermCost({60, 50}, cost);
    dut.Update({});  // a step without scans: only the long-term rule runs
    EXPECT_EQ(dut.LongTermOccupancy({60, 50}), expected) << "cost " << int{cost};
  }
}

TEST(DynamicLayersTest, StaticWallsAreNeverErased) {
  // Seed 001 test 14: the laser sees through a wall cell (a gap opened in the world): the
  // long-term value stays the static one however long it lasts.
  DynamicLayers dut(StaticMap());
  for (int update = 0; update < 400; ++update) dut.Update({ClearThrough(110, 30)});
  EXPECT_EQ(dut.ShortTermOccupancy({110, 30}), 0);
  EXPECT_EQ(dut.LongTermOccupancy({110, 30}), 100);
  EXPECT_EQ(dut.FinalOccupancy({110, 30}), 100);
  // Nor lowered by adoption: a short-term 96 on a static 100 keeps 100.
  dut.SetShortTermCost({110, 31}, 247);
  dut.Update({});
  EXPECT_EQ(dut.LongTermOccupancy({110, 31}), 100);
}

TEST(DynamicLayersTest, LongTermNeverNegative) {
  // Seed 001 test 15: long 0 with short 0 stays 0; with dec 3, long 2 stays 2.
  DynamicLayers dut(StaticMap());
  dut.SetShortTermCost({60, 50}, 0);
  for (int i = 0; i < 5; ++i) dut.Update({});
  EXPECT_EQ(dut.LongTermOccupancy({60, 50}), 0);
  DynamicLayersParams params;
  params.longterm_cost_dec = 3;
  DynamicLayers dec3(StaticMap(), params);
  dec3.SetLongTermOccupancy({60, 50}, 2);
  dec3.SetShortTermCost({60, 50}, 0);
  for (int i = 0; i < 5; ++i) dec3.Update({});
  EXPECT_EQ(dec3.LongTermOccupancy({60, 50}), 2);
}

TEST(DynamicLayersTest, SofaLearnedThenForgotten) {
  // Seed 001 test 16 in updates: an object in view enters the long-term layer within 65
  // updates (13 s at 5 Hz). Once it is gone, the long-term value follows the short-term one
  // down while that is still above 95 (to 96 after 7 updates), then waits until the
  // short-term layer sees the cell free (OG < 5, 243 updates = 48.6 s) and falls by one per
  // update, reaching 0 within 100 more updates (20 s).
  DynamicLayers dut(StaticMap());
  const CellIndex cell{60, 50};
  int learned = 0;
  for (int update = 1; update <= 65 && !learned; ++update) {
    dut.Update({HitAt(60, 50)});
    if (dut.LongTermOccupancy(cell) >= 96) learned = update;
  }
  EXPECT_EQ(learned, 63);
  for (int update = learned + 1; update <= 65; ++update) dut.Update({HitAt(60, 50)});
  ASSERT_EQ(dut.LongTermOccupancy(cell), 100);
  int zero = 0;
  for (int update = 1; update <= 400 && !zero; ++update) {
    dut.Update({ClearThrough(60, 50)});
    const int long_og = dut.LongTermOccupancy(cell);
    if (update == 1) {
      EXPECT_EQ(long_og, 99);
    }
    if (update >= 7 && update < 243) {
      ASSERT_EQ(long_og, 96) << update;
    }
    if (update == 243) {
      EXPECT_EQ(long_og, 95);
    }
    if (long_og == 0) zero = update;
  }
  EXPECT_EQ(zero, 243 + 95);
  EXPECT_LE(zero - 243, 100);
}

TEST(DynamicLayersTest, FinalIsTheMaximum) {
  // Seed 001 test 17: (-1, 37) -> 37, (-1, -1) -> -1, (14, 100) -> 100, (60, 0) -> 60.
  DynamicLayers dut(StaticMap());
  dut.SetLongTermOccupancy({1, 1}, 37);
  dut.SetLongTermOccupancy({2, 1}, -1);
  dut.SetShortTermCost({3, 1}, 36);
  dut.SetLongTermOccupancy({3, 1}, 100);
  dut.SetShortTermCost({4, 1}, 154);
  dut.SetLongTermOccupancy({4, 1}, 0);
  EXPECT_EQ(dut.ShortTermOccupancy({3, 1}), 14);
  EXPECT_EQ(dut.ShortTermOccupancy({4, 1}), 60);
  EXPECT_EQ(dut.FinalOccupancy({1, 1}), 37);
  EXPECT_EQ(dut.FinalOccupancy({2, 1}), -1);
  EXPECT_EQ(dut.FinalOccupancy({3, 1}), 100);
  EXPECT_EQ(dut.FinalOccupancy({4, 1}), 60);
  const std::vector<int8_t> final_og = dut.final_occupancy();
  EXPECT_EQ(final_og[dut.geometry().LinearIndex({4, 1})], 60);
}

TEST(DynamicLayersTest, TransientPersonStaysLowAndFades) {
  // Seed 001 test 18: 10 updates of a person on a free cell: OG 16 in the final layer, the
  // long-term layer unchanged; then OG <= 4 after 29 clearing updates (cost 40 -> 11).
  DynamicLayers dut(StaticMap());
  const CellIndex cell{60, 50};
  dut.SetShortTermCost(cell, 0);
  for (int i = 0; i < 10; ++i) dut.Update({HitAt(60, 50)});
  EXPECT_EQ(dut.ShortTermCost(cell), 40);
  EXPECT_EQ(dut.FinalOccupancy(cell), 16);
  EXPECT_EQ(dut.LongTermOccupancy(cell), 0);
  int updates = 0;
  while (dut.ShortTermOccupancy(cell) > 4) {
    dut.Update({ClearThrough(60, 50)});
    ++updates;
  }
  EXPECT_EQ(updates, 29);
}

TEST(DynamicLayersTest, ExtraRaysAddToTheLaserWithoutChangingItAlone) {
  DynamicLayers a(StaticMap()), b(StaticMap());
  const std::vector<common::LaserScan> scans = {Beam(20, 40, 1.2), Beam(20, 60, 3.0)};
  for (int i = 0; i < 5; ++i) {
    a.Update(scans);
    b.Update(scans, {});
  }
  EXPECT_EQ(a.short_term_costs(), b.short_term_costs());
  EXPECT_EQ(a.long_term_occupancy(), b.long_term_occupancy());
  // A band ray marks a table top the laser passes under.
  const PlanarRay table{Centre(20, 70), Centre(40, 70), true};
  const DynamicUpdateStats stats = a.Update(scans, {table});
  EXPECT_EQ(stats.cells_marked, 2);  // the first beam's end and the table
  EXPECT_EQ(a.ShortTermCost({40, 70}), kCostFree);
  const PlanarRay free_ray{Centre(20, 80), Centre(90, 80), false};  // clears 2.5 m only
  a.Update({}, {free_ray});
  EXPECT_EQ(a.ShortTermCost({69, 80}), kCostFree);
  EXPECT_EQ(a.ShortTermCost({70, 80}), kCostUnknown);
}

TEST(DynamicLayersTest, RestoresAStoredLongTermLayer) {
  DynamicLayers dut(StaticMap());
  for (int i = 0; i < 65; ++i) dut.Update({HitAt(60, 50)});
  const common::GridMap stored = dut.ToGridMap();
  DynamicLayers next_run(StaticMap());
  next_run.SetLongTerm(stored);
  EXPECT_EQ(next_run.long_term_occupancy(), dut.long_term_occupancy());
  EXPECT_EQ(next_run.FinalOccupancy({60, 50}), 100);  // known before it is seen again
  common::GridGeometry other = stored.geometry();
  other.size_x += 1;
  common::GridMap wrong(other);
  wrong.AddLayer(layers::kLongTerm, 0.f);
  EXPECT_THROW(next_run.SetLongTerm(wrong), std::invalid_argument);
}

TEST(DynamicLayersTest, RestoringALongTermLayerNeverErasesAStaticWall) {
  // A layer stored before the wall column at ix = 110 was drawn (free there) and a free cell:
  // the wall keeps its static value, the rest is taken as stored.
  common::GridMap stored(StaticMap().geometry());
  stored.AddLayer(layers::kLongTerm, 0.f);
  stored.at(layers::kLongTerm)(60, 50) = 97.f;
  DynamicLayers dut(StaticMap());
  dut.SetLongTerm(stored);
  EXPECT_EQ(dut.LongTermOccupancy({110, 30}), 100);
  EXPECT_EQ(dut.LongTermOccupancy({60, 50}), 97);
  EXPECT_EQ(dut.LongTermOccupancy({6, 5}), 0);  // static 37 is no wall: the stored value wins
}

TEST(DynamicLayersTest, RejectsBadInput) {
  DynamicLayersParams params;
  params.max_length_m = 0.1;
  EXPECT_THROW(DynamicLayers(StaticMap(), params), std::invalid_argument);
  params = DynamicLayersParams();
  params.cost_inc = 0;
  EXPECT_THROW(DynamicLayers(StaticMap(), params), std::invalid_argument);
  EXPECT_THROW(DynamicLayers(StaticMap(), {}, "no_such_layer"), std::out_of_range);
  DynamicLayers dut(StaticMap());
  common::LaserScan bad = Beam(10, 10, 1.0);
  bad.sensor_pose.position_m.x() = NAN;
  EXPECT_THROW(dut.Update({bad}), std::invalid_argument);
  EXPECT_THROW(dut.SetShortTermCost({500, 0}, 3), std::invalid_argument);
  EXPECT_THROW(dut.SetLongTermOccupancy({1, 1}, 101), std::invalid_argument);
}

// ---- Static map files -------------------------------------------------------------------------

std::string TempDir() {
  const std::filesystem::path dir =
      std::filesystem::path(CAIRN_BINARY_DIR) / "test-tmp" / "dynamic_layers_test";
  std::filesystem::create_directories(dir);
  return dir.string();
}

void WriteFile(const std::string& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

TEST(LoadStaticMapTest, PgmTrinaryRowsFlippedOriginKept) {
  const std::string dir = TempDir();
  // 3 x 2 image, first row is the top: black (occupied), white (free), 205 (unknown).
  std::string pgm = "P5\n# comment\n3 2\n255\n";
  pgm += std::string{'\x00', '\xfe', '\xcd', '\xfe', '\xfe', '\x00'};
  WriteFile(dir + "/map.pgm", pgm);
  WriteFile(dir + "/map.yaml",
            "image: map.pgm\nresolution: 0.05\norigin: [-7.76, -9.4, 0.0]\nnegate: 0\n"
            "occupied_thresh: 0.65\nfree_thresh: 0.196\n");
  const auto map = LoadStaticMap(dir + "/map.yaml");
  ASSERT_TRUE(map.ok()) << map.status().ToString();
  const common::Layer& layer = map.value().at(layers::kStaticMap);
  EXPECT_EQ(map.value().size_x(), 3);
  EXPECT_EQ(map.value().size_y(), 2);
  EXPECT_DOUBLE_EQ(map.value().geometry().origin.x_m, -7.76);
  EXPECT_DOUBLE_EQ(map.value().geometry().origin.y_m, -9.4);
  EXPECT_EQ(layer(0, 1), 100.f);  // top row
  EXPECT_EQ(layer(1, 1), 0.f);
  EXPECT_TRUE(std::isnan(layer(2, 1)));
  EXPECT_EQ(layer(2, 0), 100.f);  // bottom row
  DynamicLayers dut(map.value());
  EXPECT_EQ(dut.StaticOccupancy({0, 1}), 100);
}

TEST(LoadStaticMapTest, PngScaleModeAndAsciiPgm) {
  const std::string dir = TempDir();
  // 2 x 1 PNG: grey 128 (between the thresholds) and white.
  png_image png;
  std::memset(&png, 0, sizeof(png));
  png.version = PNG_IMAGE_VERSION;
  png.width = 2;
  png.height = 1;
  png.format = PNG_FORMAT_GRAY;
  const uint8_t pixels[2] = {128, 255};
  ASSERT_TRUE(png_image_write_to_file(&png, (dir + "/scale.png").c_str(), 0, pixels, 0, nullptr));
  WriteFile(dir + "/scale.yaml",
            "image: scale.png\nresolution: 0.1\norigin: [0, 0, 0]\nnegate: 0\n"
            "occupied_thresh: 0.65\nfree_thresh: 0.196\nmode: scale\n");
  const auto scaled = LoadStaticMap(dir + "/scale.yaml");
  ASSERT_TRUE(scaled.ok()) << scaled.status().ToString();
  // occ = (255 - 128) / 255 = 0.498: 1 + 98 (0.498 - 0.196) / (0.65 - 0.196) = 66.2 -> 66.
  EXPECT_EQ(scaled.value().at(layers::kStaticMap)(0, 0), 66.f);
  EXPECT_EQ(scaled.value().at(layers::kStaticMap)(1, 0), 0.f);

  WriteFile(dir + "/ascii.pgm", "P2\n2 1\n15\n0 15\n");
  WriteFile(dir + "/ascii.yaml",
            "image: ascii.pgm\nresolution: 0.1\norigin: [1, 2, 0]\nnegate: 1\n"
            "occupied_thresh: 0.65\nfree_thresh: 0.196\n");
  const auto ascii = LoadStaticMap(dir + "/ascii.yaml");
  ASSERT_TRUE(ascii.ok()) << ascii.status().ToString();
  EXPECT_EQ(ascii.value().at(layers::kStaticMap)(0, 0), 0.f);  // negated: black is free
  EXPECT_EQ(ascii.value().at(layers::kStaticMap)(1, 0), 100.f);
}

TEST(LoadStaticMapTest, BadFilesGiveClearErrors) {
  const std::string dir = TempDir();
  WriteFile(dir + "/typo.yaml", "image: map.pgm\nresolution: 0.05\norigin: [0, 0, 0]\nnegat: 0\n");
  auto result = LoadStaticMap(dir + "/typo.yaml");
  ASSERT_FALSE(result.ok());
  EXPECT_EQ(result.status().code(), common::StatusCode::kInvalidArgument);
  EXPECT_NE(result.status().message().find("typo.yaml:4"), std::string::npos)
      << result.status().message();

  WriteFile(dir + "/missing.yaml", "image: nothere.pgm\nresolution: 0.05\norigin: [0, 0, 0]\n");
  result = LoadStaticMap(dir + "/missing.yaml");
  ASSERT_FALSE(result.ok());
  EXPECT_EQ(result.status().code(), common::StatusCode::kNotFound);

  WriteFile(dir + "/broken.pgm", "P5\n3 2\n255\n\x01");
  WriteFile(dir + "/broken.yaml", "image: broken.pgm\nresolution: 0.05\norigin: [0, 0, 0]\n");
  result = LoadStaticMap(dir + "/broken.yaml");
  ASSERT_FALSE(result.ok());
  EXPECT_EQ(result.status().code(), common::StatusCode::kCorrupt);

  WriteFile(dir + "/badpng.png", "not a png");
  WriteFile(dir + "/badpng.yaml", "image: badpng.png\nresolution: 0.05\norigin: [0, 0, 0]\n");
  result = LoadStaticMap(dir + "/badpng.yaml");
  ASSERT_FALSE(result.ok());
  EXPECT_EQ(result.status().code(), common::StatusCode::kCorrupt);

  WriteFile(dir + "/origin.yaml", "image: map.pgm\nresolution: 0.05\norigin: [0, 0]\n");
  result = LoadStaticMap(dir + "/origin.yaml");
  ASSERT_FALSE(result.ok());
  EXPECT_NE(result.status().message().find("origin"), std::string::npos);

  result = LoadStaticMap(dir + "/does-not-exist.yaml");
  EXPECT_FALSE(result.ok());
}

}  // namespace
}  // namespace cairn::mapping
