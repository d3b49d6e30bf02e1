#include "planner/local/dwa_planner.h"

#include <algorithm>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "planner/local/critic_registry.h"
#include "planner/recovery.h"
#include "tests/unit/planner/local/door_scene.h"
#include "tests/unit/planner/test_maps.h"

namespace cairn::planner {
namespace {

using common::Pose2;
using common::Vector2;
using testing::PioneerFootprint;
using testing::TestLayer;

VelocityLimits Limits() { return VelocityLimits::FromProfile(testing::PioneerProfile()); }

DwaInput Input(const CostMap& map, const Path& path, const Pose2& pose, const Velocity& last,
               const Vector2& goal) {
  DwaInput in;
  in.map = &map;
  in.pose = pose;
  in.last_command = last;
  in.path = &path;
  in.segment_begin = 0;
  in.segment_end = path.size();
  in.local_goal = goal;
  return in;
}

TEST(DwaPlannerTest, FollowsAStraightPathAtSpeed) {
  TestLayer layer(100, 60, 0.1);
  const auto map = layer.Build(PioneerFootprint());
  const Path path({{1.0, 3.0, 0.0}, {9.0, 3.0, 0.0}});
  DwaPlanner dut(Limits(), {});
  Velocity last;
  Pose2 pose{1.0, 3.0, 0.0};
  for (int k = 0; k < 40; ++k) {
    const DwaResult r = dut.Compute(Input(*map, path, pose, last, {pose.x_m + 1.2, 3.0}));
    ASSERT_TRUE(r.found);
    ASSERT_TRUE(Limits().Allows(last, r.command, 0.05, 1e-12));
    dut.Commit(r.command, pose);
    last = r.command;
  }
  EXPECT_NEAR(last.linear_mps, 0.5, 1e-9);
  EXPECT_NEAR(last.angular_radps, 0.0, 0.08);
  EXPECT_EQ(dut.critic_names().size(), 5u);
}

TEST(DwaPlannerTest, SlowsForAnObstacleAheadAndCountsRejections) {
  TestLayer layer(100, 60, 0.1);
  layer.Rect(1.55, 2.5, 1.9, 3.5, 100.0f);  // a block from x = 1.5
  const auto map = layer.Build(PioneerFootprint());
  const Path path({{1.0, 3.0, 0.0}, {9.0, 3.0, 0.0}});
  DwaPlanner dut(Limits(), {});
  // From 0.3 m/s the window is [0.26, 0.34] m/s; the front is 0.155 m from the block, which
  // the fastest samples reach before they could stop: the clearance critic rejects them.
  const Velocity last{0.3, 0.0};
  const DwaResult r = dut.Compute(Input(*map, path, {1.03, 3.0, 0.0}, last, {2.0, 3.0}));
  ASSERT_TRUE(r.found);
  const size_t clearance = 4;
  ASSERT_EQ(dut.critic_names()[clearance], "clearance");
  EXPECT_GT(r.rejections[clearance], 0);
  EXPECT_EQ(dut.rejection_counts()[clearance], r.rejections[clearance]);
  EXPECT_LT(r.valid, r.samples);
  EXPECT_LT(r.command.linear_mps, 0.34 - 1e-6);
  // The first poses of the chosen trajectory (its braking distance) are collision-free.
  EXPECT_TRUE(map->IsValid(r.best.poses.front()));
  dut.Reset();
  EXPECT_EQ(dut.rejection_counts()[clearance], 0);
  // Driving on from there, the robot stops short of the block without touching it.
  Velocity v = r.command;
  Pose2 pose{1.03, 3.0, 0.0};
  for (int k = 0; k < 100; ++k) {
    pose.x_m += v.linear_mps * 0.05 * std::cos(pose.yaw_rad);
    pose.y_m += v.linear_mps * 0.05 * std::sin(pose.yaw_rad);
    pose.yaw_rad = common::WrapAngle(pose.yaw_rad + v.angular_radps * 0.05);
    ASSERT_TRUE(map->IsValid(pose)) << "cycle " << k;
    const DwaResult next = dut.Compute(Input(*map, path, pose, v, {2.0, 3.0}));
    dut.Commit(next.command, pose);
    v = next.command;
  }
  EXPECT_NEAR(v.linear_mps, 0.0, 0.05);
}

TEST(DwaPlannerTest, BrakesWhenNothingIsValid) {
  TestLayer layer(60, 60, 0.1);
  layer.Rect(0.0, 0.0, 6.0, 6.0, 100.0f)
      .Rect(2.6, 2.7, 3.4, 3.3, 0.0f);  // a tight box of free cells
  const auto map = layer.Build(PioneerFootprint());
  const Path path({{3.0, 3.0, 0.0}, {5.0, 3.0, 0.0}});
  // The window holds only speeds near 0.3 m/s, all blocked. (Path tracking would find its ramp
  // down to a stop inside the box valid, which is what braking does.)
  DwaParams params;
  params.path_tracking = false;
  DwaPlanner dut(Limits(), params);
  const Velocity last{0.3, 0.2};
  const DwaResult r = dut.Compute(Input(*map, path, {3.0, 3.0, 0.0}, last, {4.0, 3.0}));
  EXPECT_FALSE(r.found);
  EXPECT_EQ(r.valid, 0);
  EXPECT_NEAR(r.command.linear_mps, 0.3 - 0.04, 1e-12);
  EXPECT_NEAR(r.command.angular_radps, 0.2 - 0.075, 1e-12);
}

TEST(DwaPlannerTest, EscapesWhenTheMapPutsAnObstacleUnderTheRobot) {
  // A wall appeared under the robot's front (its cells reach 0.085 m past the bumper): with
  // the goal behind, the robot backs away instead of finding every trajectory blocked; driving
  // deeper into the wall stays blocked.
  TestLayer layer(100, 60, 0.1);
  layer.Rect(1.25, 0.0, 1.6, 6.0, 100.0f);
  const auto map = layer.Build(PioneerFootprint());
  const Pose2 pose{1.0, 3.0, 0.0};
  ASSERT_FALSE(map->IsValid(pose));
  const Path path({{1.0, 3.0, M_PI}, {-0.0, 3.0, M_PI}});
  DwaPlanner dut(Limits(), {});
  const DwaResult r = dut.Compute(Input(*map, path, pose, {0.0, 0.0}, {0.2, 3.0}));
  ASSERT_TRUE(r.found);
  EXPECT_LT(r.command.linear_mps, 0.0);
  // Recovery motions may move away too, not deeper.
  EXPECT_TRUE(MotionClear(map.get(), pose, {-0.1, 0.0}, 0.5));
  EXPECT_FALSE(MotionClear(map.get(), pose, {0.3, 0.0}, 0.5));
}

TEST(DwaPlannerTest, OscillationAloneNeverStallsTheRobot) {
  // The robot turned left, then right (one reversal), and is turning left fast again: the
  // whole window turns left, so the oscillation critic rejects every sample. Rather than stall,
  // the planner clears that memory and drives the best of them.
  TestLayer layer(100, 100, 0.1);
  const auto map = layer.Build(PioneerFootprint());
  const Path path({{5.0, 5.0, 0.0}, {5.0, 9.0, 0.0}});
  DwaParams params;
  params.path_tracking = false;  // tracking the path north would be a way out of the memory
  DwaPlanner dut(Limits(), params);
  const Pose2 pose{5.0, 5.0, 0.0};
  dut.Commit({0.0, 0.3}, pose);
  dut.Commit({0.0, -0.3}, pose);
  const DwaResult r = dut.Compute(Input(*map, path, pose, {0.0, 0.5}, {5.0, 6.2}));
  EXPECT_EQ(r.valid, 0);
  EXPECT_EQ(r.rejections[1], r.samples);  // "oscillation"
  EXPECT_TRUE(r.found);
  EXPECT_TRUE(r.oscillation_reset);
  EXPECT_GT(r.command.angular_radps, 0.4);
}

// Closed loop at 20 Hz with the navigator's carrot (1.2 m ahead) and path window (3 m), from rest
// at `pose` until `done`; the cycles that took, or -1 (400 cycles, or a collision).
int Drive(const testing::KobukiDoorScene& scene, const DwaParams& params, const CostMap& on,
          Pose2 pose, const Path& path, const std::function<bool(const Pose2&)>& done,
          Pose2* end = nullptr) {
  const VelocityLimits& kobuki = scene.kobuki;
  DwaPlanner dut(kobuki, params);
  Velocity last;
  int k = 0;
  for (; k < 400 && !done(pose); ++k) {
    const auto proj = path.Project(pose.position());
    DwaInput in = Input(on, path, pose, last,
                        path.PoseAt(std::min(path.length_m(), proj.arc_length_m + 1.2)).position());
    in.segment_begin = proj.segment;
    in.segment_end = path.IndexAt(proj.arc_length_m + 3.0);
    const DwaResult r = dut.Compute(in);
    EXPECT_TRUE(kobuki.Allows(last, r.command, 0.05, 1e-12)) << "cycle " << k;
    dut.Commit(r.command, pose);
    pose.x_m += r.command.linear_mps * 0.05 * std::cos(pose.yaw_rad);
    pose.y_m += r.command.linear_mps * 0.05 * std::sin(pose.yaw_rad);
    pose.yaw_rad = common::WrapAngle(pose.yaw_rad + r.command.angular_radps * 0.05);
    if (!on.IsValid(pose)) {
      ADD_FAILURE() << "touched an obstacle at cycle " << k << ", (" << pose.x_m << ", " << pose.y_m
                    << ")";
      k = 400;
      break;
    }
    last = r.command;
  }
  if (end != nullptr) *end = pose;
  return k < 400 ? k : -1;
}

// A critic from outside the shipped set, registered through the seam: it refuses turning left
// faster than `max_left_radps` and charges the yaw rate otherwise.
class NoLeftTurnCritic : public TrajectoryCritic {
 public:
  NoLeftTurnCritic(double scale, double max_left_radps)
      : TrajectoryCritic("no_left_turn", scale), max_left_radps_(max_left_radps) {}
  Score Evaluate(const Trajectory& t) const override {
    if (t.target.angular_radps > max_left_radps_) return {false, 0.0};
    return {true, std::abs(t.target.angular_radps)};
  }

