#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

/// @file
/// Parameters of the simulated sensors. Defaults describe the reference hardware; every value
/// can be overridden per robot in a scenario file. Angles in degrees where the name says so.

namespace cairn::sim {

/// Sensor names as they appear in scenario files and in `cairn-sim --help`.
inline constexpr char kSensorLidar[] = "hdl32e";
inline constexpr char kSensorPlanarLaser[] = "planar_laser";
inline constexpr char kSensorTurret[] = "turret";
inline constexpr char kSensorOdometry[] = "odometry";
inline constexpr char kSensorImu[] = "imu";
inline constexpr char kSensorGroundTruth[] = "ground_truth";

/// A spinning multi-ring lidar shaped like a Velodyne HDL-32E, published as azimuth slices.
struct LidarParams {
  int rings{32};
  double min_elevation_deg{-30.67};
  double max_elevation_deg{10.67};
  int azimuth_steps{1800};        ///< per revolution (0.2 deg)
  double rate_hz{10.0};           ///< revolutions per second
  int slices_per_revolution{20};  ///< each slice is one message
  double max_range_m{70.0};
  double min_range_m{0.4};
  double range_noise_sigma_m{0.02};
  int azimuths_per_ray_group{10};  ///< broad-phase granularity of the ray caster...
  int rings_per_ray_group{32};     ///< ... in azimuth and in elevation
  std::string mount_site{"lidar_mount"};

  /// @throws std::invalid_argument naming the bad field.
  void Validate() const;
};

/// A planar (2-D) laser scanner, one scan at a time.
struct PlanarLaserParams {
  double fov_deg{240.0};
  int beams{683};
  double max_range_m{5.6};
  double min_range_m{0.02};
  double rate_hz{10.0};
  double range_noise_sigma_m{0.01};
  std::string mount_site{"laser_mount"};

  void Validate() const;
};

/// A planar laser on a rotating turret (seed 002): the scanning plane is vertical and turns
/// about the turret's z axis one pan step per line, so a robot that stands still gets a full
/// 3-D scan every pan_range_deg / pan_step_deg lines.
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

  void Validate() const;
};

/// Wheel odometry integrated from the wheel joint speeds. Each physics step's travel of the
/// left and right wheels is scaled by (1 + n) with n ~ N(0, slip_noise_ratio^2): with noise the
/// estimate drifts, without it the integration is exact.
struct OdometryParams {
  double rate_hz{50.0};
  double slip_noise_ratio{0.0};

  void Validate() const;
};

/// Inertial measurement at the robot's "imu" site.
struct ImuParams {
  double rate_hz{100.0};
  double gyro_noise_sigma_radps{0.002};
  double accel_noise_sigma_mps2{0.02};
  double orientation_noise_sigma_rad{0.002};
  std::string site{"imu"};

  void Validate() const;
};

/// Ground-truth pose and velocity of the robot base.
struct GroundTruthParams {
  double rate_hz{50.0};

  void Validate() const;
};

/// The sensors one robot carries; an absent sensor is off.
struct SensorSet {
  std::optional<LidarParams> lidar;
  std::optional<PlanarLaserParams> planar_laser;
  std::optional<TurretParams> turret;
  std::optional<OdometryParams> odometry;
  std::optional<ImuParams> imu;
  std::optional<GroundTruthParams> ground_truth;

  /// Names of the sensors that are on, in a fixed order.
  std::vector<std::string> Names() const;
  void Validate() const;
};

/// Every sensor name the simulator knows, with a one-line description (for --help).
std::vector<std::pair<std::string, std::string>> SensorCatalogue();

}  // namespace cairn::sim
