#pragma once

#include <cstdint>
#include <string>

#include "common/types.h"
#include "common/yaml_reader.h"
#include "simulator/sim_sensor.h"

/// @file
/// imu: inertial measurement at a robot site from MuJoCo's gyro, accelerometer and framequat
/// sensors on that site, with Gaussian noise. The specific force includes gravity.

namespace cairn::sim {

struct ImuParams {
  double rate_hz{100.0};
  double gyro_noise_sigma_radps{0.002};
  double accel_noise_sigma_mps2{0.02};
  double orientation_noise_sigma_rad{0.002};
  std::string site{"imu"};

  /// @throws std::invalid_argument naming the bad field.
  void Validate() const;
};

/// Overrides of `defaults` from a scenario's `imu:` map (every key optional).
/// @throws common::ConfigError naming the file and line of an unknown key or a bad value.
ImuParams LoadImuParams(common::YamlMap& map, const ImuParams& defaults = {});

/// Orientation of the IMU frame in the world, rates and specific force in the IMU frame.
struct ImuReading {
  int64_t utime{0};
  std::string robot;
  common::Quaternion orientation{common::Quaternion::Identity()};
  common::Vector3 angular_velocity_radps{common::Vector3::Zero()};
  common::Vector3 linear_acceleration_mps2{common::Vector3::Zero()};
  double orientation_variance_rad2{0.0};
  double angular_velocity_variance{0.0};
  double linear_acceleration_variance{0.0};
};

class ImuSensor final : public SimSensor {
 public:
  static constexpr char kName[] = "imu";
  static constexpr char kDescription[] =
      "orientation, angular rate and specific force with noise on <robot>.IMU";
  using Params = ImuParams;
  using Reading = ImuReading;
  static constexpr auto kLoadParams = &LoadImuParams;

  /// @throws std::invalid_argument when the site lacks a gyro, accelerometer or framequat.
  ImuSensor(const ImuParams& params, const SensorContext& context);

  bool Due(double now_s) const override { return schedule_.Due(now_s); }
  void Produce(const SensorFrame& frame, SimOutputs* out) override;

 private:
  ImuParams params_;
  std::string robot_;
  int gyro_adr_{-1}, accel_adr_{-1}, quat_adr_{-1};  ///< in sensordata
  SensorSchedule schedule_;
  NoiseSource noise_;
};

}  // namespace cairn::sim
