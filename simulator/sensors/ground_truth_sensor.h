#pragma once

#include <cstdint>
#include <string>

#include "common/types.h"
#include "common/yaml_reader.h"
#include "simulator/sim_sensor.h"

/// @file
/// ground_truth: the true pose and velocity of the robot base.

namespace cairn::sim {

struct GroundTruthParams {
  double rate_hz{50.0};

  /// @throws std::invalid_argument naming the bad field.
  void Validate() const;
};

/// Overrides of `defaults` from a scenario's `ground_truth:` map (every key optional).
/// @throws common::ConfigError naming the file and line of an unknown key or a bad value.
GroundTruthParams LoadGroundTruthParams(common::YamlMap& map,
                                        const GroundTruthParams& defaults = {});

/// True pose of the robot base; velocities in the world frame.
struct GroundTruthReading {
  int64_t utime{0};
  std::string robot;
  common::Pose3 pose;
  common::Vector3 linear_velocity_mps{common::Vector3::Zero()};
  common::Vector3 angular_velocity_radps{common::Vector3::Zero()};
};

class GroundTruthSensor final : public SimSensor {
 public:
  static constexpr char kName[] = "ground_truth";
  static constexpr char kDescription[] = "true pose and velocity of the robot base on <robot>.POSE";
  using Params = GroundTruthParams;
  using Reading = GroundTruthReading;
  static constexpr auto kLoadParams = &LoadGroundTruthParams;

  GroundTruthSensor(const GroundTruthParams& params, const SensorContext& context);

  bool Due(double now_s) const override { return schedule_.Due(now_s); }
  void Produce(const SensorFrame& frame, SimOutputs* out) override;

 private:
  std::string robot_;
  int qpos_adr_{0};
  int qvel_adr_{0};
  SensorSchedule schedule_;
};

}  // namespace cairn::sim
