#include "simulator/mujoco_sim.h"

#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "simulator/sensors/ground_truth_sensor.h"
#include "simulator/sensors/imu_sensor.h"
#include "simulator/sensors/lidar_sensor.h"
#include "simulator/sensors/odometry_sensor.h"
#include "simulator/sensors/planar_laser_sensor.h"
#include "simulator/sensors/turret_sensor.h"
#include "tests/unit/simulator/sim_test_util.h"

namespace cairn::sim {
namespace {

using testing::Drive;
using testing::FlatWorld;
using testing::InlineScenario;
using testing::SimTest;

constexpr double kDeg = M_PI / 180.0;

// A solid ramp of `slope_deg` from x = 2 rising to a platform `height_m` high that ends at x_end.
std::string RampWorld(double slope_deg, double height_m, double x_end) {
  const double a = slope_deg * kDeg;
  const double length = height_m / std::tan(a);
  const double half_thick = height_m / 2.0 / std::cos(a) + 0.1;
  const double cx = 2.0 + length / 2.0 + std::sin(a) * half_thick;
  const double cz = height_m / 2.0 - std::cos(a) * half_thick;
  const double platform_half = (x_end - (2.0 + length)) / 2.0;
  char xml[512];
  std::snprintf(xml, sizeof(xml),
                R"(<geom type="box" size="%f 2 %f" pos="%f 0 %f" euler="0 %f 0"/>
                   <geom type="box" size="%f 2 %f" pos="%f 0 %f"/>)",
                length / 2.0 / std::cos(a), half_thick, cx, cz, -slope_deg, platform_half,
                height_m / 2.0, 2.0 + length + platform_half, height_m / 2.0);
  return FlatWorld(xml);
}

class PhysicsTest : public SimTest {};

// A robot of `model` (no sensors) at the origin, facing a step `step_m` high from x = 2 on,
// `half_m` deep and wide on each side.
Scenario StepScenario(double step_m, double half_m, const std::string& id,
                      const std::string& model) {
  char box[160];
  std::snprintf(box, sizeof(box), R"(<geom type="box" size="%f %f %f" pos="%f 0 %f"/>)", half_m,
                half_m, step_m / 2, 2.0 + half_m, step_m / 2);
  Scenario s = InlineScenario(FlatWorld(box), id, model);
  s.robots[0].sensors = SensorSet{};
  return s;
}

TEST_F(PhysicsTest, Pioneer3AtClimbsFiveAndTenDegreeRamps) {
  for (double slope : {5.0, 10.0}) {
    Scenario s = InlineScenario(RampWorld(slope, 0.3, 12.0), "p3at", "pioneer3at");
    s.robots[0].sensors = SensorSet{};
    MujocoSim sim(s);
    SimOutputs out;
    Drive(sim, "p3at", 0.4, 0.0, 30.0, &out);
    const common::Pose3 pose = sim.RobotPose("p3at");
    // On the platform: base at platform height + wheel radius.
    EXPECT_GT(pose.position_m.x(), 2.0 + 0.3 / std::tan(slope * kDeg) + 0.5) << slope;
    EXPECT_NEAR(pose.position_m.z(), 0.3 + 0.1075, 0.02) << slope;
  }
}

TEST_F(PhysicsTest, Pioneer3AtCannotMountTwentyCentimetreStepButRollsOverOneCentimetre) {
  for (double step : {0.2, 0.01}) {
    MujocoSim sim(StepScenario(step, 2.0, "p3at", "pioneer3at"));
    SimOutputs out;
    Drive(sim, "p3at", 0.5, 0.0, 12.0, &out);
    const common::Pose3 pose = sim.RobotPose("p3at");
    if (step > 0.1) {
      EXPECT_LT(pose.position_m.x(), 2.0) << "climbed the 20 cm step";
      EXPECT_LT(pose.position_m.z(), 0.15);
    } else {
      EXPECT_GT(pose.position_m.x(), 3.0) << "stuck at the 1 cm step";
      EXPECT_NEAR(pose.position_m.z(), 0.01 + 0.1075, 0.01);
    }
  }
}

TEST_F(PhysicsTest, RoverMountsAnEightCentimetreStepButNotTwenty) {
  // Its profile's step up is 8 cm: slowly or at full speed, head on or turning at it.
  struct Run {
    double step_m, v_mps, w_radps;
  };
  for (const Run run : {Run{0.08, 0.5, 0.0}, Run{0.08, 0.2, 0.0}, Run{0.08, 0.6, -0.45},
                        Run{0.08, 0.25, 0.4}, Run{0.2, 0.5, 0.0}}) {
    const double step = run.step_m;
    MujocoSim sim(StepScenario(step, 6.0, "rover", "rover"));
    SimOutputs out;
    // Straight at the face; from 0.3 m short of it a turn for 1.5 s, then straight again.
    Drive(sim, "rover", run.v_mps, 0.0, (2.0 - 0.35 - 0.3) / run.v_mps, &out);
    Drive(sim, "rover", run.v_mps, run.w_radps, 1.5, &out);
    Drive(sim, "rover", run.v_mps, 0.0, 12.0, &out);
    SCOPED_TRACE(::testing::Message() << "v " << run.v_mps << " w " << run.w_radps);
    const common::Pose3 pose = sim.RobotPose("rover");
    if (step > 0.15) {
      // The front wheels may reach its top (it is as high as their axles); the rear ones never.
      EXPECT_LT(pose.position_m.x(), 2.0) << "climbed the 20 cm step";
    } else {
      EXPECT_GT(pose.position_m.x(), 3.0) << "stuck at the " << step << " m step";
      EXPECT_NEAR(pose.position_m.z(), step + 0.2, 0.01) << step;
    }
  }
}

TEST_F(PhysicsTest, Pioneer3AtFallsOffADrop) {
  // A 0.2 m platform ending at x = 3; the robot starts on it.
  Scenario s = InlineScenario(FlatWorld(R"(<geom type="box" size="3 2 0.1" pos="0 0 0.1"/>)"),
                              "p3at", "pioneer3at");
  s.robots[0].sensors = SensorSet{};
  MujocoSim sim(s);
  SimOutputs out;
  EXPECT_NEAR(sim.RobotPose("p3at").position_m.z(), 0.2 + 0.1075, 0.01);
  // Driving off the edge it pitches nose-down and tips over the 20 cm drop.
  double max_nose_down_rad = 0.0;
  const double end = sim.time_s() + 10.0;
  while (sim.time_s() < end) {
    sim.Command("p3at", 0.5, 0.0);
    sim.Step(&out);
    max_nose_down_rad = std::max(max_nose_down_rad, -sim.RobotPose("p3at").pitch_rad());
  }
  EXPECT_GT(sim.RobotPose("p3at").position_m.x(), 3.0);
  EXPECT_LT(sim.RobotPose("p3at").position_m.z(), 0.2 + 0.1075 - 0.05);
  EXPECT_GT(max_nose_down_rad, 30.0 * kDeg);
}

TEST_F(PhysicsTest, CommandedVelocitiesAreMetOnFlatGround) {
  for (const char* model : {"pioneer3at", "rover", "p3dx", "kobuki"}) {
    Scenario s = InlineScenario(FlatWorld(), "r", model);
    s.robots[0].sensors = SensorSet{};
    MujocoSim sim(s);
    SimOutputs out;
    Drive(sim, "r", 0.3, 0.3, 3.0, &out);
    EXPECT_NEAR(sim.RobotVelocity("r").norm(), 0.3, 0.02) << model;
    const double yaw0 = sim.RobotPose("r").yaw_rad();
    Drive(sim, "r", 0.3, 0.3, 1.0, &out);
    EXPECT_NEAR(common::WrapAngle(sim.RobotPose("r").yaw_rad() - yaw0), 0.3, 0.03) << model;
  }
}

class DriveSimTest : public SimTest {};

TEST_F(DriveSimTest, WatchdogStopsARobotThatIsNoLongerCommanded) {
  Scenario s = InlineScenario(FlatWorld(), "r", "pioneer3at");
  s.robots[0].sensors = SensorSet{};
  MujocoSim sim(s);
  SimOutputs out;
  Drive(sim, "r", 0.5, 0.0, 2.0, &out);
  EXPECT_NEAR(sim.RobotVelocity("r").x(), 0.5, 0.03);
  // Commands stop: for 0.5 s the robot keeps going...
  while (sim.time_s() < 2.45) sim.Step(&out);
  EXPECT_NEAR(sim.RobotVelocity("r").x(), 0.5, 0.03);
  EXPECT_TRUE(out.events.empty());
  // ... then the watchdog stops it (within its deceleration limit).
  while (sim.time_s() < 4.0) sim.Step(&out);
  EXPECT_LT(sim.RobotVelocity("r").norm(), 0.01);
  EXPECT_TRUE(sim.drive("r").watchdog_active());
  ASSERT_EQ(out.events.size(), 1u);
  EXPECT_NE(out.events[0].find("watchdog"), std::string::npos);
}

TEST_F(DriveSimTest, NanCommandsAreDroppedAndOverLimitCommandsClamped) {
  Scenario s = InlineScenario(FlatWorld(), "r", "pioneer3at");
  s.robots[0].sensors = SensorSet{};
  MujocoSim sim(s);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(sim.Command("r", nan, 0.0), CommandVerdict::kDropped);
  EXPECT_EQ(sim.Command("r", 0.2, std::numeric_limits<double>::infinity()),
            CommandVerdict::kDropped);
  SimOutputs out;
  for (int i = 0; i < 200; ++i) {
    sim.Command("r", nan, nan);
    sim.Step(&out);
  }
  EXPECT_LT(sim.RobotVelocity("r").norm(), 1e-3);  // never moved
  EXPECT_EQ(sim.Command("r", 5.0, 0.0), CommandVerdict::kClamped);
  EXPECT_EQ(sim.drive("r").target_linear_mps(), 0.5);  // pioneer3at profile limit
  EXPECT_THROW(sim.Command("nobody", 0.1, 0.0), std::invalid_argument);
}

TEST_F(DriveSimTest, ResetPutsTheRobotAtRestAndRestartsOdometry) {
  Scenario s = InlineScenario(FlatWorld(), "r", "p3dx");
  MujocoSim sim(s);
  SimOutputs out;
  Drive(sim, "r", 0.3, 0.2, 2.0, &out);
  ASSERT_TRUE(sim.ResetRobot("r", 4.0, -3.0, 1.0).ok());
  EXPECT_NEAR(sim.RobotPose("r").position_m.x(), 4.0, 1e-9);
  EXPECT_NEAR(sim.RobotPose("r").yaw_rad(), 1.0, 1e-9);
  EXPECT_NEAR(sim.FindSensor<OdometrySensor>("r")->pose().x_m, 4.0, 1e-9);
  while (sim.time_s() < 3.0) sim.Step(&out);
  EXPECT_NEAR(sim.RobotPose("r").position_m.x(), 4.0, 0.01);
  EXPECT_NEAR(sim.RobotPose("r").position_m.z(), 0.0975, 0.005);
  EXPECT_EQ(sim.ResetRobot("nobody", 0, 0, 0).code(), common::StatusCode::kNotFound);
  EXPECT_EQ(sim.ResetRobot("r", std::nan(""), 0, 0).code(), common::StatusCode::kInvalidArgument);
}

TEST(UnstablePhysicsTest, AnUnstableStepIsUndoneTheClockRunsOnAndItIsSaidOnce) {
  InstallMujocoLogHooks();
  const int64_t warnings_before = MujocoWarningCount();
  // A 1 g wheel on a hinge driven by a constant 1e12 N m (a bias-only actuator): its
  // acceleration is far beyond MuJoCo's bound (mjWARN_BADQACC), and MuJoCo then resets all of
  // mjData, time 0 and the robot at the model's origin included. The step is undone instead:
  // the robot stays where it was, the clock runs on, and one event line a second says so.
  Scenario s = InlineScenario(FlatWorld(R"(<body name="wheel" pos="3 3 1">
      <joint name="spin" type="hinge" axis="0 0 1"/>
      <geom type="cylinder" size="0.1 0.01" mass="0.001" contype="0" conaffinity="0"/>
    </body>
  </worldbody>
  <actuator>
    <general joint="spin" biastype="affine" biasprm="1e12 0 0"/>
  </actuator>
  <worldbody>)"),
                              "r", "p3dx", 1.0, -2.0);
  s.robots[0].sensors = SensorSet{};
  MujocoSim sim(s);
  SimOutputs out;
  double last = sim.time_s();
  bool monotonic = true;
  for (int i = 0; i < 1000; ++i) {  // 2 s
    sim.Command("r", 0.0, 0.0);
    sim.Step(&out);
    monotonic &= sim.time_s() > last;
    last = sim.time_s();
  }
  EXPECT_TRUE(monotonic);
  EXPECT_NEAR(sim.time_s(), 2.0, 1e-6);
  EXPECT_GT(sim.stats().unstable_steps, 0);
  EXPECT_NEAR(sim.RobotPose("r").position_m.x(), 1.0, 0.01);
  EXPECT_NEAR(sim.RobotPose("r").position_m.y(), -2.0, 0.01);
  int lines = 0;
  for (const auto& e : out.events) lines += e.find("physics unstable") != std::string::npos;
  EXPECT_GE(lines, 1);
  EXPECT_LE(lines, 3);                               // one a second of sim time at most
  EXPECT_GT(MujocoWarningCount(), warnings_before);  // MuJoCo's own warning, rate-limited
}

class SensorRatesTest : public SimTest {};

TEST_F(SensorRatesTest, EverySensorAtItsRate) {
  Scenario s = InlineScenario(FlatWorld(), "r", "pioneer3at");
  s.robots[0].sensors.Set<TurretSensor>(TurretParams{});
  MujocoSim sim(s);
  SimOutputs out;
  while (sim.time_s() < 2.0 - 1e-9) sim.Step(&out);
  EXPECT_EQ(out.Readings<LidarSensor>().size(), 2u * 10u * 10u);  // 10 Hz x 10 slices for 2 s
  EXPECT_EQ(out.Readings<PlanarLaserSensor>().size(), 20u);
  EXPECT_EQ(out.Readings<TurretSensor>().size(), 100u);
  EXPECT_EQ(out.Readings<OdometrySensor>().size(), 100u);
  EXPECT_EQ(out.Readings<GroundTruthSensor>().size(), 100u);
  EXPECT_EQ(out.Readings<ImuSensor>().size(), 200u);
  // Readings carry sim time.
  EXPECT_EQ(out.Readings<GroundTruthSensor>().back().utime, sim.utime());
  EXPECT_EQ(out.Readings<GroundTruthSensor>().front().utime, 20000);
}

class DeterminismTest : public SimTest {};

TEST_F(DeterminismTest, SameSeedSameRunDifferentSeedDifferentNoise) {
  // The readings compared: ground truth, lidar and odometry.
  struct Run {
    std::vector<common::LidarSlice> lidar;
    std::vector<GroundTruthReading> poses;
    std::vector<OdometryReading> odometry;
  };
  auto run = [](uint64_t seed) {
    Scenario s = InlineScenario(FlatWorld(R"(<geom type="box" size="0.5 0.5 0.5" pos="3 1 0.5"/>)"),
                                "r", "pioneer3at");
    s.seed = seed;
    s.robots[0].sensors.Find<OdometrySensor>()->slip_noise_ratio = 0.05;
    s.robots[0].commands = {{0.0, 2.0, 0.4, 0.3}, {2.0, 1.0, 0.2, -0.5}};
    MujocoSim sim(s);
    SimOutputs out;
    while (sim.time_s() < 3.0) sim.Step(&out);
    return Run{out.Readings<LidarSensor>(), out.Readings<GroundTruthSensor>(),
               out.Readings<OdometrySensor>()};
  };
  const Run a = run(11), b = run(11), c = run(12);
  ASSERT_EQ(a.poses.size(), b.poses.size());
  for (size_t i = 0; i < a.poses.size(); ++i) {
    ASSERT_EQ(a.poses[i].pose.position_m, b.poses[i].pose.position_m) << i;
    ASSERT_EQ(a.poses[i].pose.orientation.coeffs(), b.poses[i].pose.orientation.coeffs()) << i;
  }
  EXPECT_GT(a.poses.back().pose.position_m.norm(), 0.5);  // it did move
  ASSERT_EQ(a.lidar.size(), b.lidar.size());
  bool lidar_differs_with_seed = false;
  for (size_t i = 0; i < a.lidar.size(); ++i) {
    // The HDL-32E's slices are range images: equal to the last step and the last byte.
    ASSERT_FALSE(a.lidar[i].range_steps.empty()) << i;
    ASSERT_EQ(a.lidar[i].range_steps, b.lidar[i].range_steps) << i;
    ASSERT_EQ(a.lidar[i].range_intensity, b.lidar[i].range_intensity) << i;
    if (c.lidar[i].range_steps != a.lidar[i].range_steps) lidar_differs_with_seed = true;
  }
  EXPECT_TRUE(lidar_differs_with_seed);
  EXPECT_NE(a.odometry.back().pose.position_m, c.odometry.back().pose.position_m);
}

}  // namespace
}  // namespace cairn::sim
