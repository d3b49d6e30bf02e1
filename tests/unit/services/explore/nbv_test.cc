#include "services/explore/nbv.h"

#include <cmath>
#include <cstdio>
#include <queue>
#include <random>
#include <set>
#include <stdexcept>

#include <gtest/gtest.h>

#include "tests/unit/services/explore/explore_test_support.h"

namespace cairn::explore {
namespace {

using testing::FillMap;
using testing::SetCell;

InfoMap OpenMap(double size_m, double cnc) {
  InfoMapParams params;
  params.margin_m = 0.0;
  InfoMap map(RectangleWorkArea({0.0, 0.0}, {size_m, size_m}), params);
  if (cnc > 0.0) FillMap(&map, cnc);
  return map;
}

// Seed 002 test 15.
TEST(NbvTest, UtilityAndStopRuleArithmetic) {
  const NbvWeights w{0.43, 0.35, 0.22, 0.09};
  EXPECT_NEAR(Utility(w, 0.6, 0.3, 0.1, 20.0), 0.385 / 1.8, 1e-12);
  EXPECT_NEAR(Utility(w, 0.6, 0.3, 0.1, 20.0), 0.2139, 5e-5);
  EXPECT_NEAR(StopThreshold(0.09, 50.0), 0.1111, 5e-5);
  EXPECT_NEAR(StopThreshold(0.2, 25.0), 0.1, 1e-12);
  // Ranking: with w_C = 0.2 a numerator of 0.5 at 5 m beats 0.9 at 20 m.
  const NbvWeights near_w{1.0, 0.0, 0.0, 0.2};
  EXPECT_NEAR(Utility(near_w, 0.5, 0, 0, 5.0), 0.5, 1e-12);
  EXPECT_NEAR(Utility(near_w, 0.9, 0, 0, 20.0), 0.225, 1e-12);
}

TEST(NbvTest, QualityCombinationMatchesTheThesisNumbers) {
  EXPECT_NEAR(CombineQuality(1, 1, 0.93, 0.07), 1.0, 1e-4);
  EXPECT_NEAR(CombineQuality(1, 0, 0.93, 0.07), 0.9972, 1e-4);
  EXPECT_NEAR(CombineQuality(0, 1, 0.93, 0.07), 0.0751, 1e-4);
  EXPECT_NEAR(CombineQuality(0.5, 0.5, 0.93, 0.07), 0.5, 1e-4);
  EXPECT_NEAR(CombineQuality(0.5, 1, 0.93, 0.07), 0.5042, 1e-4);
}

TEST(NbvTest, PresetsCarryTheThesisWeightsAndAnUnknownNameIsRefused) {
  const NbvParams balanced = NbvPreset("simple-balanced");
  EXPECT_DOUBLE_EQ(balanced.weights.w_a, 0.43);
  EXPECT_DOUBLE_EQ(balanced.weights.w_c, 0.09);
  EXPECT_EQ(NbvPreset("greedy").strategy, NbvStrategy::kGreedy);
  EXPECT_DOUBLE_EQ(NbvPreset("unstructured-balanced").weights.w_c, 0.125);
  EXPECT_DOUBLE_EQ(NbvPreset("structured-information").weights.w_c, 0.08);
  EXPECT_GE(NbvPresetNames().size(), 8u);
  try {
    NbvPreset("fast");
    FAIL() << "an unknown preset was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("simple-quality"), std::string::npos);
  }
  NbvParams bad;
  bad.weights.w_c = 0.0;
  EXPECT_THROW(bad.Validate(), std::invalid_argument);
}

// Seed 002 test 12.
TEST(NbvTest, CandidatesAreSafeSpacedFewAndDeterministic) {
  InfoMap map = OpenMap(30.0, 0.9);
  // A band of unsafe cells.
  for (int iy = 0; iy < map.size_y(); ++iy) SetCell(&map, map.Linear({50, iy}), 0.0);
  NbvParams params;
  const common::Vector2 robot{1.0, 1.0};
  const auto a = SampleCandidates(map, params, robot, 7);
  const auto b = SampleCandidates(map, params, robot, 7);
  const auto c = SampleCandidates(map, params, robot, 8);
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);
  ASSERT_FALSE(a.empty());
  int64_t safe = 0;
  for (int64_t i = 0; i < map.num_cells(); ++i) safe += map.Navigability(i) > 0.7f;
  EXPECT_LE(static_cast<int64_t>(a.size()), safe / 50);
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_GT(map.Navigability(a[i]), 0.7f);
    const auto pi = map.geometry().CenterOf(map.Cell(a[i]));
    EXPECT_GT((pi - robot).norm(), 3.0);
    for (size_t j = i + 1; j < a.size(); ++j) {
      EXPECT_GT((pi - map.geometry().CenterOf(map.Cell(a[j]))).norm(), 3.0);
    }
  }
}

