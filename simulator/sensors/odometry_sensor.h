#pragma once

#include <cstdint>
#include <string>

#include "common/types.h"
#include "common/yaml_reader.h"
#include "simulator/sim_sensor.h"

/// @file
/// odometry: wheel odometry integrated from the wheel joints' rotation over every physics step.
/// Each step's travel of the left and right wheels is scaled by (1 + n) with
/// n ~ N(0, slip_noise_ratio^2): with noise the estimate drifts, without it the integration is
/// exact. The frame `odom` starts at the spawn (or reset) pose.

namespace cairn::sim {

struct OdometryParams {
  double rate_hz{50.0};
  double slip_noise_ratio{0.0};

  /// @throws std::invalid_argument naming the bad field.
  void Validate() const;
};

/// Overrides of `defaults` from a scenario's `odometry:` map (every key optional).
/// @throws common::ConfigError naming the file and line of an unknown key or a bad value.
OdometryParams LoadOdometryParams(common::YamlMap& map, const OdometryParams& defaults = {});

/// Planar dead reckoning from left and right wheel rotation. Each increment is integrated as an
/// arc of constant curvature, so noise-free input reproduces the true path of a rolling robot.
class WheelOdometry {
 public:
  WheelOdometry(const OdometryParams& params, double wheel_radius_m, double track_m,
                NoiseSource noise);

  void Reset(const common::Pose2& pose);
  /// Adds one step: wheel rotation increments (rad) over dt_s, and a sideways travel (m, body
  /// frame, left positive; an AUV's sway) applied at the step's mean heading.
  void Integrate(double left_delta_rad, double right_delta_rad, double dt_s,
                 double lateral_m = 0.0);

  const common::Pose2& pose() const { return pose_; }
  double linear_mps() const { return linear_mps_; }
  double angular_radps() const { return angular_radps_; }

 private:
  OdometryParams params_;
  double wheel_radius_m_;
  double track_m_;
  NoiseSource noise_;
  uint64_t counter_{0};
  common::Pose2 pose_;
  double linear_mps_{0.0};
  double angular_radps_{0.0};
};

/// Pose of the base in the odometry frame, and the twist in the base frame.
struct OdometryReading {
  int64_t utime{0};
  std::string robot;
  common::Pose3 pose;
  common::Vector3 linear_velocity_mps{common::Vector3::Zero()};
  common::Vector3 angular_velocity_radps{common::Vector3::Zero()};
};

class OdometrySensor final : public SimSensor {
 public:
  static constexpr char kName[] = "odometry";
  static constexpr char kDescription[] =
      "wheel odometry from wheel joint rotation, optional slip noise, on <robot>.ODOM";
  using Params = OdometryParams;
  using Reading = OdometryReading;
  static constexpr auto kLoadParams = &LoadOdometryParams;

  OdometrySensor(const OdometryParams& params, const SensorContext& context);

  bool Due(double now_s) const override { return schedule_.Due(now_s); }
  void Produce(const SensorFrame& frame, SimOutputs* out) override;
  void OnStep(const StepMotion& motion) override;
  void OnPlaced(const common::Pose2& pose, double z_m) override;

  /// The current estimate (odometry frame).
  const common::Pose2& pose() const { return odometry_.pose(); }

 private:
  std::string robot_;
  SensorSchedule schedule_;
  WheelOdometry odometry_;
  double z_m_{0.0};  ///< planar odometry: the base height at the spawn
};

}  // namespace cairn::sim
