#include "planner/local/trajectory_generator.h"

#include <random>

#include <gtest/gtest.h>

#include "tests/unit/planner/local/door_scene.h"
#include "tests/unit/planner/test_maps.h"

namespace cairn::planner {
namespace {

using common::Pose2;

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

TEST(TrajectoryGeneratorTest, TrackPathFollowsTheBendAndSlowsNearWalls) {
  const testing::KobukiDoorScene scene;
  const Path path = testing::DoorPath();
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

}  // namespace
}  // namespace cairn::planner
