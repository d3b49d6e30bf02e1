#include "simulator/sensors/imu_sensor.h"

#include <cmath>

#include <gtest/gtest.h>

#include "simulator/mujoco_sim.h"
#include "tests/unit/simulator/sim_test_util.h"

namespace cairn::sim {
namespace {

using testing::FlatWorld;
using testing::InlineScenario;
using testing::SimTest;

class ImuSensorTest : public SimTest {};

TEST_F(ImuSensorTest, ImuReadsGravityAtRest) {
  Scenario s = InlineScenario(FlatWorld(), "r", "pioneer3at");
  MujocoSim sim(s);
  SimOutputs out;
  while (sim.time_s() < 1.0) sim.Step(&out);
  ASSERT_FALSE(out.Readings<ImuSensor>().empty());
  const ImuReading& imu = out.Readings<ImuSensor>().back();
  EXPECT_NEAR(imu.linear_acceleration_mps2.z(), 9.81, 0.1);
  EXPECT_NEAR(imu.angular_velocity_radps.norm(), 0.0, 0.02);
  EXPECT_NEAR(imu.orientation.angularDistance(common::Quaternion::Identity()), 0.0, 0.02);
}

TEST_F(ImuSensorTest, WithoutNoiseItIsMujocosSensorsAndCarriesTheVariances) {
  Scenario s = InlineScenario(FlatWorld(), "r", "pioneer3at");
  ImuParams& p = *s.robots[0].sensors.Find<ImuSensor>();
  p.gyro_noise_sigma_radps = 0.0;
  p.accel_noise_sigma_mps2 = 0.0;
  p.orientation_noise_sigma_rad = 0.0;
  MujocoSim sim(s);
  SimOutputs out;
  sim.Command("r", 0.3, 0.5);
  while (sim.time_s() < 0.5 - 1e-9) {
    sim.Command("r", 0.3, 0.5);
    sim.Step(&out);
  }
  const auto& readings = out.Readings<ImuSensor>();
  ASSERT_EQ(readings.size(), 50u);  // 100 Hz
  const ImuReading& last = readings.back();
  EXPECT_EQ(last.utime, 500000);
  const mjModel* m = sim.model();
  const double* data = sim.data()->sensordata;
  for (int i = 0; i < m->nsensor; ++i) {
    const double* v = data + m->sensor_adr[i];
    if (m->sensor_type[i] == mjSENS_GYRO) {
      EXPECT_EQ(last.angular_velocity_radps, common::Vector3(v[0], v[1], v[2]));
    } else if (m->sensor_type[i] == mjSENS_ACCELEROMETER) {
      EXPECT_EQ(last.linear_acceleration_mps2, common::Vector3(v[0], v[1], v[2]));
    }
  }
  EXPECT_GT(last.angular_velocity_radps.z(), 0.1);  // it is turning
  EXPECT_EQ(last.orientation_variance_rad2, 0.0);

  // With noise the variances are the sigmas squared.
  Scenario noisy = InlineScenario(FlatWorld(), "r", "pioneer3at");
  MujocoSim sim2(noisy);
  SimOutputs out2;
  while (sim2.time_s() < 0.1 - 1e-9) sim2.Step(&out2);
  const ImuParams defaults;
  const ImuReading& r = out2.Readings<ImuSensor>().back();
  EXPECT_DOUBLE_EQ(r.angular_velocity_variance, std::pow(defaults.gyro_noise_sigma_radps, 2));
  EXPECT_DOUBLE_EQ(r.linear_acceleration_variance, std::pow(defaults.accel_noise_sigma_mps2, 2));
  EXPECT_DOUBLE_EQ(r.orientation_variance_rad2, std::pow(defaults.orientation_noise_sigma_rad, 2));
}

TEST_F(ImuSensorTest, ASiteWithoutInertialSensorsIsRefusedWithTheReason) {
  Scenario s = InlineScenario(FlatWorld(), "r", "p3dx");
  s.robots[0].sensors.Set<ImuSensor>().site = "laser_mount";
  try {
    MujocoSim sim(s);
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("robot 'r'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("sensor 'imu' needs gyro, accelerometer and framequat "
                                         "sensors on site 'laser_mount'"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace cairn::sim
