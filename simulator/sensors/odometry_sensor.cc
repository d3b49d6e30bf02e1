#include "simulator/sensors/odometry_sensor.h"

#include <cmath>

#include "common/check.h"
#include "simulator/sensor_registry.h"
#include <Eigen/Geometry>

namespace cairn::sim {

void OdometryParams::Validate() const {
  CAIRN_THROW_UNLESS(std::isfinite(rate_hz) && rate_hz > 0.0, "odometry.rate_hz must be > 0");
  CAIRN_THROW_UNLESS(
      std::isfinite(slip_noise_ratio) && slip_noise_ratio >= 0.0 && slip_noise_ratio < 1.0,
      "odometry.slip_noise_ratio must be in [0, 1)");
}

OdometryParams LoadOdometryParams(common::YamlMap& map, const OdometryParams& defaults) {
  OdometryParams p = defaults;
  map.Get("rate_hz", &p.rate_hz);
  map.Get("slip_noise_ratio", &p.slip_noise_ratio);
  FinishSensorParams(map, p);
  return p;
}

// --- WheelOdometry -----------------------------------------------------------------------------

WheelOdometry::WheelOdometry(const OdometryParams& params, double wheel_radius_m, double track_m,
                             NoiseSource noise)
    : params_(params), wheel_radius_m_(wheel_radius_m), track_m_(track_m), noise_(noise) {
  CAIRN_THROW_UNLESS(wheel_radius_m > 0.0 && track_m > 0.0,
                     "odometry needs a positive wheel radius and track");
}

void WheelOdometry::Reset(const common::Pose2& pose) {
  pose_ = pose;
  linear_mps_ = 0.0;
  angular_radps_ = 0.0;
}

void WheelOdometry::Integrate(double left_delta_rad, double right_delta_rad, double dt_s,
                              double lateral_m) {
  double left_m = left_delta_rad * wheel_radius_m_;
  double right_m = right_delta_rad * wheel_radius_m_;
  if (params_.slip_noise_ratio > 0.0) {
    left_m *= 1.0 + params_.slip_noise_ratio * noise_.Gaussian(counter_++);
    right_m *= 1.0 + params_.slip_noise_ratio * noise_.Gaussian(counter_++);
  }
  const double ds = 0.5 * (left_m + right_m);
  const double dtheta = (right_m - left_m) / track_m_;
  const double theta = pose_.yaw_rad;
  if (std::abs(dtheta) > 1e-9) {
    // Exact arc of constant curvature.
    const double radius = ds / dtheta;
    pose_.x_m += radius * (std::sin(theta + dtheta) - std::sin(theta));
    pose_.y_m -= radius * (std::cos(theta + dtheta) - std::cos(theta));
  } else {
    pose_.x_m += ds * std::cos(theta + 0.5 * dtheta);
    pose_.y_m += ds * std::sin(theta + 0.5 * dtheta);
  }
  // Sideways at the step's mean heading (left of the heading is +90 deg).
  pose_.x_m -= lateral_m * std::sin(theta + 0.5 * dtheta);
  pose_.y_m += lateral_m * std::cos(theta + 0.5 * dtheta);
  pose_.yaw_rad = common::WrapAngle(theta + dtheta);
  if (dt_s > 0.0) {
    linear_mps_ = ds / dt_s;
    angular_radps_ = dtheta / dt_s;
  }
}

// --- the sensor --------------------------------------------------------------------------------

OdometrySensor::OdometrySensor(const OdometryParams& params, const SensorContext& context)
    : robot_(context.robot),
      odometry_(params, context.wheel_radius_m, context.track_m, context.Noise()) {
  schedule_.rate_hz = params.rate_hz;
}

void OdometrySensor::OnStep(const StepMotion& motion) {
  odometry_.Integrate(motion.left_wheel_delta_rad, motion.right_wheel_delta_rad, motion.dt_s,
                      motion.lateral_m);
}

void OdometrySensor::OnPlaced(const common::Pose2& pose, double z_m) {
  odometry_.Reset(pose);
  z_m_ = z_m;
}

void OdometrySensor::Produce(const SensorFrame& frame, SimOutputs* out) {
  schedule_.Advance(frame.now_s);
  OdometryReading o;
  o.utime = frame.utime;
  o.robot = robot_;
  const common::Pose2& p = odometry_.pose();
  o.pose.position_m = common::Vector3(p.x_m, p.y_m, z_m_);
  o.pose.orientation = common::Quaternion(Eigen::AngleAxisd(p.yaw_rad, common::Vector3::UnitZ()));
  o.linear_velocity_mps = common::Vector3(odometry_.linear_mps(), 0.0, 0.0);
  o.angular_velocity_radps = common::Vector3(0.0, 0.0, odometry_.angular_radps());
  out->Add(kName, std::move(o));
}

}  // namespace cairn::sim
