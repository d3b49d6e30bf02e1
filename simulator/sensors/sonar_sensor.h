#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "common/types.h"
#include "common/yaml_reader.h"
#include "simulator/ray_caster.h"
#include "simulator/sim_sensor.h"
#include "simulator/sonar_model.h"

/// @file
/// sonar: seed 004's mechanically scanned imaging sonar (a Tritech Miniking-like MSIS). Each ping
/// casts a vertical fan of rays (2001 over ±20°) in the head's direction, turns their ranges into
/// an echo profile of 1 m bins (sonar_model.h), and steps the head through its ±60° sector. The
/// pings come at the rate the speed of sound allows: one round trip to range_max (plus
/// ping_overhead_s) apart.
///
/// Two modes (`mode`):
/// - faithful: the thesis as it ran: its echo model, the head's angle published one step after
///   the ping was taken (§3.2.2), no noise;
/// - default: the geometric echo model, the angle the ping was taken at, Gaussian noise on the
///   bins that echo (a shadow stays 0).

namespace cairn::sim {

struct SonarParams {
  std::string mode{"default"};  ///< default or faithful
  int rays{2001};
  double half_aperture_deg{20.0};  ///< the fan: γ 40°
  double range_min_m{0.0};
  double range_max_m{50.0};
  double bin_m{1.0};
  double sector_deg{60.0};  ///< the head sweeps ±sector_deg
  double step_rad{0.005};   ///< per ping
  double start_deg{35.0};
  bool continuous{false};             ///< 360° rotation instead of the sector
  double sound_speed_mps{1500.0};     ///< sea water (the thesis's text: 1550)
  double ping_overhead_s{0.0};        ///< added to the round trip between pings
  double intensity_noise_sigma{4.0};  ///< default mode, on echoing bins (0..255 scale)
  std::string mount_site{"sonar_mount"};

  /// @throws std::invalid_argument naming the bad field.
  void Validate() const;
  bool faithful() const { return mode == "faithful"; }
  SonarFanParams Fan() const;
  SonarSweepParams Sweep() const;
  /// 2 · range_max / sound_speed + ping_overhead_s.
  double PingPeriodS() const;
};

/// Overrides of `defaults` from a scenario's `sonar:` map (every key optional).
/// @throws common::ConfigError naming the file and line of an unknown key or a bad value.
SonarParams LoadSonarParams(common::YamlMap& map, const SonarParams& defaults = {});

/// One ping: one beam of bins at the head's angle.
struct SonarPing {
  int64_t utime{0};
  std::string robot;
  common::Pose3 sensor_pose;  ///< the head at the ping: x along the beam, z up
  double pan_rad{0.0};        ///< the head's angle from the mount's x axis, positive left
  double range_min_m{0.0};
  double range_max_m{50.0};
  double sound_speed_mps{1500.0};
  std::vector<uint8_t> bins;  ///< intensity 0..255 per bin, nearest first
};

/// The fan in the head's frame: ray i at elevation -half_aperture + i · increment in the x-z
/// plane, the lowest first.
RayPattern BuildSonarFanPattern(const SonarFanParams& fan);

class SonarSensor final : public SimSensor {
 public:
  static constexpr char kName[] = "sonar";
  static constexpr char kDescription[] =
      "mechanically scanned imaging sonar (seed 004: a vertical fan, 1 m bins, a ±60° sweep) on "
      "<robot>.SONAR";
  using Params = SonarParams;
  using Reading = SonarPing;
  static constexpr auto kLoadParams = &LoadSonarParams;

  SonarSensor(const SonarParams& params, const SensorContext& context);

  bool Due(double now_s) const override { return schedule_.Due(now_s); }
  bool CastsRays() const override { return true; }
  void Produce(const SensorFrame& frame, SimOutputs* out) override;

 private:
  SonarParams params_;
  SonarFanParams fan_;
  RayPattern pattern_;
  SonarSweep sweep_;
  std::string robot_;
  int site_{-1};
  SensorSchedule schedule_;
  std::vector<RayHit> hits_;
  std::vector<double> ranges_;
  NoiseSource noise_;
};

}  // namespace cairn::sim
