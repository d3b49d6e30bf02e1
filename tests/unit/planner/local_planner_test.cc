#include <functional>
#include <random>

#include <gtest/gtest.h>

#include "planner/local/critics.h"
#include "planner/local/dwa_planner.h"
#include "planner/local/trajectory_generator.h"
#include "planner/recovery.h"
#include "tests/unit/planner/test_maps.h"

namespace cairn::planner {
namespace {

using common::Pose2;
using common::Vector2;
using testing::PioneerFootprint;
using testing::TestLayer;

VelocityLimits Limits() { return VelocityLimits::FromProfile(testing::PioneerProfile()); }

TEST(TrajectoryGeneratorTest, WindowRespectsAccelerationAndVelocityLimits) {
  const TrajectoryGenerator gen(Limits(), {});
  // From rest: one 50 ms period reaches 0.04 m/s and 0.075 rad/s.
  DynamicWindow w = gen.Window({0.0, 0.0});
  EXPECT_NEAR(w.min_linear_mps, -0.04, 1e-12);
  EXPECT_NEAR(w.max_linear_mps, 0.04, 1e-12);
  EXPECT_NEAR(w.min_angular_radps, -0.075, 1e-12);
  EXPECT_NEAR(w.max_angular_radps, 0.075, 1e-12);
  // Near the top speed the window is clipped to the limit.
  w = gen.Window({0.49, 0.98});
  EXPECT_NEAR(w.max_linear_mps, 0.5, 1e-12);
  EXPECT_NEAR(w.max_angular_radps, 1.0, 1e-12);
  // Reverse stops at min_vel_x.
  w = gen.Window({-0.19, 0.0});
  EXPECT_NEAR(w.min_linear_mps, -0.2, 1e-12);
  // Every sample is reachable from the last command, for many random last commands.
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> v(-0.2, 0.5), om(-1.0, 1.0);
  for (int t = 0; t < 500; ++t) {
    const Velocity last{v(rng), om(rng)};
    const auto samples = gen.Samples(last);
    ASSERT_EQ(samples.size(), 400u) << last.linear_mps << " " << last.angular_radps;
    for (const Velocity& s : samples) {
      ASSERT_TRUE(gen.limits().Allows(last, s, 0.05, 1e-12))
          << "from (" << last.linear_mps << ", " << last.angular_radps << ") to (" << s.linear_mps
          << ", " << s.angular_radps << ")";
    }
    ASSERT_TRUE(gen.limits().Allows(last, gen.Brake(last), 0.05, 1e-12));
  }
}

TEST(TrajectoryGeneratorTest, SamplesIncludeStopAndStraight) {
  const TrajectoryGenerator gen(Limits(), {});
  const auto samples = gen.Samples({0.02, -0.03});
  bool stop = false, straight = false;
  for (const Velocity& s : samples) {
    stop = stop || (s.linear_mps == 0.0 && s.angular_radps == 0.0);
    straight = straight || (s.linear_mps > 0.05 && s.angular_radps == 0.0);
  }
  EXPECT_TRUE(stop);
  EXPECT_TRUE(straight);
  TrajectoryGeneratorParams p;
  p.vx_samples = 3;
  p.vtheta_samples = 5;
  EXPECT_EQ(TrajectoryGenerator(Limits(), p).Samples({0.3, 0.0}).size(), 15u);
  p.vx_samples = 0;
  EXPECT_THROW(TrajectoryGenerator(Limits(), p), std::invalid_argument);
}

TEST(TrajectoryGeneratorTest, SimulatesConstantVelocityArcs) {
  const TrajectoryGenerator gen(Limits(), {});
  Trajectory t;
  gen.Simulate({1.0, 2.0, M_PI / 2}, {0.5, 0.0}, &t);
  ASSERT_EQ(t.poses.size(), 17u);
  EXPECT_NEAR(t.poses.back().x_m, 1.0, 1e-9);
  EXPECT_NEAR(t.poses.back().y_m, 2.0 + 0.85, 1e-9);
  // A quarter circle of radius 0.5: v = 0.5, w = 1 for pi/2 s ends at (r, r) from a start
  // facing +x, turning left.
  TrajectoryGeneratorParams p;
  p.sim_time_s = M_PI / 2;
  p.sim_step_s = M_PI / 20;
  TrajectoryGenerator quarter(Limits(), p);
  quarter.Simulate({0.0, 0.0, 0.0}, {0.5, 1.0}, &t);
  EXPECT_NEAR(t.poses.back().x_m, 0.5, 1e-9);
  EXPECT_NEAR(t.poses.back().y_m, 0.5, 1e-9);
  EXPECT_NEAR(t.poses.back().yaw_rad, M_PI / 2, 1e-9);
}

class CriticTest : public ::testing::Test {
 protected:
  CriticTest() : layer_(100, 60, 0.1) {
    layer_.Rect(6.0, 0.0, 6.5, 6.0, 100.0f);  // a wall across x = 6..6.5
    layer_.Rect(3.0, 4.0, 4.0, 6.0, 40.0f);   // graded terrain up at y > 4
    map_ = layer_.Build(PioneerFootprint());
    path_ =
        Path({{1.0, 3.0, 0.0}, {2.0, 3.0, 0.0}, {3.0, 3.0, 0.0}, {4.0, 3.0, 0.0}, {5.0, 3.0, 0.0}});
    ctx_.map = map_.get();
    ctx_.pose = {1.0, 3.0, 0.0};
    ctx_.path = &path_;
    ctx_.segment_begin = 0;
    ctx_.segment_end = 3;
    ctx_.local_goal = {3.0, 3.0};
  }
  Trajectory Arc(const Pose2& start, Velocity v) {
    Trajectory t;
    gen_.Simulate(start, v, &t);
    return t;
  }
  TestLayer layer_;
  std::shared_ptr<const CostMap> map_;
  Path path_;
  CriticContext ctx_;
  TrajectoryGenerator gen_{Limits(), {}};
};

TEST_F(CriticTest, ClearanceRejectsCollisionsAndGradesCost) {
  ClearanceCritic::Params strict;
  strict.admissible_braking = false;
  ClearanceCritic dut(1.0, strict);
  dut.Prepare(ctx_);
  EXPECT_TRUE(dut.Evaluate(Arc({1.0, 3.0, 0.0}, {0.5, 0.0})).valid);
  EXPECT_DOUBLE_EQ(dut.Evaluate(Arc({1.0, 3.0, 0.0}, {0.5, 0.0})).value, 0.0);
  // Driving into the wall from 5.2 m: the footprint reaches x = 6 within 1.7 s at 0.5 m/s.
  EXPECT_FALSE(dut.Evaluate(Arc({5.2, 3.0, 0.0}, {0.5, 0.0})).valid);
  EXPECT_TRUE(dut.Evaluate(Arc({5.2, 3.0, 0.0}, {0.0, 0.5})).valid);  // turning in place
  // Along the graded patch the value is its cost over the lethal cost.
  const Score graded = dut.Evaluate(Arc({2.5, 3.9, 0.0}, {0.3, 0.0}));
  EXPECT_TRUE(graded.valid);
  EXPECT_NEAR(graded.value, 0.4, 1e-6);
}

// Where the robot stands after one control period (0.05 s, half a simulation step) is checked
// too: a slow arc beside a blob passed between two valid 0.1 s poses over a cell neither
// covered, and the navigator drove a Pioneer's corner into the blob (pose and command from
// that run).
TEST(ClearanceCriticTest, AnArcIsRefusedWhenThePoseAfterOneControlPeriodCollides) {
  TestLayer layer(200, 100, 0.1);
  layer.Rect(14.85, 4.85, 15.15, 5.15, 100.0f);
  const auto map = layer.Build(PioneerFootprint());
  const Pose2 start{15.152042353397055, 5.5774276655325812, -1.2524082744070004};
  const Velocity v{0.033684210526315803, -0.22602339181286565};
  ASSERT_TRUE(map->IsValid(start));
  const TrajectoryGenerator gen(Limits(), {});
  Trajectory t;
  gen.Simulate(start, v, &t);
  ASSERT_TRUE(map->IsValid(t.poses[0])) << "the first 0.1 s pose is clear";
  const Pose2 after{start.x_m + v.linear_mps * 0.05 * std::cos(start.yaw_rad),
                    start.y_m + v.linear_mps * 0.05 * std::sin(start.yaw_rad),
                    start.yaw_rad + v.angular_radps * 0.05};
  ASSERT_FALSE(map->IsValid(after)) << "the pose after 0.05 s is not";
  ClearanceCritic::Params strict;
  strict.admissible_braking = false;
  ClearanceCritic dut(1.0, strict);
  CriticContext ctx;
  ctx.map = map.get();
  ctx.pose = start;
  dut.Prepare(ctx);
  EXPECT_FALSE(dut.Evaluate(t).valid);
}

TEST_F(CriticTest, ClearanceKeepsTrajectoriesThatCanStillBrake) {
  ClearanceCritic dut(1.0, {});  // admissible braking, 0.8 m/s^2, 0.15 s margin
  dut.Prepare(ctx_);
  // From x = 5.2 the front (at 5.515) hits the wall at x = 6.0 after about 1 s at 0.5 m/s;
  // braking from 0.5 m/s covers 0.3125 s of the arc: admissible, but worse than any clear one.
  const Score far = dut.Evaluate(Arc({5.2, 3.0, 0.0}, {0.5, 0.0}));
  EXPECT_TRUE(far.valid);
  EXPECT_GT(far.value, 2.0);
  EXPECT_LT(far.value, 3.0);
  // Closer, the same speed reaches the wall before the robot could stop.
  EXPECT_FALSE(dut.Evaluate(Arc({5.6, 3.0, 0.0}, {0.5, 0.0})).valid);
  // Slowly, it could still stop: admissible, and scored worse the sooner it would hit.
  const Score slow = dut.Evaluate(Arc({5.6, 3.0, 0.0}, {0.1, 0.0}));
  EXPECT_TRUE(slow.valid);
  EXPECT_GT(slow.value, far.value - 0.5);
  // Already touching: nothing moving forward is admissible.
  EXPECT_FALSE(dut.Evaluate(Arc({5.7, 3.0, 0.0}, {0.05, 0.0})).valid);
}

// Graded terrain a metre ahead (a ramp the global path climbs) costs a fast sample no more than
// a slow one: over the whole horizon the fast one would reach it and always score worse, and
// the robot would creep to a stall at its foot. Terrain within the first 0.3 m still counts.
TEST_F(CriticTest, GradedTerrainFurtherAheadDoesNotFavourCreeping) {
  ClearanceCritic dut(1.0, {});
  dut.Prepare(ctx_);
  const Pose2 start{3.5, 3.0, M_PI / 2};  // the cost-40 band starts at y = 4
  const Score slow = dut.Evaluate(Arc(start, {0.05, 0.0}));
  const Score fast = dut.Evaluate(Arc(start, {0.5, 0.0}));
  ASSERT_TRUE(slow.valid && fast.valid);
  EXPECT_DOUBLE_EQ(fast.value, slow.value);
  const Score close = dut.Evaluate(Arc({3.5, 3.6, M_PI / 2}, {0.5, 0.0}));
  EXPECT_NEAR(close.value, 0.4, 1e-6);
}

TEST_F(CriticTest, ClearancePrefersStayingAwayFromWalls) {
  ClearanceCritic dut(1.0, {});  // 0.3 m of inflation beyond the 0.25 m inscribed radius
  dut.Prepare(ctx_);
  // Parallel to the wall whose first cell centre is at x = 6.05 (heading +y): 1 m away costs
  // nothing, 0.5 m away a little, 0.35 m away (0.1 m beyond the inscribed radius) a lot.
  const double far = dut.Evaluate(Arc({5.05, 1.0, M_PI / 2}, {0.3, 0.0})).value;
  const double near = dut.Evaluate(Arc({5.55, 1.0, M_PI / 2}, {0.3, 0.0})).value;
  const double close = dut.Evaluate(Arc({5.7, 1.0, M_PI / 2}, {0.3, 0.0})).value;
  EXPECT_DOUBLE_EQ(far, 0.0);
  EXPECT_GT(near, 0.0);
  EXPECT_GT(close, near);
  EXPECT_LE(close, 1.0);
  // Continuous: a centimetre closer costs only a little more.
  const double closer = dut.Evaluate(Arc({5.71, 1.0, M_PI / 2}, {0.3, 0.0})).value;
  EXPECT_GT(closer, close);
  EXPECT_LT(closer - close, 0.1);
}

// A global path bent close around a table leg (seen in the apartment's kitchen): proximity the
// path itself has is not charged to the trajectories that follow it, so from rest creeping on
// along the path beats standing beside the leg; getting closer than the path still costs.
TEST(ClearanceCriticTest, ProximityCountsOnlyBeyondThePathsOwn) {
  TestLayer layer(60, 60, 0.05, 0.0f, Pose2{6.0, 0.5, 0.0});
  layer.Rect(7.2, 1.6, 7.3, 1.7, 100.0f);  // the leg (2 x 2 cells)
  const auto map = layer.Build(testing::KobukiFootprint());
  const Path path(
      {{6.92, 1.75, 0.55}, {7.15, 1.91, 0.2}, {7.40, 1.93, -0.3}, {7.675, 1.675, -0.75}});
  CriticContext ctx;
  ctx.map = map.get();
  ctx.pose = {6.999, 1.784, 0.41};
  ctx.path = &path;
  ctx.segment_begin = 0;
  ctx.segment_end = path.size();
  ClearanceCritic::Params params;
  params.inflation_m = 0.15;
  params.path_reach_m = 1.15;
  ClearanceCritic dut(1.0, params);
  dut.Prepare(ctx);
  // The path passes about 0.25 m from the leg's cells: proximity 0.5 with 0.15 m of inflation.
  EXPECT_GT(dut.path_proximity(), 0.4);
  EXPECT_LT(dut.path_proximity(), 0.6);
  VelocityLimits kobuki;
  kobuki.acc_lim_x_mps2 = 1.0;
  kobuki.acc_lim_theta_radps2 = 2.0;
  TrajectoryGenerator gen(kobuki, {});
  Trajectory creep, stand, closer;
  gen.Simulate(ctx.pose, {0.016, 0.0}, &creep);
  gen.Simulate(ctx.pose, {0.0, 0.0}, &stand);
  gen.Simulate(ctx.pose, {0.04, -0.3}, &closer);  // curving in towards the leg
  EXPECT_DOUBLE_EQ(dut.Evaluate(stand).value, 0.0);
  EXPECT_LT(dut.Evaluate(creep).value, 0.05);
  EXPECT_GT(dut.Evaluate(closer).value, 0.2);
  // Without a path the same creep pays its whole proximity.
  CriticContext no_path = ctx;
  no_path.path = nullptr;
  dut.Prepare(no_path);
  EXPECT_DOUBLE_EQ(dut.path_proximity(), 0.0);
  gen.Simulate(ctx.pose, {0.04, 0.0}, &creep);
  EXPECT_GT(dut.Evaluate(creep).value, 0.4);
}

TEST_F(CriticTest, PathAlignPrefersStayingOnAndFacingAlongThePath) {
  PathAlignCritic dut(1.0, 0.325);
  dut.Prepare(ctx_);
  const Score along = dut.Evaluate(Arc({1.0, 3.0, 0.0}, {0.5, 0.0}));
  const Score veering = dut.Evaluate(Arc({1.0, 3.0, 0.0}, {0.5, 0.6}));
  EXPECT_NEAR(along.value, 0.0, 1e-9);
  EXPECT_GT(veering.value, 0.3);
  // Turning in place towards the path direction beats turning away from it.
  ctx_.pose = {1.0, 3.0, 0.8};
  dut.Prepare(ctx_);
  EXPECT_LT(dut.Evaluate(Arc(ctx_.pose, {0.0, -0.5})).value,
            dut.Evaluate(Arc(ctx_.pose, {0.0, 0.5})).value);
}

TEST_F(CriticTest, GoalDistMeasuresToTheLocalGoal) {
  GoalDistCritic dut(1.0);
  dut.Prepare(ctx_);
  EXPECT_NEAR(dut.Evaluate(Arc({1.0, 3.0, 0.0}, {0.5, 0.0})).value, 2.0 - 0.85, 1e-9);
  EXPECT_NEAR(dut.Evaluate(Arc({1.0, 3.0, 0.0}, {0.0, 0.0})).value, 2.0, 1e-9);
  EXPECT_GT(dut.Evaluate(Arc({1.0, 3.0, 0.0}, {-0.2, 0.0})).value, 2.0);
}

TEST_F(CriticTest, SpeedPrefersFastForward) {
  SpeedCritic dut(1.0, 0.5);
  dut.Prepare(ctx_);
  EXPECT_DOUBLE_EQ(dut.Evaluate(Arc({0, 0, 0}, {0.5, 0.0})).value, 0.0);
  EXPECT_DOUBLE_EQ(dut.Evaluate(Arc({0, 0, 0}, {0.25, 0.0})).value, 0.5);
  EXPECT_DOUBLE_EQ(dut.Evaluate(Arc({0, 0, 0}, {0.0, 0.0})).value, 1.0);
  EXPECT_DOUBLE_EQ(dut.Evaluate(Arc({0, 0, 0}, {-0.1, 0.0})).value, 1.2);
}

TEST_F(CriticTest, OscillationRejectsASecondReversalUntilTheRobotMoves) {
  OscillationCritic dut(1.0, 0.05, 0.2);
  dut.Prepare(ctx_);
  const Pose2 p{1.0, 3.0, 0.0};
  dut.Commit({0.0, 0.3}, p);                             // turning left
  EXPECT_TRUE(dut.Evaluate(Arc(p, {0.0, -0.3})).valid);  // one reversal is allowed ...
  EXPECT_DOUBLE_EQ(dut.Evaluate(Arc(p, {0.0, -0.3})).value, 1.0);
  EXPECT_DOUBLE_EQ(dut.Evaluate(Arc(p, {0.0, 0.3})).value, 0.0);
  dut.Commit({0.0, -0.3}, {1.0, 3.0, 0.01});
  EXPECT_TRUE(dut.angular_flipped());
  EXPECT_FALSE(dut.Evaluate(Arc(p, {0.0, 0.3})).valid);  // ... the second is not
  EXPECT_TRUE(dut.Evaluate(Arc(p, {0.0, -0.3})).valid);
  // Linear direction flips are tracked the same way.
  dut.Commit({0.2, -0.3}, {1.0, 3.0, 0.02});
  dut.Commit({-0.1, -0.3}, {1.0, 3.0, 0.03});
  EXPECT_FALSE(dut.Evaluate(Arc(p, {0.2, -0.3})).valid);
  // Turning far enough clears the memory.
  dut.Commit({-0.1, -0.3}, {1.0, 3.0, -0.3});
  EXPECT_FALSE(dut.angular_flipped());
  EXPECT_TRUE(dut.Evaluate(Arc(p, {0.2, 0.3})).valid);
  dut.Reset();
  EXPECT_DOUBLE_EQ(dut.Evaluate(Arc(p, {0.2, 0.3})).value, 0.0);
}

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

// A Kobuki (round, 0.176 m) at rest in the apartment's corridor, just west of the bathroom's
// 0.8 m door, facing 30 deg off the corridor: the path runs on east and bends north through the
// door, 5 cm from its western frame (the map as the navigator had it when it stalled there).
// Every constant arc that reaches the door clips the frame, and the rest gain less than
// standing still costs, so the dynamic window alone stands still for ever; the path-tracking
// candidates follow the bend.
struct KobukiScene {
  KobukiScene() : layer(100, 100, 0.05, 0.0f, Pose2{5.0, 4.0, 0.0}) {
    layer.Rect(5.0, 5.68, 7.5, 5.86, 100.0f).Rect(8.32, 5.68, 10.0, 5.86, 100.0f);  // the door
    round = testing::KobukiFootprint();
    map = layer.Build(round);
    kobuki.max_vel_x_mps = 0.5;
    kobuki.min_vel_x_mps = -0.1;
    kobuki.max_vel_theta_radps = 1.5;
    kobuki.acc_lim_x_mps2 = 1.0;
    kobuki.acc_lim_theta_radps2 = 2.0;
  }
  // Closed loop at 20 Hz with the navigator's carrot (1.2 m ahead) and path window (3 m), from
  // rest at `pose` until `done`; the cycles that took, or -1 (400 cycles, or a collision).
  int Drive(const DwaParams& params, const CostMap& on, Pose2 pose, const Path& path,
            const std::function<bool(const Pose2&)>& done, Pose2* end = nullptr) {
    DwaPlanner dut(kobuki, params);
    Velocity last;
    int k = 0;
    for (; k < 400 && !done(pose); ++k) {
      const auto proj = path.Project(pose.position());
      DwaInput in =
          Input(on, path, pose, last,
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
        ADD_FAILURE() << "touched an obstacle at cycle " << k << ", (" << pose.x_m << ", "
                      << pose.y_m << ")";
        k = 400;
        break;
      }
      last = r.command;
    }
    if (end != nullptr) *end = pose;
    return k < 400 ? k : -1;
  }
  TestLayer layer;
  std::vector<Vector2> round;
  std::shared_ptr<const CostMap> map;
  VelocityLimits kobuki;
};

// The path from the corridor through the bathroom door, as the navigator had it.
Path DoorPath() {
  return Path({{7.07, 5.39, 0.2},
               {7.36, 5.44, 0.2},
               {7.64, 5.50, 0.5},
               {7.68, 5.56, 1.0},
               {7.74, 5.71, 1.2},
               {7.77, 5.79, 1.57},
               {7.74, 5.98, 1.6},
               {7.71, 6.17, 1.6},
               {7.7, 7.0, 1.6}});
}

TEST(DwaPlannerTest, ThreadsADoorBesideTheWallFromRestByTrackingThePath) {
  KobukiScene scene;
  const Pose2 start{7.36, 5.46, 0.60};
  const auto through = [](const Pose2& p) { return p.y_m >= 6.3; };
  DwaParams params;
  params.clearance_inflation_m = 0.15;  // config/navigator/apartment.yaml
  const int cycles = scene.Drive(params, *scene.map, start, DoorPath(), through);
  EXPECT_GT(cycles, 0);
  EXPECT_LT(cycles, 300);
  // Without the tracking candidates, for the record: the dynamic window stands still.
  params.path_tracking = false;
  EXPECT_EQ(scene.Drive(params, *scene.map, start, DoorPath(), through), -1);
}

// The apartment's kitchen as a laser-only Kobuki saw it: the global path bends around a table
// leg a few centimetres off the footprint, the goal just past the leg, the robot at rest. The
// window's creeping arcs gained less than they cost and it stood beside the leg until its
// recoveries ran out; tracking the bend, it arrives without touching the leg.
TEST(DwaPlannerTest, FollowsAPathBentCloseAroundATableLegFromRest) {
  KobukiScene scene;
  TestLayer layer(60, 60, 0.05, 0.0f, Pose2{6.0, 0.5, 0.0});
  layer.Rect(7.2, 1.6, 7.3, 1.7, 100.0f);  // the leg (2 x 2 cells)
  const auto map = layer.Build(scene.round);
  DwaParams params;
  params.clearance_inflation_m = 0.15;  // config/navigator/apartment.yaml
  const Path path(
      {{6.92, 1.75, 0.55}, {7.15, 1.91, 0.2}, {7.40, 1.93, -0.3}, {7.675, 1.675, -0.75}});
  const Vector2 goal{7.675, 1.675};
  const auto arrived = [&](const Pose2& p) { return (p.position() - goal).norm() <= 0.2; };
  const Pose2 start{6.92, 1.75, 0.39};
  Pose2 end;
  EXPECT_GT(scene.Drive(params, *map, start, path, arrived, &end), 0)
      << "stopped at (" << end.x_m << ", " << end.y_m << ")";
  params.path_tracking = false;  // the window alone, for the record
  EXPECT_EQ(scene.Drive(params, *map, start, path, arrived), -1);
}

TEST(TrajectoryGeneratorTest, TrackPathFollowsTheBendAndSlowsNearWalls) {
  KobukiScene scene;
  const Path path = DoorPath();
  TrajectoryGeneratorParams p;
  p.sim_time_s = 4.0;
  const TrajectoryGenerator gen(scene.kobuki, p);
  TrajectoryGenerator::TrackingParams tracking;
  tracking.lookahead_m = 0.3;
  Trajectory t;
  ASSERT_TRUE(gen.TrackPath({7.36, 5.46, 0.2}, {0.0, 0.0}, path, 0, tracking, scene.map.get(), &t));
  // The first command is one period of acceleration; the trajectory goes on along the path into
  // the bend, never touching the frame, never near the top speed beside it.
  EXPECT_NEAR(t.velocity.linear_mps, 0.05, 1e-12);
  EXPECT_GT(path.Project(t.poses.back().position()).arc_length_m,
            path.Project({7.36, 5.46}).arc_length_m + 0.3);
  EXPECT_LT(path.Project(t.poses.back().position()).distance_m, 0.1);
  for (const Pose2& q : t.poses) EXPECT_TRUE(scene.map->IsValid(q)) << q.x_m << ", " << q.y_m;
  EXPECT_LT(t.peak_linear_mps, 0.3);
  // Without a map nothing slows it but the bend and the path's end.
  Trajectory free;
  ASSERT_TRUE(gen.TrackPath({7.36, 5.46, 0.2}, {0.0, 0.0}, path, 0, tracking, nullptr, &free));
  EXPECT_GT(free.peak_linear_mps, t.peak_linear_mps);
  // Far off its heading, the robot turns in place first.
  Trajectory turn;
  ASSERT_TRUE(gen.TrackPath({7.36, 5.46, M_PI}, {0.0, 0.0}, path, 0, tracking, nullptr, &turn));
  EXPECT_EQ(turn.target.linear_mps, 0.0);
  EXPECT_NE(turn.target.angular_radps, 0.0);
  EXPECT_FALSE(gen.TrackPath({7.36, 5.46, 0.2}, {0.0, 0.0}, Path({{1.0, 1.0, 0.0}}), 0, tracking,
                             nullptr, &turn));
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