// Seed 002 test 13.
TEST(NbvTest, PathCostIsManhattanOverNavigability) {
  const InfoMap open = OpenMap(6.0, 1.0);
  const NavigationTree tree = BuildNavigationTree(open, open.Linear({2, 3}), 0.7);
  EXPECT_NEAR(tree.cost[open.Linear({7, 10})], (5 + 7) * 0.3, 1e-4);
  const auto path = tree.PathTo(open.Linear({7, 10}));
  ASSERT_EQ(path.size(), 13u);
  EXPECT_EQ(path.front(), open.Linear({2, 3}));
  EXPECT_EQ(path.back(), open.Linear({7, 10}));

  const InfoMap slow = OpenMap(6.0, 0.8);
  const NavigationTree slow_tree = BuildNavigationTree(slow, slow.Linear({2, 3}), 0.7);
  EXPECT_NEAR(slow_tree.cost[slow.Linear({7, 10})], 1.25 * (5 + 7) * 0.3, 1e-4);
}

TEST(NbvTest, AWallWithOneGapForcesThePathThroughTheGap) {
  InfoMap map = OpenMap(6.0, 0.0);
  for (int64_t i = 0; i < map.num_cells(); ++i) {
    const auto c = map.Cell(i);
    SetCell(&map, i, c.ix == 10 && c.iy != 15 ? 0.7 : 1.0);  // 0.7 is not > 0.7
  }
  const NavigationTree tree = BuildNavigationTree(map, map.Linear({2, 2}), 0.7);
  const auto path = tree.PathTo(map.Linear({18, 2}));
  ASSERT_FALSE(path.empty());
  bool through_gap = false;
  for (int64_t c : path) {
    if (map.Cell(c).ix == 10) through_gap = map.Cell(c).iy == 15;
  }
  EXPECT_TRUE(through_gap);
  EXPECT_NEAR(tree.cost[map.Linear({18, 2})], (16 + 2 * 13) * 0.3, 1e-3);
}

TEST(NbvTest, AnEnclosedRegionIsUnreachableAndItsCandidatesDropped) {
  InfoMap map = OpenMap(15.0, 1.0);
  // A ring of obstacle cells around (35..45)^2.
  for (int k = 34; k <= 46; ++k) {
    for (const common::CellIndex c : {common::CellIndex{k, 34}, common::CellIndex{k, 46},
                                      common::CellIndex{34, k}, common::CellIndex{46, k}}) {
      SetCell(&map, map.Linear(c), 0.0);
    }
  }
  const NavigationTree tree = BuildNavigationTree(map, map.Linear({2, 2}), 0.7);
  EXPECT_FALSE(tree.Reachable(map.Linear({40, 40})));
  EXPECT_TRUE(tree.PathTo(map.Linear({40, 40})).empty());
  EXPECT_TRUE(tree.Reachable(map.Linear({20, 20})));
  NbvParams params;
  params.candidate_fraction = 1;
  params.candidate_spacing_m = 1.0;
  NbvPlanner planner(params);
  const NbvDecision d = planner.Decide(map, {}, {0.75, 0.75});
  int inside = 0;
  for (const Candidate& c : d.candidates) {
    const auto cell = map.Cell(c.cell);
    const bool enclosed = cell.ix > 34 && cell.ix < 46 && cell.iy > 34 && cell.iy < 46;
    if (enclosed) {
      ++inside;
      EXPECT_FALSE(c.reachable);
    }
  }
  EXPECT_GT(inside, 0);
  ASSERT_TRUE(d.best);
  EXPECT_TRUE(d.best->reachable);
}

