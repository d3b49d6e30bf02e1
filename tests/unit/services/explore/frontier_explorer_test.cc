#include "services/explore/frontier_explorer.h"

#include <cmath>

#include <gtest/gtest.h>

namespace cairn::explore {
namespace {

constexpr char kLayer[] = "cost";

// A 10 x 4 m corridor at 0.1 m: x < known_until_m is free (cost 0), the rest unknown; walls
// (lethal) along y = 0 and y = 3.9.
common::GridMap Corridor(double known_until_m) {
  common::GridGeometry g;
  g.resolution_m = 0.1;
  g.size_x = 100;
  g.size_y = 40;
  common::GridMap map(g);
  common::Layer& cost = map.AddLayer(kLayer);
  for (int iy = 0; iy < g.size_y; ++iy) {
    for (int ix = 0; ix < g.size_x; ++ix) {
      if ((ix + 0.5) * 0.1 >= known_until_m) continue;
      cost(ix, iy) = (iy == 0 || iy == g.size_y - 1) ? 100.f : 0.f;
    }
  }
  return map;
}

FrontierModeParams Params() {
  FrontierModeParams p;
  p.choose_period_s = 1.0;
  p.progress_timeout_s = 10.0;
  p.finish_wait_s = 2.0;
  return p;
}

TEST(FrontierExplorerTest, NothingHappensWithoutAMap) {
  FrontierExplorer e(Params());
  EXPECT_EQ(e.Tick(nullptr, kLayer, {1.0, 2.0}, 0.0).kind, FrontierAction::Kind::kNone);
  EXPECT_EQ(e.goals_sent(), 0);
}

TEST(FrontierExplorerTest, SendsAGoalAtTheFrontierAndWaitsForTheNavigator) {
  FrontierExplorer e(Params());
  const common::GridMap map = Corridor(4.0);
  const FrontierAction a = e.Tick(&map, kLayer, {1.0, 2.0}, 0.0);
  ASSERT_EQ(a.kind, FrontierAction::Kind::kSendGoal) << a.why;
  EXPECT_EQ(a.goal_id, 1);
  EXPECT_NEAR(a.goal_m.x(), 3.95, 0.15);
  EXPECT_EQ(e.active_goal(), 1);
  EXPECT_EQ(e.frontiers(), 1);
  // The same map a moment later: keep driving.
  EXPECT_EQ(e.Tick(&map, kLayer, {1.5, 2.0}, 1.5).kind, FrontierAction::Kind::kNone);
  e.OnGoalResult(1, true, 3.0);
  EXPECT_EQ(e.goals_reached(), 1);
  EXPECT_FALSE(e.active_goal());
}

TEST(FrontierExplorerTest, AGoalWhoseFrontierIsExploredIsReplaced) {
  FrontierExplorer e(Params());
  const common::GridMap early = Corridor(4.0);
  ASSERT_EQ(e.Tick(&early, kLayer, {1.0, 2.0}, 0.0).kind, FrontierAction::Kind::kSendGoal);
  const common::GridMap later = Corridor(8.0);
  const FrontierAction a = e.Tick(&later, kLayer, {3.0, 2.0}, 1.5);
  ASSERT_EQ(a.kind, FrontierAction::Kind::kSendGoal) << a.why;
  EXPECT_EQ(a.goal_id, 2);
  EXPECT_NEAR(a.goal_m.x(), 7.95, 0.15);
  EXPECT_NE(a.why.find("explored"), std::string::npos) << a.why;
}

TEST(FrontierExplorerTest, AFailedGoalIsBlacklistedAndNoProgressGivesUp) {
  FrontierExplorer e(Params());
  const common::GridMap map = Corridor(4.0);
  const FrontierAction first = e.Tick(&map, kLayer, {1.0, 2.0}, 0.0);
  ASSERT_EQ(first.kind, FrontierAction::Kind::kSendGoal);
  e.OnGoalResult(1, false, 1.0);
  EXPECT_EQ(e.goals_failed(), 1);
  ASSERT_EQ(e.failed_goals().size(), 1u);
  // The frontier's next cell outside the 0.25 m disc round the failed goal is its goal now.
  const FrontierAction next = e.Tick(&map, kLayer, {1.0, 2.0}, 2.0);
  ASSERT_EQ(next.kind, FrontierAction::Kind::kSendGoal) << next.why;
  EXPECT_EQ(next.goal_id, 2);
  EXPECT_NEAR(next.goal_m.x(), first.goal_m.x(), 1e-9);
  EXPECT_GT((next.goal_m - first.goal_m).norm(), 0.25);
  // Every goal along the 3.6 m of reached frontier fails: the discs cover it after a few
  // (each spans five cells) and no frontier is left.
  e.OnGoalResult(2, false, 3.0);
  double now_s = 4.0;
  FrontierAction a = e.Tick(&map, kLayer, {1.0, 2.0}, now_s);
  while (a.kind == FrontierAction::Kind::kSendGoal && e.goals_failed() < 40) {
    e.OnGoalResult(a.goal_id, false, now_s);
    now_s += 1.0;
    a = e.Tick(&map, kLayer, {1.0, 2.0}, now_s);
  }
  EXPECT_EQ(a.kind, FrontierAction::Kind::kNone);
  EXPECT_GE(e.goals_failed(), 8);
  EXPECT_LE(e.goals_failed(), 20);
  for (size_t i = 0; i < e.failed_goals().size(); ++i) {
    for (size_t j = 0; j < i; ++j) {
      EXPECT_GT((e.failed_goals()[i] - e.failed_goals()[j]).norm(), 0.25) << i << " " << j;
    }
  }

  FrontierExplorer stuck(Params());
  ASSERT_EQ(stuck.Tick(&map, kLayer, {1.0, 2.0}, 0.0).kind, FrontierAction::Kind::kSendGoal);
  EXPECT_EQ(stuck.Tick(&map, kLayer, {1.0, 2.0}, 9.0).kind, FrontierAction::Kind::kNone);
  const FrontierAction give_up = stuck.Tick(&map, kLayer, {1.0, 2.0}, 10.5);
  EXPECT_EQ(give_up.kind, FrontierAction::Kind::kCancelGoal) << give_up.why;
  EXPECT_EQ(give_up.goal_id, 1);
  EXPECT_EQ(stuck.goals_failed(), 1);
}

TEST(FrontierExplorerTest, AGoalMovedAlongItsFrontierIsKeptWhileDriving) {
  FrontierModeParams params = Params();
  params.frontier.blacklist_radius_m = 1.2;  // the next goal lies over 1 m from the first
  FrontierExplorer e(params);
  const common::GridMap map = Corridor(4.0);
  const FrontierAction first = e.Tick(&map, kLayer, {1.0, 2.0}, 0.0);
  ASSERT_EQ(first.kind, FrontierAction::Kind::kSendGoal);
  e.OnGoalResult(1, false, 1.0);
  const FrontierAction next = e.Tick(&map, kLayer, {1.0, 2.0}, 2.0);
  ASSERT_EQ(next.kind, FrontierAction::Kind::kSendGoal) << next.why;
  EXPECT_GT((next.goal_m - first.goal_m).norm(), 1.2);
  // The frontier is the same, its first cell still the failed goal: the goal is not sent again
  // (a new id every second would make the navigator start over).
  for (double t = 3.5; t < 8.0; t += 1.5) {
    const FrontierAction a = e.Tick(&map, kLayer, {1.5, 2.0}, t);
    EXPECT_EQ(a.kind, FrontierAction::Kind::kNone) << t << ": " << a.why;
  }
  EXPECT_EQ(e.goals_sent(), 2);
  EXPECT_EQ(e.active_goal(), 2);
}

TEST(FrontierExplorerTest, AGoalThatFailedForAPassingReasonMayBeChosenAgain) {
  FrontierExplorer e(Params());
  const common::GridMap map = Corridor(4.0);
  ASSERT_EQ(e.Tick(&map, kLayer, {1.0, 2.0}, 0.0).kind, FrontierAction::Kind::kSendGoal);
  e.OnGoalResult(1, false, 1.0, /*blacklist=*/false);
  EXPECT_EQ(e.goals_failed(), 1);
  EXPECT_TRUE(e.failed_goals().empty());
  const FrontierAction again = e.Tick(&map, kLayer, {1.0, 2.0}, 2.0);
  ASSERT_EQ(again.kind, FrontierAction::Kind::kSendGoal);
  EXPECT_EQ(again.goal_id, 2);
  EXPECT_NEAR(again.goal_m.x(), 3.95, 0.15);
}

TEST(FrontierExplorerTest, UnknownCellsUnderTheRobotReadAsFree) {
  // The robot stands in an unknown patch (its laser, ahead of the centre, has not seen it):
  // the search still leaves it.
  common::GridMap map = Corridor(4.0);
  common::Layer& cost = map.at(kLayer);
  for (int iy = 17; iy <= 23; ++iy) {
    for (int ix = 7; ix <= 13; ++ix) cost(ix, iy) = NAN;
  }
  FrontierExplorer e(Params());
  const FrontierAction a = e.Tick(&map, kLayer, {1.0, 2.0}, 0.0);
  ASSERT_EQ(a.kind, FrontierAction::Kind::kSendGoal) << a.why;
  EXPECT_NEAR(a.goal_m.x(), 3.95, 0.15);
  FrontierModeParams strict = Params();
  strict.free_around_robot_m = 0.0;
  FrontierExplorer blind(strict);
  EXPECT_EQ(blind.Tick(&map, kLayer, {1.0, 2.0}, 0.0).kind, FrontierAction::Kind::kNone);
}

TEST(FrontierExplorerTest, FinishesWhenNoFrontierIsLeftForTheWait) {
  FrontierExplorer e(Params());
  const common::GridMap done = Corridor(100.0);  // all known: no frontier
  EXPECT_EQ(e.Tick(&done, kLayer, {1.0, 2.0}, 0.0).kind, FrontierAction::Kind::kNone);
  EXPECT_EQ(e.Tick(&done, kLayer, {1.0, 2.0}, 1.0).kind, FrontierAction::Kind::kNone);
  const FrontierAction a = e.Tick(&done, kLayer, {1.0, 2.0}, 2.5);
  EXPECT_EQ(a.kind, FrontierAction::Kind::kFinished);
  EXPECT_TRUE(e.finished());
  EXPECT_EQ(e.Tick(&done, kLayer, {1.0, 2.0}, 3.0).kind, FrontierAction::Kind::kNone);
}

}  // namespace
}  // namespace cairn::explore
