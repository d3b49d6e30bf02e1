#include "planner/navigator.h"

#include <algorithm>
#include <limits>
#include <random>

#include <gtest/gtest.h>

#include "planner/global/global_planner.h"
#include "tests/unit/planner/test_maps.h"

namespace cairn::planner {
namespace {

using common::Pose2;
using common::Vector2;
using testing::PioneerFootprint;
using testing::TestLayer;
using testing::WallWithGap;

// A kinematic robot, a map publisher and a synchronous planner around a Navigator, on fake
// time: every cycle advances 50 ms.
class NavSim {
 public:
  explicit NavSim(std::shared_ptr<const CostMap> map, NavigatorParams params = {},
                  std::vector<Place> places = {}, uint32_t seed = 3,
                  common::RobotProfile profile = testing::PioneerProfile())
      : map_(std::move(map)),
        profile_(std::move(profile)),
        nav_(profile_, params, DwaParams{}, std::move(places)),
        planner_(PlannerParams(seed)) {}

  // Plans as the navigator's defaults make them, but with wall-clock caps far beyond what a
  // plan needs (here and in Run), so that a plan is the same for a seed on a loaded machine.
  static GlobalPlannerParams PlannerParams(uint32_t seed) {
    GlobalPlannerParams p;
    p.seed = seed;
    p.time_budget_s = 60.0;
    p.improvement_time_s = 60.0;
    p.simplify_time_s = 60.0;
    return p;
  }

  // Runs until `done` holds or `seconds` pass; returns whether `done` held.
  bool Run(double seconds, const std::function<bool()>& done = nullptr) {
    const int cycles = static_cast<int>(std::round(seconds / 0.05));
    for (int k = 0; k < cycles; ++k) {
      t_ += 0.05;
      if (feed_pose_) nav_.OnPose(pose_, t_);
      if (feed_map_ && t_ - last_map_s_ >= 0.2 - 1e-9) {
        nav_.OnMap(map_, t_);
        last_map_s_ = t_;
      }
      const StepOutput out = nav_.Step(t_);
      if (out.plan) {
        ++plans_;
        PlanRequest request = out.plan->request;
        request.time_budget_s = 60.0;
        last_plan_ = planner_.Plan(*out.plan->map, request);
        nav_.OnPlanResult(out.plan->request_id, last_plan_, t_);
      }
      if (out.clear_short_term) ++clears_;
      events_.insert(events_.end(), out.events.begin(), out.events.end());
      if (out.status_changed && (states_.empty() || states_.back() != nav_.status().state)) {
        states_.push_back(nav_.status().state);
        if (getenv("NAV_DEBUG"))
          printf("t=%.2f %s %s %s\n", t_, NavStateName(nav_.status().state),
                 NavReasonName(nav_.status().reason), nav_.status().message.c_str());
      }
      if (out.command) {
        const Velocity v = *out.command;
        if (out.emergency_stop) {
          ++emergency_stops_;
          EXPECT_EQ(v.linear_mps, 0.0);
          EXPECT_EQ(v.angular_radps, 0.0);
        } else {
          EXPECT_TRUE(nav_.limits().Allows(last_sent_, v, 0.05, 1e-9))
              << "t=" << t_ << ": (" << last_sent_.linear_mps << ", " << last_sent_.angular_radps
              << ") -> (" << v.linear_mps << ", " << v.angular_radps << ")";
        }
        last_sent_ = v;
        ++commands_;
        if (!stuck_) {
          pose_.x_m += v.linear_mps * 0.05 * std::cos(pose_.yaw_rad);
          pose_.y_m += v.linear_mps * 0.05 * std::sin(pose_.yaw_rad);
          pose_.yaw_rad = common::WrapAngle(pose_.yaw_rad + v.angular_radps * 0.05);
        }
      }
      if (check_collisions_) {
        EXPECT_TRUE(map_->IsValid(pose_)) << "collision at t=" << t_;
      }
      if (getenv("NAV_DEBUG") && (k % 20 == 0 || getenv("NAV_DEBUG_ALL"))) {
        printf("  t=%.1f pose (%.2f, %.2f, %.2f) cmd (%.2f, %.2f)\n", t_, pose_.x_m, pose_.y_m,
               pose_.yaw_rad, last_sent_.linear_mps, last_sent_.angular_radps);
      }
      if (done && done()) return true;
    }
    return false;
  }
  bool RunUntilState(double seconds, NavState state) {
    return Run(seconds, [&] { return nav_.status().state == state; });
  }