TEST(NbvTest, TheTreeMatchesABellmanFordOnARandomMap) {
  InfoMap map = OpenMap(6.0, 0.0);
  std::mt19937_64 rng(3);
  std::uniform_int_distribution<int> tenth(0, 10);
  for (int64_t i = 0; i < map.num_cells(); ++i) SetCell(&map, i, tenth(rng) / 10.0);
  const int64_t root = map.Linear({10, 10});
  const NavigationTree tree = BuildNavigationTree(map, root, 0.7);
  std::vector<double> cost(map.num_cells(), INFINITY);
  cost[root] = 0.0;
  for (bool changed = true; changed;) {
    changed = false;
    for (int64_t i = 0; i < map.num_cells(); ++i) {
      if (!std::isfinite(cost[i])) continue;
      const auto c = map.Cell(i);
      for (const common::CellIndex n :
           {common::CellIndex{c.ix + 1, c.iy}, common::CellIndex{c.ix - 1, c.iy},
            common::CellIndex{c.ix, c.iy + 1}, common::CellIndex{c.ix, c.iy - 1}}) {
        if (!map.geometry().Contains(n)) continue;
        const int64_t j = map.Linear(n);
        if (!(map.Navigability(j) > 0.7f)) continue;
        const double next = cost[i] + 0.3 / map.Navigability(j);
        if (next < cost[j] - 1e-9) {
          cost[j] = next;
          changed = true;
        }
      }
    }
  }
  for (int64_t i = 0; i < map.num_cells(); ++i) {
    if (std::isfinite(cost[i])) {
      EXPECT_NEAR(tree.cost[i], cost[i], 1e-4) << i;
    } else {
      EXPECT_FALSE(tree.Reachable(i)) << i;
    }
  }
}

// Seed 002 test 14.
TEST(NbvTest, InformationGainCountsVisibleUnexploredCellsInTheWorkArea) {
  InfoMapParams info;
  info.margin_m = 0.0;
  NbvParams params;
  params.gain_range_m = 6.0;
  {
    InfoMap map(RectangleWorkArea({0, 0}, {30, 30}), info);
    const int64_t c = map.Linear({50, 50});
    SetCell(&map, c, 1.0);
    ViewEvaluator eval(map, params);
    EXPECT_NEAR(eval.Evaluate(c, {}).info_gain, 1.0, 0.01);
    // A wall of obstacle cells through the candidate's neighbourhood (x = 15.15 m, the column
    // beside it) hides the far half.
    for (int iy = 0; iy < map.size_y(); ++iy) SetCell(&map, map.Linear({51, iy}), 0.0);
    ViewEvaluator eval2(map, params);
    EXPECT_NEAR(eval2.Evaluate(c, {}).info_gain, 0.5, 0.04);
  }
  {
    InfoMap map(RectangleWorkArea({0, 0}, {30, 30}), info);
    FillMap(&map, 1.0);
    ViewEvaluator eval(map, params);
    EXPECT_EQ(eval.Evaluate(map.Linear({50, 50}), {}).info_gain, 0.0);
  }
  {
    // The work area is only the west half: the east half neither counts nor normalises.
    InfoMapParams wide = info;
    wide.margin_m = 15.0;
    InfoMap map(RectangleWorkArea({0, 0}, {15.15, 30}), wide);
    const auto c = *map.geometry().IndexOf({15.0, 15.0});
    SetCell(&map, map.Linear(c), 1.0);
    ViewEvaluator eval(map, params);
    EXPECT_NEAR(eval.Evaluate(map.Linear(c), {}).info_gain, 1.0, 0.02);
  }
}

TEST(NbvTest, QualityGainIsHigherNearPoorlyScannedCells) {
  InfoMap map = OpenMap(30.0, 0.0);
  FillMap(&map, 1.0, 0.2f);
  NbvParams params;
  ViewEvaluator eval(map, params);
  const double poor = eval.Evaluate(map.Linear({50, 50}), {}).quality_gain;
  EXPECT_GT(poor, 0.1);
  InfoMap good = OpenMap(30.0, 0.0);
  FillMap(&good, 1.0, 1.0f);
  ViewEvaluator eval_good(good, params);
  EXPECT_EQ(eval_good.Evaluate(good.Linear({50, 50}), {}).quality_gain, 0.0);
}

