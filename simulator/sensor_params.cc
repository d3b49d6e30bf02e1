#include "simulator/sensor_params.h"

#include <cmath>

#include "common/check.h"

namespace cairn::sim {
namespace {

bool Positive(double v) { return std::isfinite(v) && v > 0.0; }
bool NonNegative(double v) { return std::isfinite(v) && v >= 0.0; }

}  // namespace

void LidarParams::Validate() const {
  CAIRN_THROW_UNLESS(rings >= 1 && rings <= 127, "hdl32e.rings must be in [1, 127]");
  CAIRN_THROW_UNLESS(std::isfinite(min_elevation_deg) && std::isfinite(max_elevation_deg) &&
                         min_elevation_deg <= max_elevation_deg && min_elevation_deg >= -90.0 &&
                         max_elevation_deg <= 90.0,
                     "hdl32e elevations must satisfy -90 <= min <= max <= 90");
  CAIRN_THROW_UNLESS(azimuth_steps >= 1, "hdl32e.azimuth_steps must be >= 1");
  CAIRN_THROW_UNLESS(Positive(rate_hz), "hdl32e.rate_hz must be > 0");
  CAIRN_THROW_UNLESS(slices_per_revolution >= 1 && slices_per_revolution <= azimuth_steps,
                     "hdl32e.slices_per_revolution must be in [1, azimuth_steps]");
  CAIRN_THROW_UNLESS(Positive(max_range_m), "hdl32e.max_range_m must be > 0");
  CAIRN_THROW_UNLESS(NonNegative(min_range_m) && min_range_m < max_range_m,
                     "hdl32e.min_range_m must be in [0, max_range_m)");
  CAIRN_THROW_UNLESS(NonNegative(range_noise_sigma_m), "hdl32e.range_noise_sigma_m must be >= 0");
  CAIRN_THROW_UNLESS(azimuths_per_ray_group >= 1, "hdl32e.azimuths_per_ray_group must be >= 1");
  CAIRN_THROW_UNLESS(rings_per_ray_group >= 1, "hdl32e.rings_per_ray_group must be >= 1");
  // One slice must fit a UDP-friendly message (17 bytes per point).
  const int64_t steps_per_slice =
      (azimuth_steps + slices_per_revolution - 1) / slices_per_revolution;
  CAIRN_THROW_UNLESS(steps_per_slice * rings * 17 <= 64 * 1024,
                     "hdl32e: a slice of " << steps_per_slice * rings
                                           << " points exceeds 64 KB; raise slices_per_revolution");
}

void PlanarLaserParams::Validate() const {
  CAIRN_THROW_UNLESS(Positive(fov_deg) && fov_deg <= 360.0,
                     "planar_laser.fov_deg must be in (0, 360]");
  CAIRN_THROW_UNLESS(beams >= 2 && beams <= 100000, "planar_laser.beams must be in [2, 100000]");
  CAIRN_THROW_UNLESS(Positive(max_range_m), "planar_laser.max_range_m must be > 0");
  CAIRN_THROW_UNLESS(NonNegative(min_range_m) && min_range_m < max_range_m,
                     "planar_laser.min_range_m must be in [0, max_range_m)");
  CAIRN_THROW_UNLESS(Positive(rate_hz), "planar_laser.rate_hz must be > 0");
  CAIRN_THROW_UNLESS(NonNegative(range_noise_sigma_m),
                     "planar_laser.range_noise_sigma_m must be >= 0");
}

void TurretParams::Validate() const {
  CAIRN_THROW_UNLESS(Positive(fan_fov_deg) && fan_fov_deg <= 360.0,
                     "turret.fan_fov_deg must be in (0, 360]");
  CAIRN_THROW_UNLESS(fan_beams >= 2 && fan_beams <= 100000, "turret.fan_beams must be >= 2");
  CAIRN_THROW_UNLESS(Positive(max_range_m), "turret.max_range_m must be > 0");
  CAIRN_THROW_UNLESS(NonNegative(min_range_m) && min_range_m < max_range_m,
                     "turret.min_range_m must be in [0, max_range_m)");
  CAIRN_THROW_UNLESS(Positive(line_rate_hz), "turret.line_rate_hz must be > 0");
  CAIRN_THROW_UNLESS(Positive(pan_step_deg), "turret.pan_step_deg must be > 0");
  CAIRN_THROW_UNLESS(
      Positive(pan_range_deg) && pan_range_deg <= 360.0 && pan_range_deg >= pan_step_deg,
      "turret.pan_range_deg must be in [pan_step_deg, 360]");
  CAIRN_THROW_UNLESS(NonNegative(range_noise_sigma_m), "turret.range_noise_sigma_m must be >= 0");
}

void OdometryParams::Validate() const {
  CAIRN_THROW_UNLESS(Positive(rate_hz), "odometry.rate_hz must be > 0");
  CAIRN_THROW_UNLESS(NonNegative(slip_noise_ratio) && slip_noise_ratio < 1.0,
                     "odometry.slip_noise_ratio must be in [0, 1)");
}

void ImuParams::Validate() const {
  CAIRN_THROW_UNLESS(Positive(rate_hz), "imu.rate_hz must be > 0");
  CAIRN_THROW_UNLESS(NonNegative(gyro_noise_sigma_radps) && NonNegative(accel_noise_sigma_mps2) &&
                         NonNegative(orientation_noise_sigma_rad),
                     "imu noise sigmas must be >= 0");
}

void GroundTruthParams::Validate() const {
  CAIRN_THROW_UNLESS(Positive(rate_hz), "ground_truth.rate_hz must be > 0");
}

std::vector<std::string> SensorSet::Names() const {
  std::vector<std::string> names;
  if (lidar) names.push_back(kSensorLidar);
  if (planar_laser) names.push_back(kSensorPlanarLaser);
  if (turret) names.push_back(kSensorTurret);
  if (odometry) names.push_back(kSensorOdometry);
  if (imu) names.push_back(kSensorImu);
  if (ground_truth) names.push_back(kSensorGroundTruth);
  return names;
}

void SensorSet::Validate() const {
  if (lidar) lidar->Validate();
  if (planar_laser) planar_laser->Validate();
  if (turret) turret->Validate();
  if (odometry) odometry->Validate();
  if (imu) imu->Validate();
  if (ground_truth) ground_truth->Validate();
}

std::vector<std::pair<std::string, std::string>> SensorCatalogue() {
  return {
      {kSensorLidar,
       "HDL-32E-like 3-D lidar: 32 rings -30.67..+10.67 deg, 1800 azimuth steps, 10 Hz, 70 m, "
       "sigma 0.02 m; azimuth slices on <robot>.LIDAR"},
      {kSensorPlanarLaser,
       "planar laser (fov, beams, range, rate per robot model) on <robot>.SCAN"},
      {kSensorTurret,
       "planar laser on a rotating turret: 270 deg vertical fan, 0.5 deg pan steps, 50 m, "
       "50 lines/s on <robot>.TURRET_SCAN"},
      {kSensorOdometry,
       "wheel odometry from wheel joint rotation, optional slip noise, on "
       "<robot>.ODOM"},
      {kSensorImu, "orientation, angular rate and specific force with noise on <robot>.IMU"},
      {kSensorGroundTruth, "true pose and velocity of the robot base on <robot>.POSE"},
  };
}

}  // namespace cairn::sim
