#include "simulator/sensors/imu_sensor.h"

#include <cmath>
#include <stdexcept>

#include "common/check.h"
#include "simulator/sensor_registry.h"
#include <Eigen/Geometry>

namespace cairn::sim {
void ImuParams::Validate() const {
  CAIRN_THROW_UNLESS(FinitePositive(rate_hz), "imu.rate_hz must be > 0");
  CAIRN_THROW_UNLESS(FiniteNonNegative(gyro_noise_sigma_radps) &&
                         FiniteNonNegative(accel_noise_sigma_mps2) &&
                         FiniteNonNegative(orientation_noise_sigma_rad),
                     "imu noise sigmas must be >= 0");
}

ImuParams LoadImuParams(common::YamlMap& map, const ImuParams& defaults) {
  ImuParams p = defaults;
  map.Get("rate_hz", &p.rate_hz);
  map.Get("gyro_noise_sigma_radps", &p.gyro_noise_sigma_radps);
  map.Get("accel_noise_sigma_mps2", &p.accel_noise_sigma_mps2);
  map.Get("orientation_noise_sigma_rad", &p.orientation_noise_sigma_rad);
  map.Get("site", &p.site);
  FinishSensorParams(map, p);
  return p;
}

ImuSensor::ImuSensor(const ImuParams& params, const SensorContext& context)
    : params_(params), robot_(context.robot), noise_(context.Noise()) {
  const mjModel* m = context.model;
  const int site = context.RequireSite(params.site);
  for (int s = 0; s < m->nsensor; ++s) {
    if (m->sensor_objtype[s] != mjOBJ_SITE || m->sensor_objid[s] != site) continue;
    if (m->sensor_type[s] == mjSENS_GYRO) gyro_adr_ = m->sensor_adr[s];
    if (m->sensor_type[s] == mjSENS_ACCELEROMETER) accel_adr_ = m->sensor_adr[s];
    if (m->sensor_type[s] == mjSENS_FRAMEQUAT) quat_adr_ = m->sensor_adr[s];
  }
  if (gyro_adr_ < 0 || accel_adr_ < 0 || quat_adr_ < 0) {
    throw std::invalid_argument(context.Where() +
                                "sensor 'imu' needs gyro, accelerometer and framequat sensors "
                                "on site '" +
                                params.site + "'");
  }
  schedule_.rate_hz = params.rate_hz;
}

void ImuSensor::Produce(const SensorFrame& frame, SimOutputs* out) {
  const uint64_t n = static_cast<uint64_t>(schedule_.count) * 16;
  schedule_.Advance(frame.now_s);
  const ImuParams& p = params_;
  const double* s = frame.data->sensordata;
  ImuReading reading;
  reading.utime = frame.utime;
  reading.robot = robot_;
  for (int i = 0; i < 3; ++i) {
    reading.angular_velocity_radps[i] =
        s[gyro_adr_ + i] + p.gyro_noise_sigma_radps * noise_.Gaussian(n + i);
    reading.linear_acceleration_mps2[i] =
        s[accel_adr_ + i] + p.accel_noise_sigma_mps2 * noise_.Gaussian(n + 3 + i);
  }
  const common::Quaternion truth(s[quat_adr_], s[quat_adr_ + 1], s[quat_adr_ + 2],
                                 s[quat_adr_ + 3]);
  const common::Vector3 tilt(noise_.Gaussian(n + 6), noise_.Gaussian(n + 7),
                             noise_.Gaussian(n + 8));
  const common::Vector3 error = p.orientation_noise_sigma_rad * tilt;
  const double angle = error.norm();
  const common::Quaternion noise_q =
      angle > 0.0 ? common::Quaternion(Eigen::AngleAxisd(angle, error / angle))
                  : common::Quaternion::Identity();
  reading.orientation = (truth.normalized() * noise_q).normalized();
  reading.orientation_variance_rad2 = p.orientation_noise_sigma_rad * p.orientation_noise_sigma_rad;
  reading.angular_velocity_variance = p.gyro_noise_sigma_radps * p.gyro_noise_sigma_radps;
  reading.linear_acceleration_variance = p.accel_noise_sigma_mps2 * p.accel_noise_sigma_mps2;
  out->Add(kName, std::move(reading));
}

}  // namespace cairn::sim
