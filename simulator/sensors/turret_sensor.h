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
///
/// Two modes. Continuous (the default): it sweeps forever, line n at (n + 1) / line_rate_hz at
/// pan step n mod pan_steps; Trigger is accepted and changes nothing (every pan_steps lines
/// are a full scan anyway). On request (`on_request: true`, stop-and-scan): it is idle until
/// Trigger(now_s), which arms exactly one sweep: pan steps 0, 1, ..., pan_steps - 1, one line
/// per line time (the times k / line_rate_hz) starting at the first one after now_s, then idle
/// again. A Trigger during a sweep starts it over at pan step 0. Line numbers never repeat: in
/// continuous mode a line's number is its line time's, on request they count the lines produced
/// (so they run on from one sweep to the next). A physics step longer than a line period never
/// makes a burst of lines: one line per step at most; in continuous mode the pan moves on with
/// the line times (steps are skipped), on request the sweep takes longer but skips no pan step.

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
  /// Idle until triggered (SIM.CONTROL OP_TRIGGER_SENSOR), then one sweep; else continuous.
  bool on_request{false};

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
      "50 lines/s on <robot>.TURRET_SCAN, continuous or one sweep per trigger (on_request)";
  using Params = TurretParams;
  using Reading = TurretLine;
  static constexpr auto kLoadParams = &LoadTurretParams;

  TurretSensor(const TurretParams& params, const SensorContext& context);

  bool Due(double now_s) const override {
    return (!params_.on_request || sweep_step_ >= 0) && schedule_.Due(now_s);
  }
  bool CastsRays() const override { return true; }
  void Produce(const SensorFrame& frame, SimOutputs* out) override;
  /// On request: arms one sweep from pan step 0 (restarting one that runs). Continuous: Ok,
  /// nothing changes. Always Ok.
  common::Status Trigger(double now_s) override;

  /// Lines per full scan: pan_range_deg / pan_step_deg, rounded.
  int pan_steps() const { return pan_steps_; }
  /// On request: a sweep is armed or running.
  bool sweeping() const { return sweep_step_ >= 0; }

 private:
  TurretParams params_;
  RayPattern pattern_;
  std::string robot_;
  int site_{-1};
  int pan_steps_{1};
  SensorSchedule schedule_;  ///< line times passed
  int sweep_step_{-1};       ///< on request: the next line's pan step, -1 when idle
  int64_t lines_{0};         ///< on request: lines produced so far
  std::vector<RayHit> hits_;
  NoiseSource noise_;
};

}  // namespace cairn::sim