TEST(NbvTest, ZoneGainCountsVisibleZonesFacingTheView) {
  InfoMap map = OpenMap(30.0, 0.0);
  for (int64_t i = 0; i < map.num_cells(); ++i) SetCell(&map, i, map.Cell(i).ix == 60 ? 0.0 : 1.0);
  NbvParams params;
  InterestZone facing;
  facing.center_m = {17.f, 15.f, 1.f};
  facing.normal = {-2.f, 0.f, 0.f};  // faces west, towards the candidate at x = 15
  facing.area_m2 = 2.f;
  InterestZone edge_on = facing;
  edge_on.normal = {0.f, 2.f, 0.f};
  const auto c = *map.geometry().IndexOf({15.0, 15.0});
  ViewEvaluator eval(map, params);
  EXPECT_GT(eval.Evaluate(map.Linear(c), {facing}).zone_gain, 0.9);
  EXPECT_LT(eval.Evaluate(map.Linear(c), {edge_on}).zone_gain, 0.1);
  // Hidden behind the wall of obstacle cells at x = 18 m: not counted.
  InterestZone behind = facing;
  behind.center_m.x() = 22.f;
  ViewEvaluator eval2(map, params);
  const ViewGains hidden = eval2.Evaluate(map.Linear(c), {behind});
  EXPECT_EQ(hidden.zone_gain, 0.0);
  EXPECT_TRUE(hidden.zones_seen.empty());
}

TEST(NbvTest, TheDecisionStopsWhenNothingIsWorthTheTrip) {
  // Fully explored at top quality: the best utility is 0 < C_p.
  InfoMap done = OpenMap(30.0, 0.0);
  FillMap(&done, 1.0, 1.0f);
  NbvPlanner planner(NbvPreset("simple-balanced"));
  const NbvDecision d = planner.Decide(done, {}, {15.0, 15.0});
  EXPECT_EQ(d.outcome, NbvDecision::Outcome::kStopUtility) << d.reason;
  // Below the minimum global quality it keeps going.
  NbvParams strict = NbvPreset("simple-balanced");
  strict.min_global_quality = 0.9;
  InfoMap poor = OpenMap(30.0, 0.0);
  FillMap(&poor, 1.0, 0.5f);
  NbvPlanner strict_planner(strict);
  EXPECT_EQ(strict_planner.Decide(poor, {}, {15.0, 15.0}).outcome, NbvDecision::Outcome::kGoTo);
  // No safe cell at all: no candidate.
  InfoMap blocked = OpenMap(30.0, 0.0);
  NbvPlanner p2(NbvParams{});
  EXPECT_EQ(p2.Decide(blocked, {}, {15.0, 15.0}).outcome, NbvDecision::Outcome::kNoCandidate);
  EXPECT_THROW(p2.Decide(blocked, {}, {-50.0, 15.0}), std::invalid_argument);
}

// Seed 002 test 26 (the CARTIF presets of table 6-8): information-heavy weights choose a view
// near the known/unknown border, a long hop away; quality-heavy weights with a high cost choose
// one near the robot.
TEST(NbvTest, Seed002Test26InformationHeavyWeightsHopToTheBorderQualityHeavyOnesStayNear) {
  // Safe ground scanned at quality 0.3 west of x = 30 m, nothing known east of it; the robot
  // 25 m from the border, beyond the gains' 20 m range.
  InfoMap map = OpenMap(40.0, 0.0);
  std::vector<ScoredPoint> points;
  for (int64_t i = 0; i < map.num_cells(); ++i) {
    if (map.Cell(i).ix >= 100) continue;
    const auto cell = testing::CellPoints(map, i, 1.0, 0.3f);
    points.insert(points.end(), cell.begin(), cell.end());
  }
  map.AddPoints(points);
  const common::Vector2 robot(5.0, 20.0);
  auto decide = [&](const char* preset) {
    const NbvDecision d = NbvPlanner(NbvPreset(preset)).Decide(map, {}, robot);
    EXPECT_EQ(d.outcome, NbvDecision::Outcome::kGoTo) << preset << ": " << d.reason;
    return d.best.value_or(Candidate{});
  };
  const Candidate fast = decide("cartif-fast");        // w 0.84, 0.10, 0.05, 0.05
  const Candidate careful = decide("cartif-quality");  // w 0.35, 0.40, 0.15, 0.40
  std::printf(
      "cartif-fast: (%.1f, %.1f), %.1f m, A %.2f Q %.2f; cartif-quality: (%.1f, %.1f), "
      "%.1f m, A %.2f Q %.2f\n",
      fast.position_m.x(), fast.position_m.y(), fast.path_length_m, fast.info_gain,
      fast.quality_gain, careful.position_m.x(), careful.position_m.y(), careful.path_length_m,
      careful.info_gain, careful.quality_gain);
  // Near the border (within 5 m of it; the first view that sees into the unknown is 10 m
  // nearer), seeing into the unknown.
  EXPECT_GT(fast.position_m.x(), 25.0);
  EXPECT_GT(fast.info_gain, 0.0);
  // Near the robot: closer than the border is to the robot by far.
  EXPECT_LT(careful.path_length_m, 8.0);
  EXPECT_GT(fast.path_length_m, 2.0 * careful.path_length_m);
}

