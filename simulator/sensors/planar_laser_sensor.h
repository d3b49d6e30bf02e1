#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "common/point_cloud.h"
#include "common/yaml_reader.h"
#include "simulator/ray_caster.h"
#include "simulator/sim_sensor.h"

/// @file
/// planar_laser: a planar (2-D) laser scanner, one scan at a time. A beam without a return
/// reads +inf, one closer than the minimum range NaN.

namespace cairn::sim {

struct PlanarLaserParams {
  double fov_deg{240.0};
  int beams{683};
  double max_range_m{5.6};
  double min_range_m{0.02};
  double rate_hz{10.0};
  double range_noise_sigma_m{0.01};
  std::string mount_site{"laser_mount"};

  /// @throws std::invalid_argument naming the bad field.
  void Validate() const;
};

/// Overrides of `defaults` from a scenario's `planar_laser:` map (every key optional).
/// @throws common::ConfigError naming the file and line of an unknown key or a bad value.
PlanarLaserParams LoadPlanarLaserParams(common::YamlMap& map,
                                        const PlanarLaserParams& defaults = {});

/// Angle of the first beam and the step between beams for a fan of `beams` over `fov_deg`
/// centred on the x axis (one beam on each edge).
void FanAngles(double fov_deg, int beams, double* angle_min_rad, double* increment_rad);
/// Beams in the sensor's x-y plane, counter-clockwise from angle_min.
RayPattern BuildFanPattern(double fov_deg, int beams);
/// Fills scan->ranges_m and intensities from one hit per beam: noise sample noise_base + beam
/// added to each return; beyond scan->range_max_m +inf, closer than range_min_m NaN.
void FillScanRanges(const std::vector<RayHit>& hits, double noise_sigma_m, const NoiseSource& noise,
                    uint64_t noise_base, const SceneRays& rays, common::LaserScan* scan);

class PlanarLaserSensor final : public SimSensor {
 public:
  static constexpr char kName[] = "planar_laser";
  static constexpr char kDescription[] =
      "planar laser (fov, beams, range, rate per robot model) on <robot>.SCAN";
  using Params = PlanarLaserParams;
  using Reading = common::LaserScan;
  static constexpr auto kLoadParams = &LoadPlanarLaserParams;

  PlanarLaserSensor(const PlanarLaserParams& params, const SensorContext& context);

  bool Due(double now_s) const override { return schedule_.Due(now_s); }
  bool CastsRays() const override { return true; }
  void Produce(const SensorFrame& frame, SimOutputs* out) override;

 private:
  PlanarLaserParams params_;
  RayPattern pattern_;
  std::string robot_;
  int site_{-1};
  SensorSchedule schedule_;
  std::vector<RayHit> hits_;
  NoiseSource noise_;
};

}  // namespace cairn::sim
