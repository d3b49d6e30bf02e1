#include "services/explore/frontier.h"

#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "common/grid_map.h"
#include "common/layers.h"

namespace cairn::explore {
namespace {

using common::CellIndex;
using common::GridMap;
using common::Vector2;

constexpr float kFree = 0.f;
constexpr float kWall = 100.f;
constexpr float kUnknown = std::numeric_limits<float>::quiet_NaN();
constexpr double kRes = 0.1;

GridMap MakeMap(int size_x, int size_y, double origin_x_m = 0.0, double origin_y_m = 0.0) {
  common::GridGeometry g;
  g.resolution_m = kRes;
  g.size_x = size_x;
  g.size_y = size_y;
  g.origin.x_m = origin_x_m;
  g.origin.y_m = origin_y_m;
  GridMap map(g);
  map.AddLayer(layers::kOccupancy, kUnknown);
  return map;
}

// Sets the cells [ix0, ix1] x [iy0, iy1] (inclusive).
void Fill(GridMap* map, int ix0, int iy0, int ix1, int iy1, float value) {
  common::Layer& layer = map->at(layers::kOccupancy);
  for (int ix = ix0; ix <= ix1; ++ix) {
    for (int iy = iy0; iy <= iy1; ++iy) layer(ix, iy) = value;
  }
}

std::vector<Frontier> Find(const GridMap& map, CellIndex robot, const FrontierParams& params = {}) {
  return FindFrontiers(map, layers::kOccupancy, map.CenterOf(robot), params);
}

// 30 x 19 cells; the left half (ix 0..14) is known: walls at ix 0, iy 0 and iy 18, free inside.
// The right half (ix 15..29) is unknown. Robot at cell (5, 9).
GridMap HalfKnownRoom(double origin_x_m = 0.0, double origin_y_m = 0.0) {
  GridMap map = MakeMap(30, 19, origin_x_m, origin_y_m);
  Fill(&map, 0, 0, 14, 18, kWall);
  Fill(&map, 1, 1, 14, 17, kFree);
  return map;
}

// 42 x 32 cells walled all round, free inside; the left wall has a 5-cell opening onto the
// unknown (iy 13..17) 9 cells from the robot at (10, 15), the right wall a 25-cell one
// (iy 3..27) 30 cells away.
GridMap TwoOpeningRoom(int left_opening_cells = 5) {
  GridMap map = MakeMap(42, 32);
  Fill(&map, 0, 0, 41, 31, kWall);
  Fill(&map, 1, 1, 40, 30, kFree);
  const int left_begin = 15 - left_opening_cells / 2;
  Fill(&map, 0, left_begin, 0, left_begin + left_opening_cells - 1, kUnknown);
  Fill(&map, 41, 3, 41, 27, kUnknown);
  return map;
}
constexpr CellIndex kTwoOpeningRobot{10, 15};

// 40 x 20 cells. A walled room (ix 0..19) holds the robot at (9, 9) and has a 10-cell opening
// in its top wall (ix 5..14). Behind its right wall (ix 19), a known free pocket (ix 20..30)
// borders the unknown at ix 31.
GridMap RoomWithPocketBehindWall() {
  GridMap map = MakeMap(40, 20);
  Fill(&map, 0, 0, 30, 19, kWall);
  Fill(&map, 1, 1, 18, 18, kFree);
  Fill(&map, 5, 19, 14, 19, kUnknown);
  Fill(&map, 20, 1, 30, 18, kFree);
  return map;
}
constexpr CellIndex kPocketRobot{9, 9};

TEST(FrontierTest, AHalfKnownRoomHasOneFrontierAtTheBoundary) {
  const GridMap map = HalfKnownRoom(-1.0, 2.0);
  const std::vector<Frontier> frontiers = Find(map, {5, 9});
  ASSERT_EQ(frontiers.size(), 1u);
  const Frontier& f = frontiers[0];
  ASSERT_EQ(f.cells.size(), 17u);
  for (int k = 0; k < 17; ++k) EXPECT_EQ(f.cells[k], (CellIndex{14, 1 + k}));
  EXPECT_NEAR(f.size_m, 1.7, 1e-9);
  EXPECT_NEAR(f.centroid_m.x(), -1.0 + 1.45, 1e-9);
  EXPECT_NEAR(f.centroid_m.y(), 2.0 + 0.95, 1e-9);
  EXPECT_EQ(f.goal_cell, (CellIndex{14, 9}));
  EXPECT_NEAR(f.goal_m.x(), -1.0 + 1.45, 1e-9);
  EXPECT_NEAR(f.goal_m.y(), 2.0 + 0.95, 1e-9);
  EXPECT_NEAR(f.distance_m, 0.9, 1e-9);
  EXPECT_NEAR(f.cost, 3.0 * 0.9 - 1.0 * 1.7, 1e-9);
}

TEST(FrontierTest, TheRobotsOwnUnknownCellCountsAsFree) {
  GridMap map = HalfKnownRoom();
  Fill(&map, 5, 9, 5, 9, kUnknown);  // never observed under the robot
  const std::vector<Frontier> frontiers = Find(map, {5, 9});
  // The ring of 4 cells around the robot borders its unknown cell but is below 0.5 m.
  ASSERT_EQ(frontiers.size(), 1u);
  EXPECT_EQ(frontiers[0].goal_cell, (CellIndex{14, 9}));
  EXPECT_NEAR(frontiers[0].distance_m, 0.9, 1e-9);
}

TEST(FrontierTest, TheNearerFrontierWinsWithTheDefaultWeights) {
  FrontierParams params;
  params.min_frontier_size_m = 0.3;
  const std::vector<Frontier> frontiers = Find(TwoOpeningRoom(), kTwoOpeningRobot, params);
  ASSERT_EQ(frontiers.size(), 2u);
  // Left: 5 cells (0.5 m) at 0.9 m: 3·0.9 − 0.5 = 2.2. Right: 25 cells (2.5 m) at 3.0 m:
  // 3·3.0 − 2.5 = 6.5.
  EXPECT_EQ(frontiers[0].goal_cell, (CellIndex{1, 15}));
  EXPECT_NEAR(frontiers[0].size_m, 0.5, 1e-9);
  EXPECT_NEAR(frontiers[0].distance_m, 0.9, 1e-9);
  EXPECT_NEAR(frontiers[0].cost, 2.2, 1e-9);
  EXPECT_EQ(frontiers[1].goal_cell, (CellIndex{40, 15}));
  EXPECT_NEAR(frontiers[1].size_m, 2.5, 1e-9);
  EXPECT_NEAR(frontiers[1].distance_m, 3.0, 1e-9);
  EXPECT_NEAR(frontiers[1].cost, 6.5, 1e-9);

  const std::optional<Frontier> goal =
      ChooseFrontierGoal(TwoOpeningRoom(), layers::kOccupancy,
                         TwoOpeningRoom().CenterOf(kTwoOpeningRobot), {}, params);
  ASSERT_TRUE(goal.has_value());
  EXPECT_EQ(goal->goal_cell, (CellIndex{1, 15}));
}

TEST(FrontierTest, TheBiggerFrontierWinsWhenTheGainWeighsMore) {
  FrontierParams params;
  params.min_frontier_size_m = 0.3;
  params.gain_scale = 10.0;
  const std::vector<Frontier> frontiers = Find(TwoOpeningRoom(), kTwoOpeningRobot, params);
  ASSERT_EQ(frontiers.size(), 2u);
  // Right: 3·3.0 − 10·2.5 = −16. Left: 3·0.9 − 10·0.5 = −2.3.
  EXPECT_EQ(frontiers[0].goal_cell, (CellIndex{40, 15}));
  EXPECT_NEAR(frontiers[0].cost, -16.0, 1e-9);
  EXPECT_EQ(frontiers[1].goal_cell, (CellIndex{1, 15}));
  EXPECT_NEAR(frontiers[1].cost, -2.3, 1e-9);
}

TEST(FrontierTest, AFrontierBehindAWallIsDropped) {
  GridMap map = RoomWithPocketBehindWall();
  std::vector<Frontier> frontiers = Find(map, kPocketRobot);
  ASSERT_EQ(frontiers.size(), 1u);
  for (const CellIndex& c : frontiers[0].cells) EXPECT_EQ(c.iy, 18);
  EXPECT_EQ(frontiers[0].cells.size(), 10u);

  // A wide door in the wall makes the pocket's frontier reachable.
  Fill(&map, 19, 6, 19, 13, kFree);
  frontiers = Find(map, kPocketRobot);
  ASSERT_EQ(frontiers.size(), 2u);
  EXPECT_EQ(frontiers[0].cells.size() + frontiers[1].cells.size(), 10u + 18u);
}

TEST(FrontierTest, ClearanceKeepsTheSearchOutOfGapsNarrowerThanTheRobot) {
  GridMap map = RoomWithPocketBehindWall();
  Fill(&map, 19, 9, 19, 10, kFree);  // a 0.2 m door
  FrontierParams params;
  params.clearance_m = 0.2;
  EXPECT_EQ(Find(map, kPocketRobot, params).size(), 1u);
  params.clearance_m = 0.0;
  EXPECT_EQ(Find(map, kPocketRobot, params).size(), 2u);
  // A 0.6 m door passes a 0.2 m clearance.
  Fill(&map, 19, 7, 19, 12, kFree);
  params.clearance_m = 0.2;
  EXPECT_EQ(Find(map, kPocketRobot, params).size(), 2u);
}

TEST(FrontierTest, ARobotInsideTheClearanceCanStillMoveAwayFromTheWall) {
  FrontierParams params;
  params.min_frontier_size_m = 0.3;
  params.clearance_m = 0.3;
  // One cell from the left wall: its neighbours are inside the clearance too.
  const std::vector<Frontier> frontiers = Find(TwoOpeningRoom(), {1, 25}, params);
  EXPECT_EQ(frontiers.size(), 2u);
}

TEST(FrontierTest, TheSearchDoesNotSlipThroughADiagonalWall) {
  // A one-cell diagonal wall (k, k); below it, the cells with ix − iy >= 6 are unknown. The
  // robot is above the wall.
  GridMap map = MakeMap(12, 12);
  for (int ix = 0; ix < 12; ++ix) {
    for (int iy = 0; iy < 12; ++iy) {
      const int d = ix - iy;
      map.at(layers::kOccupancy)(ix, iy) = d == 0 ? kWall : (d >= 6 ? kUnknown : kFree);
    }
  }
  FrontierParams params;
  params.clearance_m = 0.0;
  EXPECT_TRUE(Find(map, {2, 8}, params).empty());
  // A gap in the wall lets the search through to the 7-cell frontier (5, 0) .. (11, 6).
  Fill(&map, 6, 6, 6, 6, kFree);
  const std::vector<Frontier> frontiers = Find(map, {2, 8}, params);
  ASSERT_EQ(frontiers.size(), 1u);
  EXPECT_EQ(frontiers[0].cells.size(), 7u);
}

TEST(FrontierTest, FailedGoalsAreBlacklistedWithinTheRadius) {
  FrontierParams params;
  params.min_frontier_size_m = 0.3;
  const std::vector<Frontier> frontiers = Find(TwoOpeningRoom(), kTwoOpeningRobot, params);
  ASSERT_EQ(frontiers.size(), 2u);
  const Vector2 left_goal = frontiers[0].goal_m;
  const Vector2 right_goal = frontiers[1].goal_m;

  std::optional<Frontier> goal = ChooseFrontierGoal(frontiers, {}, params);
  ASSERT_TRUE(goal.has_value());
  EXPECT_EQ(goal->goal_cell, (CellIndex{1, 15}));

  goal = ChooseFrontierGoal(frontiers, {left_goal}, params);
  ASSERT_TRUE(goal.has_value());
  EXPECT_EQ(goal->goal_cell, (CellIndex{40, 15}));

  // 0.3 m from the failed goal is outside the default 0.25 m radius ...
  const Vector2 near_left = left_goal + Vector2(0.3, 0.0);
  goal = ChooseFrontierGoal(frontiers, {near_left}, params);
  ASSERT_TRUE(goal.has_value());
  EXPECT_EQ(goal->goal_cell, (CellIndex{1, 15}));
  // ... and inside a 0.35 m one, as are all three reached cells of the left opening (iy 14..16;
  // 13 and 17 lie within the 0.2 m clearance of the wall's ends).
  params.blacklist_radius_m = 0.35;
  goal = ChooseFrontierGoal(frontiers, {near_left}, params);
  ASSERT_TRUE(goal.has_value());
  EXPECT_EQ(goal->goal_cell, (CellIndex{40, 15}));
  EXPECT_NEAR(goal->cost, frontiers[1].cost, 1e-12);

  // Both goals failed: the right frontier's next cell outside the disc.
  goal = ChooseFrontierGoal(frontiers, {left_goal, right_goal}, params);
  ASSERT_TRUE(goal.has_value());
  EXPECT_EQ(goal->goal_cell.ix, 40);
  EXPECT_GT((goal->goal_m - right_goal).norm(), 0.35);
  // Every candidate of both failed: nothing left.
  std::vector<Vector2> all;
  for (const Frontier& f : frontiers) {
    for (const FrontierGoalCandidate& c : f.candidates) all.push_back(c.position_m);
  }
  EXPECT_FALSE(ChooseFrontierGoal(frontiers, all, params).has_value());
  EXPECT_FALSE(ChooseFrontierGoal(std::vector<Frontier>{}, {}, params).has_value());
}

// The half-known room with a pillar cell two cells in front of the frontier's middle: the
// frontier cell nearest the centroid, (14, 9), is reached (0.2 m from the pillar, the search's
// clearance) but the robot would not fit there in every heading.
GridMap HalfKnownRoomWithPillar() {
  GridMap map = HalfKnownRoom();
  Fill(&map, 12, 9, 12, 9, kWall);
  return map;
}

TEST(FrontierTest, TheGoalIsTheCellNearestTheCentroidThatIsClearOfWalls) {
  const GridMap map = HalfKnownRoomWithPillar();
  std::vector<Frontier> frontiers = Find(map, {5, 9});
  ASSERT_EQ(frontiers.size(), 1u);
  const Frontier& f = frontiers[0];
  // Clear (0.35 m) cells first: (14, 6) and (14, 12) lie 0.36 m from the pillar and 0.3 m from the
  // centroid; the same path length, so the lower index wins.
  EXPECT_EQ(f.goal_cell, (CellIndex{14, 6}));
  // Rows 1 and 17 lie within the search's clearance of the walls and are never reached.
  ASSERT_EQ(f.candidates.size(), 15u);
  EXPECT_EQ(f.candidates[0].cell, (CellIndex{14, 6}));
  EXPECT_EQ(f.candidates[1].cell, (CellIndex{14, 12}));
  EXPECT_TRUE(f.candidates[0].clear);
  EXPECT_NEAR(f.distance_m, f.candidates[0].distance_m, 1e-12);
  EXPECT_NEAR(f.cost, 3.0 * f.distance_m - 1.0 * 1.7, 1e-9);
  // The cells near the pillar come last, nearest the centroid first.
  int clear = 0;
  for (const FrontierGoalCandidate& c : f.candidates) clear += c.clear ? 1 : 0;
  EXPECT_EQ(clear, 6);  // iy 4..6 and 12..14: 0.35 m from the pillar and from the walls
  EXPECT_FALSE(f.candidates[clear].clear);
  EXPECT_EQ(f.candidates[clear].cell, (CellIndex{14, 9}));
  for (const FrontierGoalCandidate& c : f.candidates) {
    EXPECT_EQ(c.position_m, map.CenterOf(c.cell));
  }

  // With no goal clearance the centroid's own cell is the goal again.
  FrontierParams params;
  params.goal_clearance_m = 0.0;
  frontiers = Find(map, {5, 9}, params);
  ASSERT_EQ(frontiers.size(), 1u);
  EXPECT_EQ(frontiers[0].goal_cell, (CellIndex{14, 9}));
  // A frontier with no clear cell at all keeps its cell nearest the centroid.
  params.goal_clearance_m = 5.0;
  frontiers = Find(map, {5, 9}, params);
  ASSERT_EQ(frontiers.size(), 1u);
  EXPECT_EQ(frontiers[0].goal_cell, (CellIndex{14, 9}));
  EXPECT_FALSE(frontiers[0].candidates[0].clear);
}

TEST(FrontierTest, AFailedGoalMovesToTheFrontiersNextCellOutsideTheBlacklist) {
  const GridMap map = HalfKnownRoomWithPillar();
  const std::vector<Frontier> frontiers = Find(map, {5, 9});
  ASSERT_EQ(frontiers.size(), 1u);
  const FrontierParams params;  // blacklist radius 0.25 m

  std::vector<Vector2> failed = {map.CenterOf({14, 6})};
  std::optional<Frontier> goal = ChooseFrontierGoal(frontiers, failed, params);
  ASSERT_TRUE(goal.has_value());
  EXPECT_EQ(goal->goal_cell, (CellIndex{14, 12}));
  // The goal's distance and cost are its own cell's.
  EXPECT_NEAR(goal->distance_m, frontiers[0].candidates[1].distance_m, 1e-12);
  EXPECT_NEAR(goal->cost, 3.0 * goal->distance_m - 1.0 * 1.7, 1e-9);
  EXPECT_EQ(goal->cells.size(), 17u);

  // Both failed: their discs cover every clear cell, so the nearest the centroid of the others,
  // the pillar's neighbour, is tried before the frontier is given up.
  failed.push_back(map.CenterOf({14, 12}));
  goal = ChooseFrontierGoal(frontiers, failed, params);
  ASSERT_TRUE(goal.has_value());
  EXPECT_EQ(goal->goal_cell, (CellIndex{14, 9}));

  // Every cell of the frontier within a failed goal's disc: the frontier is given up.
  failed.clear();
  for (int iy = 1; iy <= 17; iy += 2) failed.push_back(map.CenterOf({14, iy}));
  EXPECT_FALSE(ChooseFrontierGoal(frontiers, failed, params).has_value());
}

TEST(FrontierTest, ChoosingDoesNotAssumeASortedList) {
  FrontierParams params;
  params.min_frontier_size_m = 0.3;
  std::vector<Frontier> frontiers = Find(TwoOpeningRoom(), kTwoOpeningRobot, params);
  ASSERT_EQ(frontiers.size(), 2u);
  std::swap(frontiers[0], frontiers[1]);
  const std::optional<Frontier> goal = ChooseFrontierGoal(frontiers, {}, params);
  ASSERT_TRUE(goal.has_value());
  EXPECT_EQ(goal->goal_cell, (CellIndex{1, 15}));
}

TEST(FrontierTest, FrontiersBelowTheMinimumSizeAreDropped) {
  FrontierParams params;
  params.clearance_m = 0.0;               // so that the 2-cell opening is reachable
  const GridMap map = TwoOpeningRoom(2);  // 0.2 m on the left
  std::vector<Frontier> frontiers = Find(map, kTwoOpeningRobot, params);
  ASSERT_EQ(frontiers.size(), 1u);
  EXPECT_EQ(frontiers[0].goal_cell, (CellIndex{40, 15}));
  params.min_frontier_size_m = 0.15;
  frontiers = Find(map, kTwoOpeningRobot, params);
  ASSERT_EQ(frontiers.size(), 2u);
  EXPECT_NEAR(frontiers[0].size_m, 0.2, 1e-9);
}

TEST(FrontierTest, OnlyFreeCellsNextToUnknownCellsAreFrontiers) {
  // A band of uncertain cells (neither free nor unknown) between the free room and the
  // unknown: no frontier.
  GridMap map = HalfKnownRoom();
  Fill(&map, 14, 1, 14, 17, 25.f);
  EXPECT_TRUE(Find(map, {5, 9}).empty());
  // Just below the free threshold the band is free and is the frontier again.
  Fill(&map, 14, 1, 14, 17, 24.9f);
  EXPECT_EQ(Find(map, {5, 9}).size(), 1u);
  // A fully known map has no frontier.
  Fill(&map, 15, 0, 29, 18, kFree);
  EXPECT_TRUE(Find(map, {5, 9}).empty());
}

TEST(FrontierTest, BadInputThrows) {
  const GridMap map = HalfKnownRoom();
  const Vector2 robot = map.CenterOf({5, 9});
  const auto expect_throw_naming = [&](const FrontierParams& p, const std::string& field) {
    try {
      FindFrontiers(map, layers::kOccupancy, robot, p);
      ADD_FAILURE() << field << " was accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
    }
    EXPECT_THROW(ChooseFrontierGoal(std::vector<Frontier>{}, {}, p), std::invalid_argument);
  };
  FrontierParams p;
  EXPECT_NO_THROW(p.Validate());
  p.min_frontier_size_m = -0.1;
  expect_throw_naming(p, "min_frontier_size_m");
  p = {};
  p.potential_scale = std::numeric_limits<double>::quiet_NaN();
  expect_throw_naming(p, "potential_scale");
  p = {};
  p.gain_scale = -1.0;
  expect_throw_naming(p, "gain_scale");
  p = {};
  p.clearance_m = -0.2;
  expect_throw_naming(p, "clearance_m");
  p = {};
  p.blacklist_radius_m = std::numeric_limits<double>::infinity();
  expect_throw_naming(p, "blacklist_radius_m");
  p = {};
  p.goal_clearance_m = -0.1;
  expect_throw_naming(p, "goal_clearance_m");
  p = {};
  p.free_threshold = 70.f;
  expect_throw_naming(p, "free_threshold");
  p = {};
  p.occupied_threshold = std::numeric_limits<float>::quiet_NaN();
  expect_throw_naming(p, "occupied_threshold");

  EXPECT_THROW(FindFrontiers(map, "no_such_layer", robot), std::invalid_argument);
  EXPECT_THROW(FindFrontiers(map, layers::kOccupancy, Vector2(-0.5, 0.5)), std::invalid_argument);
  EXPECT_THROW(FindFrontiers(map, layers::kOccupancy, Vector2(NAN, 0.5)), std::invalid_argument);
  EXPECT_THROW(ChooseFrontierGoal(std::vector<Frontier>{}, {Vector2(INFINITY, 0.0)}),
               std::invalid_argument);
}

}  // namespace
}  // namespace cairn::explore
