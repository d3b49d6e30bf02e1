#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "common/point_cloud.h"
#include "common/yaml_reader.h"
#include "simulator/ray_caster.h"
#include "simulator/sim_sensor.h"
#include <Eigen/Core>

/// @file
/// turret: a planar laser on a rotating turret (seed 002). The scanning plane is vertical and
/// turns about the turret's z axis one pan step per line, so a robot that stands still gets a
/// full 3-D scan every pan_range_deg / pan_step_deg lines.

namespace cairn::sim {

struct TurretParams {
  double fan_fov_deg{270.0};  ///< centred on the turret's up axis
  int fan_beams{541};         ///< 0.5 deg between beams
  double max_range_m{50.0};
  double min_range_m{0.05};
  double line_rate_hz{50.0};
  double pan_step_deg{0.5};
  double pan_range_deg{180.0};  ///< one full scan
  double range_noise_sigma_m{0.01};
  std::string mount_site{"turret_mount"};

  /// @throws std::invalid_argument naming the bad field.
  void Validate() const;
};

/// Overrides of `defaults` from a scenario's `turret:` map (every key optional).
/// @throws common::ConfigError naming the file and line of an unknown key or a bad value.
TurretParams LoadTurretParams(common::YamlMap& map, const TurretParams& defaults = {});

/// Rotation from a turret line's scanning frame to the turret frame at pan angle `pan_rad`:
/// the line's x axis is the turret's up axis and its y axis the horizontal pan direction, so
/// beam angle 0 points up and +90 deg points horizontally along the pan direction.
Eigen::Matrix3d TurretLineRotation(double pan_rad);

/// One line of a turret scanner: a planar scan in the line's frame and the pan angle.
struct TurretLine {
  common::LaserScan scan;
  double pan_rad{0.0};
  int64_t line{0};
  double line_period_s{0.0};  ///< 1 / line rate
};

class TurretSensor final : public SimSensor {
 public:
  static constexpr char kName[] = "turret";
  static constexpr char kDescription[] =
      "planar laser on a rotating turret: 270 deg vertical fan, 0.5 deg pan steps, 50 m, "
      "50 lines/s on <robot>.TURRET_SCAN";
  using Params = TurretParams;
  using Reading = TurretLine;
  static constexpr auto kLoadParams = &LoadTurretParams;

  TurretSensor(const TurretParams& params, const SensorContext& context);

  bool Due(double now_s) const override { return schedule_.Due(now_s); }
  bool CastsRays() const override { return true; }
  void Produce(const SensorFrame& frame, SimOutputs* out) override;

 private:
  TurretParams params_;
  RayPattern pattern_;
  std::string robot_;
  int site_{-1};
  int pan_steps_{1};
  SensorSchedule schedule_;
  std::vector<RayHit> hits_;
  NoiseSource noise_;
};

}  // namespace cairn::sim