 private:
  double max_left_radps_;
};

CriticRegistry WithNoLeftTurn() {
  CriticRegistry registry = BuiltinCritics();
  registry.Add("no_left_turn", [](const CriticConfig& c, const CriticSetup&) {
    CriticParamReader reader(c);
    double max_left_radps = 0.0;
    reader.Get("max_left_radps", &max_left_radps);
    reader.Finish();
    return std::make_unique<NoLeftTurnCritic>(c.scale, max_left_radps);
  });
  return registry;
}

TEST(DwaPlannerTest, ACriticRegisteredThroughTheSeamScoresAndRejects) {
  // The robot drives east at 0.3 m/s; the carrot lies to its left (north).
  TestLayer layer(100, 100, 0.1);
  const auto map = layer.Build(PioneerFootprint());
  const Path path({{5.0, 5.0, M_PI / 2}, {5.0, 9.0, M_PI / 2}});
  const Pose2 pose{5.0, 5.0, 0.0};
  const Velocity last{0.3, 0.0};
  DwaParams plain;
  plain.path_tracking = false;
  DwaPlanner shipped(Limits(), plain);
  ASSERT_GT(shipped.Compute(Input(*map, path, pose, last, {5.0, 6.2})).command.angular_radps, 0.0)
      << "the shipped critics turn left towards the carrot";

  DwaParams params = plain;
  params.critics.insert(params.critics.begin(), {"no_left_turn", 2.0, {{"max_left_radps", 0.0}}});
  DwaPlanner dut(Limits(), params, WithNoLeftTurn());
  ASSERT_EQ(dut.critic_names().size(), 6u);
  EXPECT_EQ(dut.critic_names()[0], "no_left_turn");
  EXPECT_EQ(dut.critic_names()[5], "clearance");
  const DwaResult r = dut.Compute(Input(*map, path, pose, last, {5.0, 6.2}));
  ASSERT_TRUE(r.found);
  EXPECT_LE(r.command.angular_radps, 0.0);
  // It rejected exactly the samples turning left, and its rejections are counted under it.
  int left = 0;
  for (const Velocity& v : dut.generator().Samples(last)) left += v.angular_radps > 0.0;
  ASSERT_GT(left, 0);
  EXPECT_EQ(r.rejections[0], left);
  EXPECT_EQ(dut.rejection_counts()[0], left);
  EXPECT_EQ(r.valid, r.samples - left);
  // Its value joined the sum with its scale.
  EXPECT_DOUBLE_EQ(r.best_values[0], 2.0 * std::abs(r.best.target.angular_radps));
  // An unknown critic is refused by name, and so is a key the critic does not read.
  params.critics[0].name = "no_right_turn";
  EXPECT_THROW(DwaPlanner(Limits(), params, WithNoLeftTurn()), std::invalid_argument);
  params.critics[0] = {"no_left_turn", 2.0, {{"max_left_degps", 0.0}}};
  EXPECT_THROW(DwaPlanner(Limits(), params, WithNoLeftTurn()), std::invalid_argument);
}

TEST(DwaPlannerTest, CriticsScoreInTheConfiguredOrder) {
  // Clearance first instead of last: the rejection counts follow the list, and the scene where
  // the path-tracking fallback (which reads the clearance critic) matters still drives through.
  DwaParams params;
  std::reverse(params.critics.begin(), params.critics.end());
  params.FindCritic("clearance")->params["inflation_m"] = 0.15;  // config/navigator/apartment.yaml
  const testing::KobukiDoorScene scene;
  DwaPlanner dut(scene.kobuki, params);
  ASSERT_EQ(dut.critic_names(), (std::vector<std::string>{"clearance", "path_align", "goal_dist",
                                                          "oscillation", "speed"}));
  const int cycles = Drive(scene, params, *scene.map, {7.36, 5.46, 0.60}, testing::DoorPath(),
                           [](const Pose2& p) { return p.y_m >= 6.3; });
  EXPECT_GT(cycles, 0);
  EXPECT_LT(cycles, 300);
  // Per-critic rejections are the same whatever the order.
  TestLayer layer(100, 60, 0.1);
  layer.Rect(1.55, 2.5, 1.9, 3.5, 100.0f);
  const auto map = layer.Build(PioneerFootprint());
  const Path path({{1.0, 3.0, 0.0}, {9.0, 3.0, 0.0}});
  const DwaInput in = Input(*map, path, {1.03, 3.0, 0.0}, {0.3, 0.0}, {2.0, 3.0});
  DwaPlanner forward(Limits(), {});
  DwaPlanner backward(Limits(), params);
  const DwaResult a = forward.Compute(in);
  const DwaResult b = backward.Compute(in);
  EXPECT_GT(b.rejections[0], 0);
  EXPECT_EQ(a.rejections[4], b.rejections[0]);
  EXPECT_EQ(a.samples, b.samples);
}

TEST(DwaPlannerTest, ThreadsADoorBesideTheWallFromRestByTrackingThePath) {
  const testing::KobukiDoorScene scene;
  const Pose2 start{7.36, 5.46, 0.60};
  const auto through = [](const Pose2& p) { return p.y_m >= 6.3; };
  DwaParams params;
  params.FindCritic("clearance")->params["inflation_m"] = 0.15;  // config/navigator/apartment.yaml
  const int cycles = Drive(scene, params, *scene.map, start, testing::DoorPath(), through);
  EXPECT_GT(cycles, 0);
  EXPECT_LT(cycles, 300);
  // Without the tracking candidates, for the record: the dynamic window stands still.
  params.path_tracking = false;
  EXPECT_EQ(Drive(scene, params, *scene.map, start, testing::DoorPath(), through), -1);
}

// The apartment's kitchen as a laser-only Kobuki saw it: the global path bends around a table
// leg a few centimetres off the footprint, the goal just past the leg, the robot at rest. The
// window's creeping arcs gained less than they cost and it stood beside the leg until its
// recoveries ran out; tracking the bend, it arrives without touching the leg.
TEST(DwaPlannerTest, FollowsAPathBentCloseAroundATableLegFromRest) {
  const testing::KobukiDoorScene scene;
  TestLayer layer(60, 60, 0.05, 0.0f, Pose2{6.0, 0.5, 0.0});
  layer.Rect(7.2, 1.6, 7.3, 1.7, 100.0f);  // the leg (2 x 2 cells)
  const auto map = layer.Build(scene.round);
  DwaParams params;
  params.FindCritic("clearance")->params["inflation_m"] = 0.15;  // config/navigator/apartment.yaml
  const Path path(
      {{6.92, 1.75, 0.55}, {7.15, 1.91, 0.2}, {7.40, 1.93, -0.3}, {7.675, 1.675, -0.75}});
  const Vector2 goal{7.675, 1.675};
  const auto arrived = [&](const Pose2& p) { return (p.position() - goal).norm() <= 0.2; };
  const Pose2 start{6.92, 1.75, 0.39};
  Pose2 end;
  EXPECT_GT(Drive(scene, params, *map, start, path, arrived, &end), 0)
      << "stopped at (" << end.x_m << ", " << end.y_m << ")";
  params.path_tracking = false;  // the window alone, for the record
  EXPECT_EQ(Drive(scene, params, *map, start, path, arrived), -1);
}

TEST(DwaPlannerTest, CommandsNeverExceedTheLimitsInRandomSituations) {
  // Property: over many seeded random maps, poses, paths and previous commands, every command
  // (found or braking) is reachable from the previous one and inside the velocity limits.
  std::mt19937 rng(2024);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const VelocityLimits limits = Limits();
  DwaPlanner dut(limits, {});
  int found = 0;
  for (int m = 0; m < 40; ++m) {
    TestLayer layer(80, 80, 0.1);
    for (int k = 0; k < 12; ++k) {
      const double x = u(rng) * 8.0, y = u(rng) * 8.0;
      layer.Rect(x, y, x + u(rng) * 1.5, y + u(rng) * 1.5,
                 k % 4 == 0 ? NAN : (k % 2 ? 100.0f : 60.0f));
    }
    const auto map = layer.Build(PioneerFootprint());
    Pose2 pose{1.0 + u(rng) * 6.0, 1.0 + u(rng) * 6.0, (u(rng) - 0.5) * 2 * M_PI};
    const Path path({pose, {u(rng) * 8.0, u(rng) * 8.0, 0.0}});
    Velocity last{limits.min_vel_x_mps + u(rng) * (limits.max_vel_x_mps - limits.min_vel_x_mps),
                  (u(rng) - 0.5) * 2 * limits.max_vel_theta_radps};
    dut.Reset();
    for (int k = 0; k < 25; ++k) {
      const DwaResult r =
          dut.Compute(Input(*map, path, pose, last, path.poses().back().position()));
      found += r.found;
      ASSERT_TRUE(limits.Allows(last, r.command, 0.05, 1e-12))
          << "map " << m << " cycle " << k << ": (" << last.linear_mps << ", " << last.angular_radps
          << ") -> (" << r.command.linear_mps << ", " << r.command.angular_radps << ")";
      dut.Commit(r.command, pose);
      // Move the robot along the command for one period.
      const Velocity v = r.command;
      pose.x_m += v.linear_mps * 0.05 * std::cos(pose.yaw_rad);
      pose.y_m += v.linear_mps * 0.05 * std::sin(pose.yaw_rad);
      pose.yaw_rad = common::WrapAngle(pose.yaw_rad + v.angular_radps * 0.05);
      last = v;
    }
  }
  EXPECT_GT(found, 100);
}

}  // namespace
}  // namespace cairn::planner

