#include "planner/local/critics.h"

#include <gtest/gtest.h>

#include "planner/local/trajectory_generator.h"
#include "tests/unit/planner/test_maps.h"

namespace cairn::planner {
namespace {

using common::Pose2;
using testing::PioneerFootprint;
using testing::TestLayer;

VelocityLimits Limits() { return VelocityLimits::FromProfile(testing::PioneerProfile()); }

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

}  // namespace
}  // namespace cairn::planner

namespace cairn::planner {
namespace {

// The Pioneer below an 8 cm step at x = 6 (up towards +x, testing::OneWayStepCorridor): it may
// drive down the step, forwards or reversing, and never up it.
TEST(ClearanceCriticTest, RefusesTrajectoriesClimbingAOneWayStep) {
  const auto map = testing::OneWayStepCorridor().Build(PioneerFootprint());
  const TrajectoryGenerator gen(Limits(), {});
  ClearanceCritic::Params strict;
  strict.admissible_braking = false;
  ClearanceCritic dut(1.0, strict);
  CriticContext ctx;
  ctx.map = map.get();
  auto score = [&](const Pose2& start, const Velocity& v) {
    ctx.pose = start;
    dut.Prepare(ctx);
    Trajectory t;
    gen.Simulate(start, v, &t);
    return dut.Evaluate(t);
  };
  // Up: forwards from below, or reversing from below facing away.
  EXPECT_FALSE(score({5.4, 2.0, 0.0}, {0.3, 0.0}).valid);
  EXPECT_FALSE(score({5.4, 2.0, M_PI}, {-0.2, 0.0}).valid);
  EXPECT_FALSE(score({5.4, 2.0, 0.3}, {0.3, 0.1}).valid);  // an arc up it
  // Down: forwards, reversing, and on an arc.
  const Score down = score({6.6, 2.0, M_PI}, {0.3, 0.0});
  EXPECT_TRUE(down.valid);
  EXPECT_LT(down.value, 2.0);
  EXPECT_TRUE(score({6.6, 2.0, 0.0}, {-0.2, 0.0}).valid);
  EXPECT_TRUE(score({6.6, 2.0, M_PI}, {0.3, 0.2}).valid);
  // Turning on the spot astride the step, and driving away from it below.
  EXPECT_TRUE(score({6.0, 2.0, 0.0}, {0.0, 0.5}).valid);
  EXPECT_TRUE(score({5.9, 2.0, M_PI}, {0.3, 0.0}).valid);
  // With admissible braking a slow climb far enough ahead scores as blocked (2..3), not clear.
  ClearanceCritic braking(1.0, {});
  ctx.pose = {5.0, 2.0, 0.0};
  braking.Prepare(ctx);
  Trajectory slow;
  gen.Simulate(ctx.pose, {0.4, 0.0}, &slow);
  const Score s = braking.Evaluate(slow);
  EXPECT_TRUE(s.valid);
  EXPECT_GE(s.value, 2.0);
}

}  // namespace
}  // namespace cairn::planner