TEST(NbvTest, GreedyPicksTheMostNewInformationAndUtilityWeighsTheTrip) {
  // Explored safe ground everywhere except an unexplored block in the far corner; the robot at
  // the other corner. Greedy goes next to the block whatever the distance.
  InfoMapParams info;
  info.margin_m = 0.0;
  InfoMap map(RectangleWorkArea({0, 0}, {30, 30}), info);
  for (int64_t i = 0; i < map.num_cells(); ++i) {
    const auto c = map.Cell(i);
    if (c.ix >= 75 && c.iy >= 75) continue;
    SetCell(&map, i, 1.0, 1.0f);
  }
  NbvParams greedy = NbvPreset("greedy");
  greedy.candidate_fraction = 5;
  NbvPlanner planner(greedy);
  const NbvDecision d = planner.Decide(map, {}, {2.0, 2.0});
  ASSERT_EQ(d.outcome, NbvDecision::Outcome::kGoTo) << d.reason;
  double max_info = 0.0;
  for (const Candidate& c : d.candidates) max_info = std::max(max_info, c.info_gain);
  EXPECT_DOUBLE_EQ(d.best->info_gain, max_info);
  EXPECT_GT(d.best->position_m.x() + d.best->position_m.y(), 30.0);
}

TEST(NbvTest, AnUnexploredCellAScanMissedWeighsHalfPerMissUntilAViewComesNearer) {
  InfoMap map = OpenMap(30.0, 0.0);
  const int64_t cell = map.Linear({50, 50});
  MissedViews missed(map.num_cells());
  const int east = MissedViews::Sector(1, 0);
  EXPECT_EQ(missed.Weight(cell, east, 10.0, 3.0), 1.0);  // never missed
  // Missed by scans from 10 m east, then from 8.08 m east-north-east: a quarter for views as
  // far from the east, 1 from nearer than 8.08 - 3 = 5.08 m.
  const int64_t from10 = map.Linear({50 + 33, 50});     // 9.9 m east
  const int64_t from8 = map.Linear({50 + 26, 50 + 7});  // 8.08 m, 15 degrees north of east
  EXPECT_EQ(RecordMissedView(map, from10, {cell}, &missed), 1);
  EXPECT_EQ(missed.Weight(cell, east, 10.0, 3.0), 0.5);
  EXPECT_EQ(RecordMissedView(map, from8, {cell}, &missed), 0);  // not a first miss
  EXPECT_EQ(missed.Weight(cell, east, 9.0, 3.0), 0.25);
  EXPECT_EQ(missed.Weight(cell, east, 5.5, 3.0), 0.25);
  EXPECT_EQ(missed.Weight(cell, east, 5.0, 3.0), 1.0);
  EXPECT_NEAR(missed.nearest_m[cell * MissedViews::kSectors + east], 0.3 * std::hypot(26, 7), 1e-5);
  // From any other direction nothing has missed it yet: what hid it from the east (a house, a
  // crest) need not hide it from the north or the west.
  for (int s = 0; s < MissedViews::kSectors; ++s) {
    if (s == east) continue;
    EXPECT_EQ(missed.Weight(cell, s, 10.0, 3.0), 1.0) << "sector " << s;
  }
  // A third miss, from the north, is a first miss from there and leaves the east's count.
  EXPECT_EQ(RecordMissedView(map, map.Linear({50, 50 + 30}), {cell}, &missed), 0);
  EXPECT_EQ(missed.Weight(cell, MissedViews::Sector(0, 1), 10.0, 3.0), 0.5);
  EXPECT_EQ(missed.Weight(cell, east, 9.0, 3.0), 0.25);
  MissedViews wrong(10);
  EXPECT_THROW(RecordMissedView(map, from8, {cell}, &wrong), std::invalid_argument);
  EXPECT_THROW(ViewEvaluator(map, NbvParams{}, &wrong), std::invalid_argument);
}