namespace cairn::planner {
namespace {

// Driving along a path up an 8 cm step the Pioneer may only drive down
// (testing::OneWayStepCorridor, step at x = 6): the DWA closes in and stops short of it, never
// choosing a trajectory that climbs, and the clearance critic counts the rejections. Down the
// same step it drives on.
TEST(DwaPlannerTest, NeverClimbsAOneWayStep) {
  const auto map = testing::OneWayStepCorridor().Build(testing::PioneerFootprint());
  const VelocityLimits limits = VelocityLimits::FromProfile(testing::PioneerProfile());
  for (const bool up : {true, false}) {
    SCOPED_TRACE(up ? "up" : "down");
    const double dir = up ? 1.0 : -1.0;
    const Path path(
        {{6.0 - 1.5 * dir, 2.0, up ? 0.0 : M_PI}, {6.0 + 3.0 * dir, 2.0, up ? 0.0 : M_PI}});
    DwaPlanner dut(limits, {});
    common::Pose2 pose = path.poses().front();
    common::Velocity last;
    for (int k = 0; k < 120; ++k) {
      DwaInput in;
      in.map = map.get();
      in.pose = pose;
      in.last_command = last;
      in.path = &path;
      in.segment_end = path.size();
      in.local_goal = {pose.x_m + 1.2 * dir, 2.0};
      const DwaResult r = dut.Compute(in);
      if (!r.found) break;
      common::Pose2 previous = pose;
      for (const common::Pose2& p : r.best.poses) {
        ASSERT_TRUE(map->MotionAllowed(previous, p)) << "cycle " << k;
        previous = p;
      }
      dut.Commit(r.command, pose);
      last = r.command;
      // Drive the command for one control period (50 ms).
      const double dt = 0.05;
      pose.yaw_rad += 0.5 * r.command.angular_radps * dt;
      pose.x_m += r.command.linear_mps * dt * std::cos(pose.yaw_rad);
      pose.y_m += r.command.linear_mps * dt * std::sin(pose.yaw_rad);
      pose.yaw_rad += 0.5 * r.command.angular_radps * dt;
    }
    const auto clearance =
        std::find(dut.critic_names().begin(), dut.critic_names().end(), std::string("clearance"));
    ASSERT_NE(clearance, dut.critic_names().end());
    const int64_t rejected = dut.rejection_counts()[clearance - dut.critic_names().begin()];
    if (up) {
      EXPECT_LT(pose.x_m + 0.315, 6.0) << "stopped below the step";
      EXPECT_GT(pose.x_m, 5.0) << "after closing in";
      EXPECT_GT(rejected, 0);
    } else {
      EXPECT_LT(pose.x_m, 5.0) << "drove down the step";
    }
  }
}

}  // namespace
}  // namespace cairn::planner