  std::shared_ptr<const CostMap> map_;
  common::RobotProfile profile_;
  Navigator nav_;
  GlobalPlanner planner_;
  Pose2 pose_{2.0, 2.0, 0.0};
  double t_{0.0};
  double last_map_s_{-1.0};
  bool feed_pose_{true};
  bool feed_map_{true};
  bool stuck_{false};
  bool check_collisions_{true};
  Velocity last_sent_;
  PlanResult last_plan_;
  int plans_{0};
  int clears_{0};
  int commands_{0};
  int emergency_stops_{0};
  std::vector<NavState> states_;
  std::vector<std::string> events_;
};

NavGoal PoseGoal(double x, double y, int64_t id = 1) {
  NavGoal g;
  g.id = id;
  g.pose = {x, y, 0.0};
  return g;
}

// Seed 004's explore first: with unknown cells blocking and only the start's surroundings
// known, the robot holds still (zero commands) and says it waits; once the map shows the way it
// goes, and says after how long.
// 20 x 10 m at 0.1 m, unknown but for the known free cells x 0..x1, y 0..y1.
TestLayer KnownOnly(double x1, double y1) {
  TestLayer layer(200, 100, 0.1, std::numeric_limits<float>::quiet_NaN());
  layer.Rect(0.0, 0.0, x1, y1, 0.0f);
  return layer;
}

TEST(NavigatorTest, ExploreFirstHoldsStillUntilTheMapShowsAWay) {
  const TestLayer start_only = KnownOnly(4.0, 4.0);
  NavigatorParams params;
  params.wait_for_map_s = 60.0;
  NavSim sim(start_only.Build(PioneerFootprint()), params);
  sim.nav_.SetGoal(PoseGoal(18.0, 2.0), 0.0);
  sim.Run(10.0);
  EXPECT_EQ(sim.nav_.status().state, NavState::kPlanning) << sim.nav_.status().message;
  EXPECT_EQ(sim.pose_.position(), Vector2(2.0, 2.0));
  EXPECT_EQ(sim.last_sent_.linear_mps, 0.0);
  EXPECT_GE(sim.plans_, 5);  // tried again, once per min_replan_interval_s
  const auto said = [&](const std::string& text) {
    return std::any_of(sim.events_.begin(), sim.events_.end(),
                       [&](const std::string& e) { return e.find(text) != std::string::npos; });
  };
  EXPECT_TRUE(said("explore first: waiting for the map"));
  sim.map_ = TestLayer(200, 100, 0.1).Build(PioneerFootprint());  // all shown, all free
  ASSERT_TRUE(sim.RunUntilState(120.0, NavState::kReached)) << sim.nav_.status().message;
  EXPECT_TRUE(said("explore first: the map showed a way after"));
}

TEST(NavigatorTest, ExploreFirstGivesUpAfterItsWait) {
  const TestLayer start_only = KnownOnly(4.0, 4.0);
  NavigatorParams params;
  params.wait_for_map_s = 3.0;
  params.recovery.sequence.clear();
  NavSim sim(start_only.Build(PioneerFootprint()), params);
  sim.nav_.SetGoal(PoseGoal(18.0, 2.0), 0.0);
  ASSERT_TRUE(sim.RunUntilState(20.0, NavState::kFailed));
  EXPECT_GT(sim.t_, 3.0);
  EXPECT_EQ(sim.pose_.position(), Vector2(2.0, 2.0));
}

// Approach through known space: the goal lies beyond what the map shows; the robot drives
// through known cells only to the known pose nearest the goal, and on to the goal once the map
// shows it.
TEST(NavigatorTest, ApproachesThroughKnownSpaceThenReachesTheGoal) {
  const TestLayer corridor = KnownOnly(12.0, 4.0);
  NavigatorParams params;
  params.wait_for_map_s = 60.0;
  params.approach_through_known = true;
  NavSim sim(corridor.Build(PioneerFootprint()), params);  // collisions (unknown) checked
  sim.nav_.SetGoal(PoseGoal(18.0, 2.0), 0.0);
  sim.Run(60.0);
  EXPECT_GT(sim.pose_.x_m, 9.0) << "it did not go through the known corridor";
  EXPECT_LT(sim.pose_.x_m, 12.0);
  EXPECT_NE(sim.nav_.status().state, NavState::kFailed) << sim.nav_.status().message;
  sim.map_ = TestLayer(200, 100, 0.1).Build(PioneerFootprint());
  ASSERT_TRUE(sim.RunUntilState(120.0, NavState::kReached)) << sim.nav_.status().message;
  EXPECT_LT((sim.pose_.position() - Vector2(18.0, 2.0)).norm(), 0.5);
  EXPECT_TRUE(std::any_of(sim.events_.begin(), sim.events_.end(), [](const std::string& e) {
    return e.find("approach: the map shows no way to the goal yet") != std::string::npos;
  }));
}

TEST(NavigatorTest, ReachesAGoalThroughTheGap) {
  NavSim sim(WallWithGap().Build(PioneerFootprint()));
  sim.nav_.SetGoal(PoseGoal(18.0, 2.0), 0.0);
  ASSERT_TRUE(sim.RunUntilState(200.0, NavState::kReached)) << sim.nav_.status().message;
  EXPECT_LT((sim.pose_.position() - Vector2(18.0, 2.0)).norm(), 0.25 + 0.2);
  EXPECT_EQ(sim.nav_.status().reason, NavReason::kSuccess);
  EXPECT_DOUBLE_EQ(sim.nav_.status().progress, 1.0);
  EXPECT_GT(sim.nav_.status().distance_travelled_m, 16.0);
  EXPECT_EQ(sim.nav_.status().recoveries, 0);
  // After the goal the robot brakes and the navigator falls silent.
  sim.Run(5.0);
  EXPECT_EQ(sim.last_sent_.linear_mps, 0.0);
  const int commands = sim.commands_;
  sim.Run(1.0);
  EXPECT_EQ(sim.commands_, commands);
}

// The kitchen of the apartment world as a laser-only Kobuki sees it: the corridor wall with its
// 0.9 m door, the counter, and the four legs of the table the goal lies under.
TEST(NavigatorTest, AKobukiReachesAGoalAmongTableLegsFromTheCorridor) {
  TestLayer kitchen(240, 140, 0.05);
  kitchen.Rect(0.0, 4.425, 7.05, 4.575, 100.0f).Rect(7.95, 4.425, 12.0, 4.575, 100.0f);
  kitchen.Rect(9.35, 0.0, 10.0, 4.0, 100.0f).Rect(10.0, 0.0, 10.15, 7.0, 100.0f);
  for (const auto& leg :
       {Vector2(7.25, 1.65), Vector2(7.25, 2.35), Vector2(8.35, 1.65), Vector2(8.35, 2.35)}) {
    kitchen.Rect(leg.x() - 0.03, leg.y() - 0.03, leg.x() + 0.03, leg.y() + 0.03, 100.0f);
  }
  common::RobotProfile kobuki = testing::PioneerProfile();
  kobuki.name = "kobuki";
  kobuki.drive = common::DriveKind::kDifferential;
  kobuki.footprint_m = testing::KobukiFootprint();
  kobuki.max_vel_x_mps = 0.5;
  kobuki.min_vel_x_mps = -0.1;
  kobuki.max_vel_theta_radps = 1.5;
  kobuki.acc_lim_x_mps2 = 1.0;
  kobuki.acc_lim_theta_radps2 = 2.0;
  NavSim sim(kitchen.Build(kobuki.footprint_m), {}, {}, 3, kobuki);
  sim.pose_ = {5.0, 5.1, 0.0};
  sim.nav_.SetGoal(PoseGoal(7.675, 1.675), 0.0);
  ASSERT_TRUE(sim.RunUntilState(60.0, NavState::kReached)) << sim.nav_.status().message;
  EXPECT_EQ(sim.nav_.status().recoveries, 0) << sim.nav_.status().message;
}

// The corridor wall of the apartment with its 0.9 m door (x 7.05..7.95) and a path that runs
// along the corridor and turns south through the door 0.25 m off its western frame. A carrot
// 1.2 m along the path lies beyond the corner: the Kobuki's footprint cannot slide straight to
// it, so the carrot comes back along the path until it can (a robot steering at the hidden
// carrot drifts into the frame's cells). In the open corridor the carrot stays at 1.2 m.
TEST(NavigatorTest, TheCarrotComesBackAlongThePathUntilTheRobotSeesIt) {
  TestLayer corridor(240, 140, 0.05);
  corridor.Rect(0.0, 4.425, 7.05, 4.575, 100.0f).Rect(7.95, 4.425, 12.0, 4.575, 100.0f);
  const auto map = corridor.Build(testing::KobukiFootprint());
  std::vector<Pose2> poses;
  for (double x = 5.0; x < 7.3 - 1e-9; x += 0.1) poses.push_back({x, 5.1, 0.0});
  for (double y = 5.1; y > 3.5 - 1e-9; y -= 0.1) poses.push_back({7.3, y, -M_PI / 2});
  const Path path(poses);
  auto sees = [&](const Pose2& from, const Vector2& to) {
    const Vector2 d = to - from.position();
    const double yaw = std::atan2(d.y(), d.x());
    for (double s = 0.18; s <= d.norm(); s += 0.01) {
      const Vector2 p = from.position() + d.normalized() * s;
      if (!map->IsValid({p.x(), p.y(), yaw})) return false;
    }
    return true;
  };
  // Beside the door, 0.2 m off the path towards the wall: the full lookahead is hidden.
  const Pose2 robot{6.75, 4.95, 0.0};
  const double arc = 1.75;
  const Vector2 hidden = path.PoseAt(arc + 1.2).position();
  ASSERT_FALSE(sees(robot, hidden)) << "the scenario must hide the full lookahead";
  const Vector2 carrot = VisibleCarrot(*map, path, robot, arc, 1.2, 0.3);
  EXPECT_TRUE(sees(robot, carrot)) << carrot.transpose();
  const double carrot_arc = path.Project(carrot).arc_length_m;
  EXPECT_LT(carrot_arc, arc + 1.2 - 0.05);
  EXPECT_GE(carrot_arc, arc + 0.3 - 1e-6);
  // Down the open corridor the carrot is the full lookahead.
  const Pose2 open{5.2, 5.1, 0.0};
  EXPECT_EQ(VisibleCarrot(*map, path, open, 0.2, 1.2, 0.3), path.PoseAt(0.2 + 1.2).position());
}

TEST(NavigatorTest, TurnsToTheGoalHeading) {
  TestLayer open(100, 100, 0.1);
  NavSim sim(open.Build(PioneerFootprint()));
  NavGoal g = PoseGoal(6.0, 2.0);
  g.pose.yaw_rad = M_PI / 2;
  g.use_yaw = true;
  g.yaw_tolerance_rad = 0.1;
  sim.nav_.SetGoal(g, 0.0);
  ASSERT_TRUE(sim.RunUntilState(60.0, NavState::kReached)) << sim.nav_.status().message;
  EXPECT_NEAR(common::WrapAngle(sim.pose_.yaw_rad - M_PI / 2), 0.0, 0.1 + 0.05);
}

TEST(NavigatorTest, CancelStopsWithinTheLimits) {
  NavSim sim(WallWithGap().Build(PioneerFootprint()));
  sim.nav_.SetGoal(PoseGoal(18.0, 2.0), 0.0);
  sim.Run(4.0);
  ASSERT_EQ(sim.nav_.status().state, NavState::kDriving);
  ASSERT_GT(sim.last_sent_.linear_mps, 0.2);
  sim.nav_.Cancel(sim.t_);
  EXPECT_EQ(sim.nav_.status().state, NavState::kCancelled);
  EXPECT_EQ(sim.nav_.status().reason, NavReason::kCancelled);
  sim.Run(2.0);
  EXPECT_EQ(sim.last_sent_.linear_mps, 0.0);
  EXPECT_EQ(sim.emergency_stops_, 0);
}

TEST(NavigatorTest, StaleOdometryStopsAtOnceAndResumes) {
  NavSim sim(WallWithGap().Build(PioneerFootprint()));
  sim.nav_.SetGoal(PoseGoal(18.0, 2.0), 0.0);
  sim.Run(4.0);
  ASSERT_GT(sim.last_sent_.linear_mps, 0.2);
  // Odometry stops arriving: within 0.5 s (plus one cycle) the command is an immediate zero.
  sim.feed_pose_ = false;
  const double lost = sim.t_;
  ASSERT_TRUE(sim.Run(1.0, [&] { return sim.emergency_stops_ > 0; }));
  EXPECT_LE(sim.t_ - lost, 0.5 + 0.05 + 1e-9);
  EXPECT_GT(sim.t_ - lost, 0.5 - 1e-9);
  EXPECT_EQ(sim.nav_.status().state, NavState::kStopped);
  EXPECT_EQ(sim.nav_.status().reason, NavReason::kStaleOdom);
  EXPECT_EQ(sim.last_sent_.linear_mps, 0.0);
  // Stopped commands keep coming while stale.
  const int stops = sim.emergency_stops_;
  sim.Run(1.0);
  EXPECT_EQ(sim.emergency_stops_, stops + 20);
  // Fresh odometry again: it resumes driving (accelerating from zero) and arrives.
  sim.feed_pose_ = true;
  ASSERT_TRUE(sim.RunUntilState(1.0, NavState::kDriving));
  ASSERT_TRUE(sim.RunUntilState(200.0, NavState::kReached)) << sim.nav_.status().message;
}

TEST(NavigatorTest, StaleOrMissingMapStops) {
  NavSim sim(WallWithGap().Build(PioneerFootprint()));
  sim.feed_map_ = false;
  sim.nav_.SetGoal(PoseGoal(18.0, 2.0), 0.0);
  sim.Run(0.1);
  EXPECT_EQ(sim.nav_.status().state, NavState::kStopped);
  EXPECT_EQ(sim.nav_.status().reason, NavReason::kNoMap);
  EXPECT_EQ(sim.plans_, 0);
  sim.feed_map_ = true;
  sim.Run(4.0);
  EXPECT_EQ(sim.nav_.status().state, NavState::kDriving);
  sim.feed_map_ = false;
  ASSERT_TRUE(sim.RunUntilState(1.0, NavState::kStopped));
  EXPECT_EQ(sim.nav_.status().reason, NavReason::kStaleMap);
  EXPECT_NE(sim.nav_.status().message.find("cost layer"), std::string::npos);
  // The stop goes out before the layer is 0.5 s old (max_map_age_s), not in the cycle after.
  EXPECT_LE(sim.t_ - sim.last_map_s_, NavigatorParams{}.max_map_age_s + 1e-9);
  EXPECT_GT(sim.t_ - sim.last_map_s_, NavigatorParams{}.max_map_age_s - 0.1);
}

// A layer with tiles missing (their cells lethal, here the tile the robot stands in) holds the
// robot without spending recoveries or failing; the complete layer lets it go on and arrive.
TEST(NavigatorTest, ALayerWithMissingTilesHoldsTheRobotUntilItIsComplete) {
  TestLayer holes = WallWithGap();
  holes.Rect(0.0, 0.0, 4.0, 4.0, 100.0f);  // a missing tile read as lethal
  auto incomplete = std::make_shared<CostMap>(holes.geometry, holes.cost, PioneerFootprint());
  incomplete->set_missing_tiles(1);
  const auto complete = WallWithGap().Build(PioneerFootprint());
  NavSim sim(incomplete);
  sim.check_collisions_ = false;
  sim.nav_.SetGoal(PoseGoal(18.0, 2.0), 0.0);
  sim.Run(5.0);
  EXPECT_EQ(sim.nav_.status().state, NavState::kStopped);
  EXPECT_EQ(sim.nav_.status().reason, NavReason::kNoMap);
  EXPECT_NE(sim.nav_.status().message.find("lacks 1 tiles"), std::string::npos)
      << sim.nav_.status().message;
  EXPECT_EQ(sim.plans_, 0);
  EXPECT_EQ(sim.last_sent_.linear_mps, 0.0);
  sim.map_ = complete;
  sim.check_collisions_ = true;
  ASSERT_TRUE(sim.RunUntilState(200.0, NavState::kReached)) << sim.nav_.status().message;
}

TEST(NavigatorTest, UnknownPlaceFailsAtOnce) {
  NavSim sim(WallWithGap().Build(PioneerFootprint()));
  NavGoal g;
  g.id = 9;
  g.is_place = true;
  g.place = "attic";
  sim.nav_.SetGoal(g, 0.0);
  EXPECT_EQ(sim.nav_.status().state, NavState::kFailed);
  EXPECT_EQ(sim.nav_.status().reason, NavReason::kUnknownPlace);
  EXPECT_EQ(sim.nav_.status().goal_id, 9);
  sim.Run(1.0);
  EXPECT_EQ(sim.plans_, 0);
}

TEST(NavigatorTest, DrivesToAPlace) {
  std::vector<Place> places = {{"east", {{12.0, 0.0}, {20.0, 0.0}, {20.0, 10.0}, {12.0, 10.0}}}};
  NavSim sim(WallWithGap().Build(PioneerFootprint()), {}, places);
  NavGoal g;
  g.is_place = true;
  g.place = "east";
  sim.nav_.SetGoal(g, 0.0);
  ASSERT_TRUE(sim.RunUntilState(200.0, NavState::kReached)) << sim.nav_.status().message;
  // The place resolves to its middle (farthest from the map border and the wall).
  EXPECT_NEAR(sim.pose_.x_m, 15.1, 0.6);
  EXPECT_NEAR(sim.pose_.y_m, 5.0, 0.6);
}

// Seed 001's place goals pick the cell farthest from obstacles on the map of the moment; a
// table first seen on the way in may stand right there. The goal moves to the cell now
// farthest from obstacles, says so once, and the robot arrives clear of the table.
TEST(NavigatorTest, APlaceGoalMovesOffFurnitureSeenOnTheWayIn) {
  std::vector<Place> places = {{"east", {{12.0, 0.0}, {20.0, 0.0}, {20.0, 10.0}, {12.0, 10.0}}}};
  TestLayer layer = WallWithGap();
  NavSim sim(layer.Build(PioneerFootprint()), {}, places);
  NavGoal g;
  g.is_place = true;
  g.place = "east";
  sim.nav_.SetGoal(g, 0.0);
  sim.Run(2.0);
  ASSERT_EQ(sim.nav_.status().state, NavState::kDriving) << sim.nav_.status().message;
  ASSERT_TRUE(sim.events_.empty());
  // A table over the middle of the place, where the goal was resolved.
  layer.Rect(14.0, 3.5, 16.2, 6.5, 100.0f);
  sim.map_ = layer.Build(PioneerFootprint());
  ASSERT_TRUE(sim.RunUntilState(200.0, NavState::kReached)) << sim.nav_.status().message;
  // Said once (replans are events of their own).
  const auto moves = std::count_if(sim.events_.begin(), sim.events_.end(), [](const auto& e) {
    return e.find("place 'east' moves to") != std::string::npos;
  });
  EXPECT_EQ(moves, 1) << ::testing::PrintToString(sim.events_);
  EXPECT_GT(sim.nav_.path().poses().back().position().x(), 12.0);
  EXPECT_GT(sim.map_->ClearanceAt(sim.pose_.position()), 1.0);
}

// A blob on the goal seen from afar (a false step at a grazing angle): the robot heads for the
// nearest free pose by it instead of failing at once. When the approach measures the blob away
// the goal is reached; when it stays, the goal fails GOAL_OCCUPIED once the robot is near, and
// the robot never drives into it.
TEST(NavigatorTest, AGoalBlockedFromAfarIsApproachedAndJudgedNear) {
  for (const bool blob_stays : {false, true}) {
    TestLayer open(200, 100, 0.1);
    TestLayer blocked = open;
    blocked.Rect(14.85, 4.85, 15.15, 5.15, 100.0f);
    NavSim sim(blocked.Build(PioneerFootprint()));
    sim.pose_ = {2.0, 5.0, 0.0};
    sim.nav_.SetGoal(PoseGoal(15.0, 5.0), 0.0);
    ASSERT_TRUE(sim.Run(20.0, [&] { return sim.pose_.x_m > 8.0; })) << sim.nav_.status().message;
    EXPECT_EQ(sim.nav_.status().recoveries, 0) << sim.nav_.status().message;
    if (!blob_stays) sim.map_ = open.Build(PioneerFootprint());  // measured away on the approach
    const bool ended = sim.Run(120.0, [&] {
      const NavState s = sim.nav_.status().state;
      return s == NavState::kReached || s == NavState::kFailed;
    });
    ASSERT_TRUE(ended) << sim.nav_.status().message;
    if (blob_stays) {
      EXPECT_EQ(sim.nav_.status().state, NavState::kFailed);
      EXPECT_EQ(sim.nav_.status().reason, NavReason::kGoalOccupied) << sim.nav_.status().message;
      EXPECT_GT(std::hypot(sim.pose_.x_m - 15.0, sim.pose_.y_m - 5.0), 0.3);
    } else {
      EXPECT_EQ(sim.nav_.status().state, NavState::kReached) << sim.nav_.status().message;
      EXPECT_LT(std::hypot(sim.pose_.x_m - 15.0, sim.pose_.y_m - 5.0), 0.3);
    }
  }
}

TEST(NavigatorTest, ReplansWhenAnObstacleAppearsOnThePath) {
  TestLayer open(200, 100, 0.1);
  NavSim sim(open.Build(PioneerFootprint()));
  sim.pose_ = {2.0, 5.0, 0.0};
  sim.nav_.SetGoal(PoseGoal(18.0, 5.0), 0.0);
  sim.Run(3.0);
  ASSERT_EQ(sim.nav_.status().state, NavState::kDriving);
  const int plans = sim.plans_;
  // A crate appears across the straight route ahead.
  open.Rect(9.0, 3.5, 10.0, 6.5, 100.0f);
  sim.map_ = open.Build(PioneerFootprint());
  ASSERT_TRUE(sim.RunUntilState(200.0, NavState::kReached)) << sim.nav_.status().message;
  EXPECT_GE(sim.nav_.status().replans, 1);
  EXPECT_GT(sim.plans_, plans);
}

TEST(NavigatorTest, PeriodicReplanTakesAClearlyBetterPathOnly) {
  // A wall forces a long detour; then the wall is gone (the map change blocks nothing, so
  // only the periodic replan notices) and the robot switches to the short way.
  TestLayer open(200, 100, 0.1);
  TestLayer walled = open;
  walled.Rect(6.0, 0.0, 6.4, 9.0, 100.0f);
  NavigatorParams p;
  p.replan_period_s = 2.0;
  NavSim sim(walled.Build(PioneerFootprint()), p);
  sim.pose_ = {2.0, 2.0, 0.0};
  sim.nav_.SetGoal(PoseGoal(10.0, 2.0), 0.0);
  sim.Run(1.0);
  ASSERT_EQ(sim.nav_.status().state, NavState::kDriving);
  const double detour = sim.nav_.path().length_m();
  EXPECT_GT(detour, 15.0);
  // An unchanged map: periodic replans find nothing clearly better and keep the path.
  sim.Run(4.5);
  EXPECT_EQ(sim.nav_.status().replans, 0);
  EXPECT_GE(sim.plans_, 3);
  sim.map_ = open.Build(PioneerFootprint());
  ASSERT_TRUE(sim.Run(10.0, [&] { return sim.nav_.status().replans > 0; }));
  EXPECT_LT(sim.nav_.path().length_m(), detour - 5.0);
  ASSERT_TRUE(sim.RunUntilState(100.0, NavState::kReached));
}

TEST(NavigatorTest, NoPathRunsEveryRecoveryThenFails) {
  TestLayer closed = WallWithGap();
  closed.Rect(9.8, 5.9, 10.2, 7.3, 100.0f);
  NavSim sim(closed.Build(PioneerFootprint()));
  sim.nav_.SetGoal(PoseGoal(18.0, 2.0), 0.0);
  ASSERT_TRUE(sim.RunUntilState(120.0, NavState::kFailed)) << sim.nav_.status().message;
  EXPECT_EQ(sim.nav_.status().reason, NavReason::kNoPath);
  // rotate, back_up, wait, clear_short_term: drive_forward only follows a blocked behaviour.
  EXPECT_EQ(sim.nav_.status().recoveries, 4);
  EXPECT_EQ(sim.clears_, 1);
  EXPECT_EQ(sim.plans_, 5);  // the first plan and one after each recovery
  EXPECT_EQ(sim.last_plan_.status, PlanStatus::kNoPath);
  // It never crossed towards the wall.
  EXPECT_LT(sim.pose_.x_m, 9.0);
  const auto recovering = std::count(sim.states_.begin(), sim.states_.end(), NavState::kRecovering);
  EXPECT_EQ(recovering, 4);
}

TEST(NavigatorTest, ABlockedRecoveryHandsOverToTheNextAtOnce) {
  // A pocket just wider than the robot, a wall 5 mm behind it and 0.6 m of room ahead, and a
  // goal outside: no path. Turning and backing up are blocked where it stands, so each hands
  // over to the next behaviour without a plan in between; driving forward is clear and moves it.
  TestLayer layer(200, 100, 0.1);
  layer.Rect(3.0, 3.0, 7.0, 4.7, 100.0f).Rect(3.0, 5.3, 7.0, 7.0, 100.0f);
  layer.Rect(3.0, 3.0, 4.7, 7.0, 100.0f).Rect(6.0, 3.0, 7.0, 7.0, 100.0f);
  NavSim sim(layer.Build(PioneerFootprint()));
  sim.pose_ = {5.02, 5.0, 0.0};
  ASSERT_TRUE(sim.map_->IsValid(sim.pose_));
  sim.nav_.SetGoal(PoseGoal(15.0, 5.0), 0.0);
  ASSERT_TRUE(sim.RunUntilState(120.0, NavState::kFailed)) << sim.nav_.status().message;
  EXPECT_EQ(sim.nav_.status().reason, NavReason::kNoPath);
  EXPECT_EQ(sim.nav_.status().recoveries, 5);
  // The first plan, then one after drive_forward, wait and clear_short_term: none after the
  // two that were blocked (one after each recovery before).
  EXPECT_EQ(sim.plans_, 4);
  EXPECT_GT(sim.pose_.x_m, 5.02 + 0.25);
  EXPECT_NEAR(sim.pose_.y_m, 5.0, 0.02);
  EXPECT_TRUE(sim.map_->IsValid(sim.pose_));
}

TEST(NavigatorTest, NoProgressTriggersRecoveriesAndThenFails) {
  NavigatorParams p;
  p.progress_timeout_s = 3.0;
  NavSim sim(WallWithGap().Build(PioneerFootprint()), p);
  sim.stuck_ = true;  // the wheels spin, the robot does not move
  sim.nav_.SetGoal(PoseGoal(18.0, 2.0), 0.0);
  ASSERT_TRUE(sim.RunUntilState(200.0, NavState::kFailed)) << sim.nav_.status().message;
  EXPECT_EQ(sim.nav_.status().reason, NavReason::kRecoveryExhausted);
  EXPECT_EQ(sim.nav_.status().recoveries, 4);
}

TEST(NavigatorTest, ReplansEverySecondDoNotHoldOffTheNoProgressRecovery) {
  // The robot is stuck and, every second, something shows up on its path 1.5 m ahead: every
  // replan succeeds, yet the robot goes nowhere. The no-progress timer must keep running across
  // those replans.
  NavigatorParams p;
  p.progress_timeout_s = 3.0;
  TestLayer open(200, 100, 0.1);
  NavSim sim(open.Build(PioneerFootprint()), p);
  sim.pose_ = {2.0, 5.0, 0.0};
  sim.stuck_ = true;
  sim.nav_.SetGoal(PoseGoal(18.0, 5.0), 0.0);
  sim.Run(0.5);
  ASSERT_EQ(sim.nav_.status().state, NavState::kDriving);
  double stuck_s = 0.5;
  while (sim.nav_.status().recoveries == 0 && stuck_s < 12.0) {
    if (sim.nav_.status().state == NavState::kDriving && !sim.nav_.path().empty()) {
      const Pose2 ahead = sim.nav_.path().PoseAt(1.5);
      TestLayer flicker = open;
      flicker.Rect(ahead.x_m - 0.2, ahead.y_m - 0.2, ahead.x_m + 0.2, ahead.y_m + 0.2, 100.0f);
      sim.map_ = flicker.Build(PioneerFootprint());
    }
    sim.Run(1.0);
    stuck_s += 1.0;
  }
  EXPECT_GE(sim.nav_.status().replans, 2) << "the map changes did not cause replans";
  EXPECT_GE(sim.nav_.status().recoveries, 1) << "no recovery after " << stuck_s << " s stuck";
  EXPECT_LE(stuck_s, p.progress_timeout_s + 1.5);
}

TEST(NavigatorTest, NewGoalReplacesTheOldOne) {
  NavSim sim(WallWithGap().Build(PioneerFootprint()));
  sim.nav_.SetGoal(PoseGoal(18.0, 2.0, 1), 0.0);
  sim.Run(2.0);
  sim.nav_.SetGoal(PoseGoal(4.0, 8.0, 2), sim.t_);
  ASSERT_TRUE(sim.RunUntilState(100.0, NavState::kReached));
  EXPECT_EQ(sim.nav_.status().goal_id, 2);
  EXPECT_LT((sim.pose_.position() - Vector2(4.0, 8.0)).norm(), 0.5);
}

TEST(NavigatorTest, NoCommandExceedsTheLimitsInRandomSituations) {
  // Property: over many seeded random worlds, goals, stale-input episodes, cancels and new
  // goals, every command but the safety stop is reachable from the previous one within the
  // profile's limits (checked inside NavSim::Run for every command).
  std::mt19937 rng(99);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int reached = 0;
  for (int world = 0; world < 12; ++world) {
    TestLayer layer(120, 120, 0.1);
    for (int k = 0; k < 8; ++k) {
      const double x = 2.0 + u(rng) * 9.0, y = 2.0 + u(rng) * 9.0;
      layer.Rect(x, y, x + 0.3 + u(rng) * 1.5, y + 0.3 + u(rng) * 1.5, k % 3 ? 100.0f : 60.0f);
    }
    layer.Rect(0.0, 0.0, 1.2, 1.2, 0.0f);
    NavSim sim(layer.Build(PioneerFootprint()), {}, {}, 1 + world);
    sim.pose_ = {0.6, 0.6, u(rng) * 2 * M_PI};
    sim.check_collisions_ = false;  // random goals may sit in graded or tight spots
    sim.nav_.SetGoal(PoseGoal(1.0 + u(rng) * 10.0, 1.0 + u(rng) * 10.0), 0.0);
    for (int episode = 0; episode < 6; ++episode) {
      sim.Run(2.0 + u(rng) * 4.0);
      const double r = u(rng);
      if (r < 0.2) {
        sim.feed_pose_ = false;
        sim.Run(0.3 + u(rng));
        sim.feed_pose_ = true;
      } else if (r < 0.35) {
        sim.feed_map_ = false;
        sim.Run(0.3 + u(rng));
        sim.feed_map_ = true;
      } else if (r < 0.45) {
        sim.nav_.Cancel(sim.t_);
      } else if (r < 0.6) {
        sim.nav_.SetGoal(PoseGoal(1.0 + u(rng) * 10.0, 1.0 + u(rng) * 10.0, episode + 2), sim.t_);
      }
    }
    reached += sim.RunUntilState(60.0, NavState::kReached);
  }
  EXPECT_GT(reached, 0);
}

}  // namespace
}  // namespace cairn::planner