TEST(NbvTest, MissedViewSectorsAreTheOctantsOfTheBearing) {
  // Anticlockwise from east, 45 degrees each; a bearing on a boundary goes to one side only.
  EXPECT_EQ(MissedViews::Sector(10, 1), 0);
  EXPECT_EQ(MissedViews::Sector(1, 10), 1);
  EXPECT_EQ(MissedViews::Sector(-1, 10), 2);
  EXPECT_EQ(MissedViews::Sector(-10, 1), 3);
  EXPECT_EQ(MissedViews::Sector(-10, -1), 4);
  EXPECT_EQ(MissedViews::Sector(-1, -10), 5);
  EXPECT_EQ(MissedViews::Sector(1, -10), 6);
  EXPECT_EQ(MissedViews::Sector(10, -1), 7);
  for (int dx = -5; dx <= 5; ++dx) {
    for (int dy = -5; dy <= 5; ++dy) {
      if (dx == 0 && dy == 0) continue;
      double deg = std::atan2(dy, dx) * 180.0 / M_PI;
      if (deg < 0.0) deg += 360.0;
      const int s = MissedViews::Sector(dx, dy);
      // Within its octant, boundaries included.
      EXPECT_GE(deg, 45.0 * s - 1e-9) << dx << "," << dy;
      EXPECT_LE(deg, 45.0 * (s + 1) + 1e-9) << dx << "," << dy;
    }
  }
}

TEST(NbvTest, InformationGainDiscountsCellsEarlierScansMissed) {
  // A safe explored square with an unexplored 3 x 3 m hole; the view 5 m from the hole.
  InfoMap map = OpenMap(30.0, 0.0);
  for (int64_t i = 0; i < map.num_cells(); ++i) {
    const auto c = map.Cell(i);
    if (c.ix >= 45 && c.ix < 55 && c.iy >= 45 && c.iy < 55) continue;
    SetCell(&map, i, 1.0, 1.0f);
  }
  NbvParams params;
  params.gain_range_m = 8.0;
  const int64_t view = map.Linear({50, 33});
  ViewEvaluator listing(map, params);
  const ViewGains first = listing.Evaluate(view, {}, true);
  EXPECT_EQ(first.unexplored.size(), 100u);
  ASSERT_GT(first.info_gain, 0.0);
  // A scan from there saw none of them: the same view now expects half as much.
  MissedViews missed(map.num_cells());
  RecordMissedView(map, view, first.unexplored, &missed);
  ViewEvaluator discounted(map, params, &missed);
  EXPECT_NEAR(discounted.Evaluate(view, {}).info_gain, 0.5 * first.info_gain, 1e-9);
  // A view nearer to every cell by more than missed_view_step_m expects them all again (about
  // 2.6 m nearer here).
  params.missed_view_step_m = 1.0;
  ViewEvaluator nearer(map, params, &missed);
  ViewEvaluator plain(map, params);
  const int64_t near_view = map.Linear({50, 42});
  EXPECT_NEAR(nearer.Evaluate(near_view, {}).info_gain, plain.Evaluate(near_view, {}).info_gain,
              1e-9);
}

TEST(NbvTest, AWallAcrossTheScannersHeightHidesTheGroundBehindItButACrownDoesNot) {
  // Explored safe ground but for an unexplored 6 m strip beyond x = 15 m; a line of cells at
  // x = 12 m between the view (x = 6 m) and the strip holds navigable ground and steep points.
  auto map_with = [](float low_z, float high_z) {
    InfoMap map = OpenMap(30.0, 0.0);
    std::vector<ScoredPoint> points;
    for (int64_t i = 0; i < map.num_cells(); ++i) {
      const auto c = map.Cell(i);
      if (c.ix >= 50 && c.ix < 70) continue;
      const auto cell = testing::CellPoints(map, i, 1.0);
      points.insert(points.end(), cell.begin(), cell.end());
      if (c.ix != 40) continue;
      for (float z : {low_z, high_z}) {
        ScoredPoint p = cell.front();
        p.position_m.z() = z;
        p.normal = {-1.f, 0.f, 0.f};
        points.push_back(p);
      }
    }
    map.AddPoints(points);
    return map;
  };
  NbvParams params;
  params.gain_range_m = 15.0;
  const int64_t view = OpenMap(30.0, 0.0).Linear({20, 50});
  // Every cell stays navigable (C_nc 1 with the steep points' F = 1): only the wall test hides.
  InfoMap open = map_with(NAN, NAN);
  InfoMap wall = map_with(0.1f, 2.5f);   // from the foot to above the 1 m scanner
  InfoMap crown = map_with(2.0f, 4.0f);  // all of it above the scanner
  InfoMap kerb = map_with(0.0f, 0.15f);  // all of it below
  InfoMap rough = map_with(0.9f, 1.1f);  // rough ground at the scanner's height: no wall
  ASSERT_GT(wall.Navigability(wall.Linear({40, 50})), params.occlusion_cnc);
  const double seen = ViewEvaluator(open, params).Evaluate(view, {}).info_gain;
  ASSERT_GT(seen, 0.01);
  EXPECT_EQ(ViewEvaluator(wall, params).Evaluate(view, {}).info_gain, 0.0);
  EXPECT_DOUBLE_EQ(ViewEvaluator(crown, params).Evaluate(view, {}).info_gain, seen);
  EXPECT_DOUBLE_EQ(ViewEvaluator(kerb, params).Evaluate(view, {}).info_gain, seen);
  EXPECT_DOUBLE_EQ(ViewEvaluator(rough, params).Evaluate(view, {}).info_gain, seen);
}

