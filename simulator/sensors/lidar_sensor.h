#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "common/point_cloud.h"
#include "common/yaml_reader.h"
#include "simulator/ray_caster.h"
#include "simulator/sim_sensor.h"

/// @file
/// hdl32e: a spinning multi-ring lidar shaped like a Velodyne HDL-32E, published as azimuth
/// slices. Each slice is cast at one instant (its end time) from the sensor pose of that
/// instant, so a moving robot gives an undistorted cloud.

namespace cairn::sim {

struct LidarParams {
  int rings{32};
  double min_elevation_deg{-30.67};
  double max_elevation_deg{10.67};
  int azimuth_steps{1800};        ///< per revolution (0.2 deg)
  double rate_hz{10.0};           ///< revolutions per second
  int slices_per_revolution{10};  ///< each slice is one message (17 KB as ranges)
  double max_range_m{70.0};
  double min_range_m{0.4};
  double range_noise_sigma_m{0.02};
  /// Slices are range images in steps of this (the HDL-32E's 2 mm; at most 1 m), 3 bytes a ray
  /// on <robot>.LIDAR_RANGES (common::LidarSlice::range_steps; common::ExpandRangeImage makes
  /// the points); 0: float points, on <robot>.LIDAR as 17 bytes a point.
  double range_resolution_m{0.002};
  int azimuths_per_ray_group{15};  ///< broad-phase granularity of the ray caster...
  int rings_per_ray_group{32};     ///< ... in azimuth and in elevation
  std::string mount_site{"lidar_mount"};

  /// @throws std::invalid_argument naming the bad field.
  void Validate() const;
};

/// Overrides of `defaults` from a scenario's `hdl32e:` map (every key optional).
/// @throws common::ConfigError naming the file and line of an unknown key or a bad value.
LidarParams LoadLidarParams(common::YamlMap& map, const LidarParams& defaults = {});

// --- layout ------------------------------------------------------------------------------------

/// Elevation of ring r (0 = lowest), evenly spaced from min to max elevation.
double LidarRingElevationRad(const LidarParams& params, int ring);
/// Azimuth of step k, counter-clockwise from the sensor's x axis: k * 360 deg / azimuth_steps.
double LidarAzimuthRad(const LidarParams& params, int step);
/// First azimuth step of slice s; slice s covers [SliceBegin(s), SliceBegin(s + 1)).
int LidarSliceBegin(const LidarParams& params, int slice);
/// All rays of one revolution, ordered so that every slice, and within it every ray group, is a
/// contiguous range: slice by slice, then by elevation band (rings_per_ray_group rings), then
/// azimuth step, then ring. Groups span azimuths_per_ray_group steps of one band.
struct LidarPattern {
  RayPattern rays;
  std::vector<int16_t> ring;           ///< per ray
  std::vector<int32_t> azimuth_step;   ///< per ray
  std::vector<int> slice_ray_begin;    ///< slice s owns rays [begin[s], begin[s + 1])
  std::vector<int> slice_group_begin;  ///< slice s owns groups [begin[s], begin[s + 1])
};
LidarPattern BuildLidarPattern(const LidarParams& params);
/// The same pattern, shared by every sensor with the same layout (eight HDL-32Es then read one
/// 2 MB table instead of eight, which keeps it in the cache). Thread-safe.
std::shared_ptr<const LidarPattern> SharedLidarPattern(const LidarParams& params);

// --- the sensor --------------------------------------------------------------------------------

class LidarSensor final : public SimSensor {
 public:
  static constexpr char kName[] = "hdl32e";
  static constexpr char kDescription[] =
      "HDL-32E-like 3-D lidar: 32 rings -30.67..+10.67 deg, 1800 azimuth steps, 10 Hz, 70 m, "
      "sigma 0.02 m; 10 slices a turn on <robot>.LIDAR_RANGES, 2 mm steps, 3 bytes a ray";
  using Params = LidarParams;
  using Reading = common::LidarSlice;
  static constexpr auto kLoadParams = &LoadLidarParams;

  LidarSensor(const LidarParams& params, const SensorContext& context);

  bool Due(double now_s) const override;
  bool CastsRays() const override { return true; }
  /// Every slice due by now (usually one), each from the sensor pose now.
  void Produce(const SensorFrame& frame, SimOutputs* out) override;

 private:
  common::LidarSlice MakeSlice(const SensorFrame& frame, int64_t revolution, int slice,
                               const common::Pose3& sensor);

  LidarParams params_;
  std::shared_ptr<const LidarPattern> pattern_;
  std::string robot_;
  int site_{-1};
  int64_t slices_done_{0};
  std::vector<RayHit> hits_;  ///< one slice: hits_[ray - slice_ray_begin[slice]]
  std::vector<double> noisy_m_;  ///< the same rays' ranges with their noise
  std::vector<float> ring_elevation_rad_;
  NoiseSource noise_;
};

}  // namespace cairn::sim
