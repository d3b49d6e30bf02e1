// The whole navigation stack as real processes on a private LCM bus: cairn-sim (MuJoCo, the
// tunnel world of seed 000, one Pioneer 3-AT), cairn-mapper (terrain and cost layers) and
// cairn-navigator, a graph under cairn-launch. Lanes, starts and goals:
// simulator/worlds/tunnel_lanes.yaml.

#include <csignal>

#include <gtest/gtest.h>

#include "tests/integration/planner/navigator_stack_fixture.h"

namespace cairn::planner {
namespace {

using namespace testing_stack;  // NOLINT: the fixture and its helpers

TEST_F(NavigatorStackTest, ReachesTheGoalBehindTheCubeWithoutTouchingIt) {
  StartStack(4.0, 2.0, 0.0);
  SendGoal(1, 14.0, 2.0);
  ASSERT_TRUE(WaitState(kStateReached, 100.0)) << StatusText();
  const auto poses = Poses();
  ASSERT_FALSE(poses.empty());
  const Pose2 last = ToPose2(poses.back());
  EXPECT_LT(std::hypot(last.x_m - 14.0, last.y_m - 2.0), 0.5);
  // Ground truth: the footprint never touched the 1 m cube (x 9..10, y 1.5..2.5) nor a lane
  // wall (y = 0 and y = 4, 0.2 m thick).
  const auto cube = Box(9.0, 1.5, 10.0, 2.5);
  for (const auto& p : poses) {
    const auto fp = FootprintAt(ToPose2(p));
    ASSERT_FALSE(ConvexOverlap(fp, cube, 0.0)) << "touched the cube at x " << p.position_m[0];
    ASSERT_FALSE(ConvexOverlap(fp, Box(3.0, -0.1, 24.0, 0.1), 0.0)) << "touched the south wall";
    ASSERT_FALSE(ConvexOverlap(fp, Box(3.0, 3.9, 24.0, 4.1), 0.0)) << "touched the lane wall";
  }
}

TEST_F(NavigatorStackTest, ClimbsTheFiveDegreeRampToItsTop) {
  StartStack(4.0, 6.0, 0.0);
  // Let the mapper integrate a few revolutions (the ramp in view) before asking: on the first
  // revolutions alone the ramp may still show edges, and the plan detours through unexplored
  // lanes.
  ASSERT_TRUE(WaitFor([&] { return CostVersion() >= 5; }, 30.0, [&] { bus_.Pump(20); }));
  SendGoal(2, 14.0, 6.0);
  ASSERT_TRUE(WaitState(kStateReached, 100.0)) << StatusText();
  const auto poses = Poses();
  ASSERT_FALSE(poses.empty());
  // On the platform at the top: x 14, z 0.3 (the base's height above the deck it stands on).
  const auto& last = poses.back();
  EXPECT_LT(std::hypot(last.position_m[0] - 14.0, last.position_m[1] - 6.0), 0.5);
  const double start_z = poses.front().position_m[2];
  EXPECT_NEAR(last.position_m[2] - start_z, 0.3, 0.05);
}

TEST_F(NavigatorStackTest, ReportsNoPathOverTheTenDegreeRampAndNeverDrivesOntoIt) {
  // The platform is walled in except for the ramp, but the other lanes (joined by the cross
  // corridor) are unexplored: counting on all unexplored space, the robot would explore them
  // before the verdict could be "no path". With a 12 m horizon the verdict comes at once.
  // Ground truth: the footprint never reaches the ramp (x >= 8.0) and the base never rises.
  ExpectNoPathNeverEntering(4.0, 10.0, 3, 14.0, Box(8.0, 8.1, 24.0, 11.9), 110.0, true);
}

TEST_F(NavigatorStackTest, ReportsNoPathOntoTheTwentyCentimetreStepAndNeverMountsIt) {
  // Lane 5: a 20 cm block from x = 10 to the end wall, wall to wall (pioneer3at: step up 3 cm).
  ExpectNoPathNeverEntering(4.0, 22.0, 6, 14.0, Box(10.0, 20.1, 24.0, 23.9), 110.0, true);
}

// The floor below the drop stays hidden until the robot is close; the rays that pass the edge
// prove only a few centimetres of it from afar, which is enough (traversability.unseen_drop_m):
// the edge is lethal long before the rays could prove more than the 10 cm step-down limit.
TEST_F(NavigatorStackTest, NeverCrossesTheEdgeOfTheTwentyCentimetreDrop) {
  // Lane 6: a 5 deg ramp up to a platform at 0.2 m that ends in a 20 cm drop at x = 13.29, wall
  // to wall; the goal lies past the drop (pioneer3at: step down 10 cm). The floor below the
  // edge is hidden from the robot until it is close: whatever it tries, it must not drive off.
  ExpectNoPathNeverEntering(4.0, 26.0, 7, 17.0, Box(13.3, 24.1, 24.0, 27.9), 150.0, false);
}

TEST_F(NavigatorStackTest, ReplansAroundAnObjectSpawnedOnItsPathAndArrives) {
  StartStack(4.0, 18.0, 0.0);  // lane 4: open floor, a 1 cm plate from x = 10 (traversable)
  SendGoal(4, 14.0, 18.0);
  ASSERT_TRUE(WaitFor(
      [&] {
        const auto poses = Poses();
        return !poses.empty() && poses.back().position_m[0] > 5.5;
      },
      60.0, [&] { bus_.Pump(20); }))
      << StatusText();
  // A 0.8 m crate appears across the straight route ahead.
  cairn::lcmt_sim_control_request spawn{};
  spawn.op = cairn::lcmt_sim_control_request::OP_SPAWN;
  spawn.name = "crate";
  spawn.shape = cairn::lcmt_sim_control_request::SHAPE_BOX;
  spawn.size_m[0] = 0.4;
  spawn.size_m[1] = 0.4;
  spawn.size_m[2] = 0.4;
  spawn.position_m[0] = 10.0;
  spawn.position_m[1] = 18.0;
  spawn.position_m[2] = 0.42;
  const auto reply = SimControl(spawn);
  ASSERT_TRUE(reply.has_value());
  ASSERT_EQ(reply->status, +cairn::lcmt_sim_control_reply::STATUS_OK) << reply->message;
  ASSERT_TRUE(WaitState(kStateReached, 100.0)) << StatusText();
  EXPECT_GE(Status()->replans, 1);
  // Seed 000 exp 5: the robot crossed onto the 1 cm plate (x >= 10) and stands on it.
  const auto poses = Poses();
  ASSERT_FALSE(poses.empty());
  EXPECT_GT(poses.back().position_m[0], 13.5);
  EXPECT_NEAR(poses.back().position_m[2] - poses.front().position_m[2], 0.01, 0.005)
      << "not on the plate";
  const auto crate = Box(9.6, 17.6, 10.4, 18.4);
  for (const auto& p : poses) {
    ASSERT_FALSE(ConvexOverlap(FootprintAt(ToPose2(p)), crate, 0.0))
        << "touched the crate at x " << p.position_m[0] << ", y " << p.position_m[1];
  }
}

TEST_F(NavigatorStackTest, StopsWithinHalfASecondOfSimTimeWhenTheMapperStops) {
  StartStack(4.0, 38.0, 0.0);  // lane 9, the demo route
  SendGoal(5, 21.0, 38.0);
  ASSERT_TRUE(WaitFor(
      [&] {
        auto c = bus_.Last<cairn::lcmt_velocity_command>(ch::ForRobot(kRobot, ch::kCmdVel));
        auto s = Status();
        return s && s->state == kStateDriving && c && c->linear_mps > 0.2;
      },
      60.0, [&] { bus_.Pump(20); }))
      << StatusText();
  // The mapper stops at sim time `killed_utime` or later: the newest pose seen before the kill.
  bus_.Pump(0);
  const auto before_kill = bus_.Last<cairn::lcmt_pose>(ch::ForRobot(kRobot, ch::kPose));
  ASSERT_TRUE(before_kill.has_value());
  const int64_t killed_utime = before_kill->utime;
  const auto mapper = Process("mapper");
  ASSERT_TRUE(mapper.has_value() && mapper->pid > 0);
  ASSERT_EQ(kill(mapper->pid, SIGKILL), 0);
  // cairn-launch sees it go (the graph restarts nothing).
  ASSERT_TRUE(WaitFor(
      [&] {
        const auto row = Process("mapper");
        return row && row->state != "ready" && row->state != "starting";
      },
      5.0, [&] { bus_.Pump(20); }));
  ASSERT_TRUE(WaitState(kStateStopped, 10.0)) << StatusText();
  EXPECT_EQ(Status()->reason, kReasonStaleMap);
  // The first zero command after the kill (sim time).
  int64_t stop_utime = -1;
  for (const auto& bytes : bus_.Kept(ch::ForRobot(kRobot, ch::kCmdVel))) {
    cairn::lcmt_velocity_command c;
    if (c.decode(bytes.data(), 0, static_cast<int>(bytes.size())) < 0) continue;
    if (c.utime > killed_utime && c.linear_mps == 0.0 && c.angular_radps == 0.0) {
      stop_utime = c.utime;
      break;
    }
  }
  ASSERT_GT(stop_utime, 0);
  // 0.5 s, and 0.1 s for the pose the test last saw lagging the sim and process scheduling.
  EXPECT_LE(stop_utime - killed_utime, 500'000 + 100'000)
      << "stopped " << (stop_utime - killed_utime) / 1e3 << " ms of sim time after the kill";
  // Not before the layer could have gone stale (the stop is the mapper's doing).
  EXPECT_GE(stop_utime - killed_utime, 200'000)
      << "stopped " << (stop_utime - killed_utime) / 1e3 << " ms of sim time after the kill";
  // And the robot really stops: its ground-truth speed falls to zero.
  EXPECT_TRUE(WaitFor(
      [&] {
        auto p = bus_.Last<cairn::lcmt_pose>(ch::ForRobot(kRobot, ch::kPose));
        return p && std::hypot(p->linear_velocity_mps[0], p->linear_velocity_mps[1]) < 0.02;
      },
      3.0, [&] { bus_.Pump(20); }));
}

// Every test above drives on ground-truth poses. Here the navigator drives on the simulator's
// wheel odometry (pose_source: odom; frame odom, which starts at the spawn pose) and the mapper
// builds its layers on the same odometry, as on a robot without localisation: map and pose share
// one frame and drift together. Arrival is judged on ground truth.
TEST_F(NavigatorStackTest, DrivesOnOdometryToAGoalAFewMetresAway) {
  StartStack(4.0, 18.0, 0.0, OdometryNavigatorConfig(), "--pose-source, odometry");
  if (HasFatalFailure()) return;
  // The navigator really listens to the odometry (it names its pose channel at start-up).
  EXPECT_NE(testing::TailOfFile(run_dir_ + "/logs/navigator.log", 200).find("pose from p3at.ODOM"),
            std::string::npos);
  SendGoal(8, 8.5, 18.5);  // lane 4, open floor (the 1 cm plate starts at x = 10)
  ASSERT_TRUE(WaitState(kStateReached, 100.0)) << StatusText();
  const auto poses = Poses();
  ASSERT_FALSE(poses.empty());
  const Pose2 start = ToPose2(poses.front());
  const Pose2 last = ToPose2(poses.back());
  EXPECT_GT(last.x_m - start.x_m, 4.0) << "it did not drive the 4.5 m";
  // The goal tolerance is 0.25 m in the odometry frame; a few metres of noise-free wheel
  // odometry on a skid-steer base drift by centimetres.
  EXPECT_LT(std::hypot(last.x_m - 8.5, last.y_m - 18.5), 0.4)
      << "ground truth (" << last.x_m << ", " << last.y_m << ")";
  // Ground truth: the footprint never touched a lane wall (y = 16 and y = 20, 0.2 m thick).
  for (const auto& p : poses) {
    const auto fp = FootprintAt(ToPose2(p));
    ASSERT_FALSE(ConvexOverlap(fp, Box(3.0, 15.9, 24.0, 16.1), 0.0)) << "touched the south wall";
    ASSERT_FALSE(ConvexOverlap(fp, Box(3.0, 19.9, 24.0, 20.1), 0.0)) << "touched the north wall";
  }
}

}  // namespace
}  // namespace cairn::planner