TEST(NbvTest, QualityGainCountsUnexploredCellsAtTheQualityAScanWouldGiveThem) {
  // Nothing explored but the view's own cell: eq. 4.10 sums over every cell in range, Q_a = 0
  // where unexplored, so the gain is the mean expected quality over the range.
  InfoMap map = OpenMap(30.0, 0.0);
  const int64_t c = map.Linear({50, 50});
  SetCell(&map, c, 1.0, 1.0f);
  NbvParams params;
  params.gain_range_m = 10.0;
  ViewEvaluator eval(map, params);
  const ViewGains g = eval.Evaluate(c, {});
  EXPECT_GT(g.quality_gain, 0.1);
  EXPECT_LT(g.quality_gain, 0.9);  // far cells get less than A_max allows
  // The same map fully explored at top quality: nothing to gain.
  InfoMap good = OpenMap(30.0, 0.0);
  FillMap(&good, 1.0, 1.0f);
  ViewEvaluator eval_good(good, params);
  EXPECT_EQ(eval_good.Evaluate(c, {}).quality_gain, 0.0);
}

TEST(NbvTest, NoCandidateNearAViewPointAlreadyScanned) {
  InfoMap map = OpenMap(30.0, 0.9);
  NbvParams params;
  params.candidate_fraction = 1;
  const common::Vector2 robot{2.0, 2.0};
  const std::vector<common::Vector2> visited = {{15.0, 15.0}, {25.0, 8.0}};
  const auto cells = SampleCandidates(map, params, robot, 3, visited);
  ASSERT_GT(cells.size(), 10u);
  for (int64_t i : cells) {
    const auto p = map.geometry().CenterOf(map.Cell(i));
    for (const auto& v : visited) EXPECT_GE((p - v).norm(), params.revisit_radius_m);
  }
  // Without the rule some candidate lies within 1.5 m of (15, 15) for some seed.
  params.revisit_radius_m = 0.0;
  bool near = false;
  for (uint64_t seed = 0; seed < 50 && !near; ++seed) {
    for (int64_t i : SampleCandidates(map, params, robot, seed)) {
      near |= (map.geometry().CenterOf(map.Cell(i)) - visited[0]).norm() < 1.5;
    }
  }
  EXPECT_TRUE(near);
}

TEST(NbvTest, TheCandidateDrawIsStableWhereTheMapDidNotChange) {
  // Two maps that differ only in the west third: candidates in the east two thirds, away from
  // the change by more than the spacing, are the same cells.
  InfoMap a = OpenMap(30.0, 0.9);
  InfoMap b = OpenMap(30.0, 0.9);
  for (int64_t i = 0; i < b.num_cells(); ++i) {
    if (b.Cell(i).ix < 33 && (b.Cell(i).iy % 7) == 0) SetCell(&b, i, 0.0);
  }
  NbvParams params;
  const common::Vector2 robot{1.0, 1.0};
  auto east = [&](const InfoMap& map, const std::vector<int64_t>& cells) {
    std::set<int64_t> out;
    for (int64_t i : cells) {
      if (map.Cell(i).ix >= 33 + 2 * 10) out.insert(i);  // 6 m past the changed band
    }
    return out;
  };
  const auto ca = SampleCandidates(a, params, robot, 11);
  const auto cb = SampleCandidates(b, params, robot, 11);
  const auto ea = east(a, ca), eb = east(b, cb);
  ASSERT_GT(ea.size(), 3u);
  // The cap (1/50 of the safe cells) is lower for b and the spacing lets a change ripple a
  // little: most, not all, of the east candidates stay.
  int same = 0;
  for (int64_t i : ea) same += eb.count(i);
  EXPECT_GE(same, static_cast<int>(ea.size()) * 2 / 3);
  EXPECT_NE(CandidateRank(5, 1), CandidateRank(5, 2));
  EXPECT_NE(CandidateRank(5, 1), CandidateRank(6, 1));
}

