#include "simulator/sensors/turret_sensor.h"

#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "common/yaml_reader.h"
#include "simulator/mujoco_sim.h"
#include "simulator/sensors/planar_laser_sensor.h"
#include "tests/unit/simulator/sim_test_util.h"

namespace cairn::sim {
namespace {

using testing::FlatWorld;
using testing::InlineScenario;
using testing::SimTest;

constexpr double kDeg = M_PI / 180.0;

TEST(TurretLineRotationTest, BeamZeroPointsUpAndNinetyDegreesAlongThePan) {
  for (double pan : {0.0, 30.0 * kDeg, 90.0 * kDeg}) {
    const Eigen::Matrix3d r = TurretLineRotation(pan);
    EXPECT_TRUE(r.col(0).isApprox(Eigen::Vector3d::UnitZ())) << pan;
    EXPECT_TRUE(r.col(1).isApprox(Eigen::Vector3d(std::cos(pan), std::sin(pan), 0.0))) << pan;
    EXPECT_NEAR(r.determinant(), 1.0, 1e-12);
    EXPECT_TRUE((r.transpose() * r).isIdentity(1e-12));
  }
}

class TurretSensorTest : public SimTest {};

TEST_F(TurretSensorTest, TurretSweepsThePanRange) {
  Scenario s = InlineScenario(FlatWorld(R"(<geom type="box" size="0.1 3 2" pos="4 0 2"/>)"), "r",
                              "pioneer3at");
  s.robots[0].sensors = SensorSet{};
  TurretParams turret;
  turret.range_noise_sigma_m = 0.0;
  s.robots[0].sensors.Set<TurretSensor>(turret);
  MujocoSim sim(s);
  SimOutputs out;
  while (sim.time_s() < 7.3) sim.Step(&out);  // 360 lines at 50 Hz
  ASSERT_GE(out.Readings<TurretSensor>().size(), 360u);
  EXPECT_NEAR(out.Readings<TurretSensor>()[0].pan_rad, 0.0, 1e-12);
  EXPECT_NEAR(out.Readings<TurretSensor>()[1].pan_rad, 0.5 * kDeg, 1e-12);
  EXPECT_NEAR(out.Readings<TurretSensor>()[359].pan_rad, 179.5 * kDeg, 1e-9);
  EXPECT_NEAR(out.Readings<TurretSensor>()[360].pan_rad, 0.0, 1e-12);  // next sweep
  // At pan 0 the beam at +90 deg points along the turret's x axis, at the wall 4 m ahead.
  const common::LaserScan& scan = out.Readings<TurretSensor>()[0].scan;
  const int beam =
      static_cast<int>(std::lround((M_PI / 2 - scan.angle_min_rad) / scan.angle_increment_rad));
  const common::Vector3 end = scan.sensor_pose.Transform(
      common::Vector3(std::cos(scan.angle_min_rad + beam * scan.angle_increment_rad),
                      std::sin(scan.angle_min_rad + beam * scan.angle_increment_rad), 0.0) *
      scan.ranges_m[beam]);
  EXPECT_NEAR(end.x(), 3.9, 1e-3);
}

// A small on-request turret: 10 deg in 0.5 deg steps (20 lines a sweep, 0.4 s at 50 Hz).
TurretParams SmallOnRequestTurret() {
  TurretParams turret;
  turret.range_noise_sigma_m = 0.0;
  turret.fan_beams = 55;
  turret.fan_fov_deg = 270.0;
  turret.pan_range_deg = 10.0;
  turret.pan_step_deg = 0.5;
  turret.on_request = true;
  return turret;
}

Scenario TurretScenario(const TurretParams& turret, bool with_planar_laser = false) {
  Scenario s = InlineScenario(FlatWorld(R"(<geom type="box" size="0.1 3 2" pos="4 0 2"/>)"), "r",
                              "pioneer3at");
  s.robots[0].sensors = SensorSet{};
  s.robots[0].sensors.Set<TurretSensor>(turret);
  if (with_planar_laser) s.robots[0].sensors.Set<PlanarLaserSensor>(PlanarLaserParams{});
  return s;
}

void RunFor(MujocoSim& sim, double duration_s, SimOutputs* out) {
  const double end = sim.time_s() + duration_s;
  while (sim.time_s() < end) sim.Step(out);
}

// Steps until `count` turret lines have come out in all.
void RunUntilLines(MujocoSim& sim, size_t count, SimOutputs* out) {
  for (int i = 0; i < 100000 && out->Readings<TurretSensor>().size() < count; ++i) sim.Step(out);
}

// Lines [begin, begin + n) are pan steps 0..n-1 in order, numbered first_line on, one line time
// apart.
void ExpectSweep(const std::vector<TurretLine>& lines, size_t begin, int n, int64_t first_line,
                 const TurretParams& p) {
  ASSERT_GE(lines.size(), begin + n);
  for (int k = 0; k < n; ++k) {
    const TurretLine& line = lines[begin + k];
    EXPECT_NEAR(line.pan_rad, k * p.pan_step_deg * kDeg, 1e-12) << k;
    EXPECT_EQ(line.line, first_line + k) << k;
    if (k > 0) {
      EXPECT_NEAR(line.scan.utime - lines[begin + k - 1].scan.utime, 1e6 / p.line_rate_hz, 1.0)
          << k;
    }
  }
}

TEST(TurretParamsTest, OnRequestIsReadFromYamlAndOffByDefault) {
  EXPECT_FALSE(TurretParams{}.on_request);
  common::YamlMap map = common::YamlMap::FromString("on_request: true\n", "robot.yaml");
  EXPECT_TRUE(LoadTurretParams(map).on_request);
  common::YamlMap bad = common::YamlMap::FromString("on_request: maybe\n", "robot.yaml");
  EXPECT_THROW(LoadTurretParams(bad), common::ConfigError);
}

TEST_F(TurretSensorTest, OnRequestTurretIsIdleUntilTriggeredThenSweepsOnce) {
  const TurretParams p = SmallOnRequestTurret();
  MujocoSim sim(TurretScenario(p));
  const TurretSensor* turret = sim.FindSensor<TurretSensor>("r");
  ASSERT_NE(turret, nullptr);
  EXPECT_EQ(turret->pan_steps(), 20);
  SimOutputs out;
  RunFor(sim, 0.5, &out);
  EXPECT_TRUE(out.Readings<TurretSensor>().empty());
  EXPECT_FALSE(turret->Due(sim.time_s() + 10.0));

  const int64_t triggered_utime = sim.utime();
  ASSERT_TRUE(sim.TriggerSensor("r", "turret").ok());
  EXPECT_TRUE(turret->sweeping());
  RunFor(sim, 1.0, &out);  // the sweep takes 0.4 s
  const std::vector<TurretLine>& lines = out.Readings<TurretSensor>();
  ASSERT_EQ(lines.size(), 20u);
  ExpectSweep(lines, 0, 20, 0, p);
  // The first line at the first line time after the trigger.
  EXPECT_GT(lines[0].scan.utime, triggered_utime);
  EXPECT_LE(lines[0].scan.utime, triggered_utime + 20000);
  EXPECT_EQ(lines[0].scan.utime % 20000, 0);
  EXPECT_FALSE(turret->sweeping());  // idle again
  // A real line: at pan 0 the beam at +90 deg reaches the wall 4 m ahead.
  const common::LaserScan& scan = lines[0].scan;
  const int beam =
      static_cast<int>(std::lround((M_PI / 2 - scan.angle_min_rad) / scan.angle_increment_rad));
  const double angle = scan.angle_min_rad + beam * scan.angle_increment_rad;
  const common::Vector3 end = scan.sensor_pose.Transform(
      common::Vector3(std::cos(angle), std::sin(angle), 0.0) * scan.ranges_m[beam]);
  EXPECT_NEAR(end.x(), 3.9, 1e-3);
}

TEST_F(TurretSensorTest, SecondTriggerGivesAnotherSweepWithLineNumbersRunningOn) {
  const TurretParams p = SmallOnRequestTurret();
  MujocoSim sim(TurretScenario(p));
  SimOutputs out;
  ASSERT_TRUE(sim.TriggerSensor("r", "turret").ok());
  RunFor(sim, 0.6, &out);
  ASSERT_EQ(out.Readings<TurretSensor>().size(), 20u);
  RunFor(sim, 1.0, &out);
  EXPECT_EQ(out.Readings<TurretSensor>().size(), 20u);  // still idle
  ASSERT_TRUE(sim.TriggerSensor("r", "turret").ok());
  RunFor(sim, 0.6, &out);
  const std::vector<TurretLine>& lines = out.Readings<TurretSensor>();
  ASSERT_EQ(lines.size(), 40u);
  ExpectSweep(lines, 0, 20, 0, p);
  ExpectSweep(lines, 20, 20, 20, p);
}

TEST_F(TurretSensorTest, TriggerDuringASweepStartsItOverAtPanZero) {
  const TurretParams p = SmallOnRequestTurret();
  MujocoSim sim(TurretScenario(p));
  SimOutputs out;
  ASSERT_TRUE(sim.TriggerSensor("r", "turret").ok());
  RunUntilLines(sim, 7, &out);
  ASSERT_EQ(out.Readings<TurretSensor>().size(), 7u);
  ASSERT_TRUE(sim.TriggerSensor("r", "turret").ok());
  RunFor(sim, 1.0, &out);
  const std::vector<TurretLine>& lines = out.Readings<TurretSensor>();
  ASSERT_EQ(lines.size(), 27u);
  ExpectSweep(lines, 0, 7, 0, p);
  ExpectSweep(lines, 7, 20, 7, p);  // pan 0 again, numbers running on, no line time missed
}

TEST_F(TurretSensorTest, OnRequestSweepSkipsNoPanStepWhenLinesComeFasterThanSteps) {
  TurretParams p = SmallOnRequestTurret();
  p.line_rate_hz = 1250.0;  // 2.5 line times per 2 ms physics step
  MujocoSim sim(TurretScenario(p));
  SimOutputs out;
  ASSERT_TRUE(sim.TriggerSensor("r", "turret").ok());
  const int64_t steps = sim.physics_steps();
  RunFor(sim, 0.2, &out);
  const std::vector<TurretLine>& lines = out.Readings<TurretSensor>();
  ASSERT_EQ(lines.size(), 20u);
  for (int k = 0; k < 20; ++k) {
    EXPECT_NEAR(lines[k].pan_rad, k * 0.5 * kDeg, 1e-12) << k;
    EXPECT_EQ(lines[k].line, k);
    if (k > 0) {
      EXPECT_GT(lines[k].scan.utime, lines[k - 1].scan.utime) << "a burst at " << k;
    }
  }
  EXPECT_GE(sim.physics_steps() - steps, 20);
}

TEST_F(TurretSensorTest, ContinuousTurretAcceptsATriggerAndSweepsOnUnchanged) {
  TurretParams p = SmallOnRequestTurret();
  p.on_request = false;
  MujocoSim sim(TurretScenario(p));
  SimOutputs out;
  RunUntilLines(sim, 5, &out);
  EXPECT_TRUE(sim.TriggerSensor("r", "turret").ok());
  RunUntilLines(sim, 45, &out);
  const std::vector<TurretLine>& lines = out.Readings<TurretSensor>();
  ASSERT_EQ(lines.size(), 45u);
  for (int k = 0; k < 45; ++k) {
    EXPECT_NEAR(lines[k].pan_rad, (k % 20) * 0.5 * kDeg, 1e-12) << k;
    EXPECT_EQ(lines[k].line, k);
  }
}

TEST_F(TurretSensorTest, TriggerRefusesUnknownRobotsSensorsAndKindsWithoutOnRequestMode) {
  MujocoSim sim(TurretScenario(SmallOnRequestTurret(), /*with_planar_laser=*/true));
  const common::Status no_robot = sim.TriggerSensor("nobody", "turret");
  EXPECT_EQ(no_robot.code(), common::StatusCode::kNotFound) << no_robot.ToString();
  const common::Status no_sensor = sim.TriggerSensor("r", "hdl32e");
  EXPECT_EQ(no_sensor.code(), common::StatusCode::kNotFound) << no_sensor.ToString();
  EXPECT_EQ(sim.TriggerSensor("r", "").code(), common::StatusCode::kNotFound);
  const common::Status laser = sim.TriggerSensor("r", "planar_laser");
  EXPECT_EQ(laser.code(), common::StatusCode::kInvalidArgument) << laser.ToString();
  EXPECT_NE(laser.message().find("planar_laser"), std::string::npos) << laser.message();
  EXPECT_NE(laser.message().find("no on-request mode"), std::string::npos) << laser.message();
  // The refusal changed nothing: the turret is still idle.
  SimOutputs out;
  RunFor(sim, 0.2, &out);
  EXPECT_TRUE(out.Readings<TurretSensor>().empty());
  EXPECT_FALSE(out.Readings<PlanarLaserSensor>().empty());
}

}  // namespace
}  // namespace cairn::sim