TEST(NbvTest, TheTreeGoesOverABridgesDeckFromTheRimsAndUnderItFromTheFloor) {
  InfoMapParams info;
  info.margin_m = 0.0;
  info.max_step_m = 0.08;
  info.level_gap_m = 1.5;
  const InfoMap map = testing::BridgeMap(info);
  const int64_t n = map.num_cells();
  // Over: from the west rim along the deck's middle row (y 2.85) to the east rim.
  const int64_t west = map.Linear({0, 9}), east = map.Linear({19, 9});
  const NavigationTree over = BuildNavigationTree(map, west, 0.7, 0.0, 3.f);
  ASSERT_TRUE(over.Reachable(east));
  bool crossed = false;
  for (int64_t node : over.PathTo(east)) {
    EXPECT_GT(map.Navigability(node), 0.7f);
    const common::Vector2 xy = map.geometry().CenterOf(map.Cell(node));
    if (xy.x() > 1.8 && xy.x() < 4.2) {
      EXPECT_EQ(map.NodeLevel(node), 1) << "over the canyon, on the deck";
      crossed = true;
    }
  }
  EXPECT_TRUE(crossed);
  // The canyon's floor is not reachable from the rims: no ramp leads down.
  EXPECT_FALSE(over.Reachable(map.Linear({10, 0})));
  // Under: along the floor from the south end to the north end.
  const int64_t south = map.Linear({10, 0}), north = map.Linear({10, 19});
  const NavigationTree under = BuildNavigationTree(map, south, 0.7, 0.0, 0.f);
  ASSERT_TRUE(under.Reachable(north));
  bool passed_under = false;
  for (int64_t node : under.PathTo(north)) {
    EXPECT_GT(map.Navigability(node), 0.7f);
    EXPECT_LT(node, n) << "on the floor";
    const common::Vector2 xy = map.geometry().CenterOf(map.Cell(node));
    passed_under = passed_under || (xy.y() > 2.4 && xy.y() < 3.6);
  }
  EXPECT_TRUE(passed_under);
  EXPECT_FALSE(under.Reachable(east));
  // A decision from the floor picks the floor's level by the robot's ground and keeps its path
  // and view there; candidates on the deck are not reachable from it.
  NbvParams params;
  params.candidate_fraction = 1;
  params.candidate_spacing_m = 0.5;
  params.revisit_radius_m = 0.0;
  params.robot_free_radius_m = 0.0;
  params.candidate_clearance_m = 0.0;
  NbvPlanner planner(params);
  const NbvDecision d =
      planner.Decide(map, {}, map.geometry().CenterOf(map.Cell(south)), nullptr, {}, 0.f);
  int on_deck = 0, on_floor = 0;
  for (const Candidate& c : d.candidates) {
    EXPECT_GT(map.Navigability(c.cell), 0.7f);
    if (map.NodeLevel(c.cell) == 1 && c.position_m.x() > 1.8 && c.position_m.x() < 4.2) {
      ++on_deck;
      EXPECT_FALSE(c.reachable);
    }
    if (c.reachable) {
      ++on_floor;
      EXPECT_LT(c.cell, n);
    }
  }
  EXPECT_GT(on_deck, 0);
  EXPECT_GT(on_floor, 0);
  // One level: the cells under the deck are neither deck nor floor, and neither route exists.
  info.level_gap_m = 0.0;
  const InfoMap flat = testing::BridgeMap(info);
  EXPECT_FALSE(BuildNavigationTree(flat, west, 0.7).Reachable(east));
  EXPECT_FALSE(BuildNavigationTree(flat, south, 0.7).Reachable(north));
}

}  // namespace
}  // namespace cairn::explore
