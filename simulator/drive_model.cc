#include "simulator/drive_model.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace cairn::sim {
namespace {

// Wheel speed loop: integral gain (1/s) and the most it may add to a servo target (rad/s).
constexpr double kWheelIntegralGain = 8.0;
constexpr double kWheelIntegralLimit = 10.0;

// The AUV's autopilot. Speed loops: proportional and integral gains per unit of mass (or of yaw
// inertia), so one tuning fits any hull. Depth hold: a critically damped spring of 1 rad/s.
// Roll and pitch: damping of the hull's rotation in water, which MuJoCo's inertia-box drag
// underestimates for a slender body, critically damping the buoyancy couple.
constexpr double kSurgeP = 4.0;      // N per (m/s) per kg
constexpr double kSurgeI = 4.0;      // N per m per kg
constexpr double kYawP = 6.0;        // N m per (rad/s) per kg m^2
constexpr double kYawI = 6.0;        // N m per rad per kg m^2
constexpr double kDepthOmega = 1.0;  // rad/s

int RequireId(const mjModel* m, mjtObj type, const std::string& name, const std::string& what) {
  const int id = mj_name2id(m, type, name.c_str());
  if (id < 0) throw std::invalid_argument(what + " '" + name + "' not found in the model");
  return id;
}

// Rotates v by the base's orientation (qpos quaternion w, x, y, z).
void Rotate(const mjtNum* quat, const mjtNum* v, mjtNum* out) { mju_rotVecQuat(out, v, quat); }

}  // namespace

// --- WheelDrive --------------------------------------------------------------------------------

WheelDrive::WheelDrive(const DriveSite& site)
    : wheel_radius_m_(site.robot->wheel_radius_m), track_m_(site.robot->track_m) {
  const mjModel* m = site.model;
  auto add = [&](const std::vector<std::string>& names, Side* side) {
    for (const std::string& wheel : names) {
      const int joint = RequireId(m, mjOBJ_JOINT, site.prefix + wheel, site.where + "wheel joint");
      const int act =
          RequireId(m, mjOBJ_ACTUATOR, site.prefix + wheel, site.where + "wheel actuator");
      if (m->jnt_type[joint] != mjJNT_HINGE) {
        throw std::invalid_argument(site.where + "wheel joint '" + wheel + "' is not a hinge");
      }
      side->actuators.push_back(act);
      side->qpos.push_back(m->jnt_qposadr[joint]);
      side->dofs.push_back(m->jnt_dofadr[joint]);
    }
    side->integral.assign(side->dofs.size(), 0.0);
  };
  add(site.robot->left_wheels, &left_);
  add(site.robot->right_wheels, &right_);
}

double WheelDrive::MeanAngle(const mjData* d, const Side& side) {
  double sum = 0.0;
  for (int a : side.qpos) sum += d->qpos[a];
  return sum / static_cast<double>(side.qpos.size());
}

void WheelDrive::Servo(Side& side, double target_radps, mjData* d, double dt_s) const {
  // Each wheel runs a PI speed loop, like motor firmware: the MJCF velocity servo is the P part,
  // the integral of the speed error raises its target until the wheel keeps up under load
  // (skid-steer turning, slopes) and holds a parked robot still.
  for (size_t i = 0; i < side.actuators.size(); ++i) {
    const double error = target_radps - d->qvel[side.dofs[i]];
    side.integral[i] = std::clamp(side.integral[i] + kWheelIntegralGain * error * dt_s,
                                  -kWheelIntegralLimit, kWheelIntegralLimit);
    d->ctrl[side.actuators[i]] = target_radps + side.integral[i];
  }
}

void WheelDrive::Apply(const DriveController& drive, mjData* d, double dt_s) {
  Servo(left_, drive.left_wheel_radps(), d, dt_s);
  Servo(right_, drive.right_wheel_radps(), d, dt_s);
}

StepMotion WheelDrive::Measure(const mjData* d, double dt_s) {
  const double left = MeanAngle(d, left_);
  const double right = MeanAngle(d, right_);
  const StepMotion motion{dt_s, left - left_.angle, right - right_.angle};
  left_.angle = left;
  right_.angle = right;
  return motion;
}

void WheelDrive::Reset(const mjData* d) {
  std::fill(left_.integral.begin(), left_.integral.end(), 0.0);
  std::fill(right_.integral.begin(), right_.integral.end(), 0.0);
  left_.angle = MeanAngle(d, left_);
  right_.angle = MeanAngle(d, right_);
}

// --- ThrusterDrive -----------------------------------------------------------------------------

ThrusterDrive::ThrusterDrive(const DriveSite& site)
    : model_(site.model),
      thrusters_(site.robot->thrusters),
      track_m_(site.robot->track_m),
      root_body_(site.root_body),
      qpos_adr_(site.qpos_adr),
      qvel_adr_(site.qvel_adr),
      mass_kg_(site.model->body_subtreemass[site.root_body]) {
  if (!(mass_kg_ > 0.0)) throw std::invalid_argument(site.where + "an auv hull needs a mass");
}

double ThrusterDrive::SurgeMps(const mjData* d) const {
  const mjtNum forward[3] = {1.0, 0.0, 0.0};
  mjtNum axis[3];
  Rotate(d->qpos + qpos_adr_ + 3, forward, axis);
  return mju_dot3(axis, d->qvel + qvel_adr_);
}

double ThrusterDrive::YawRateRadps(const mjData* d) const {
  // A free joint's angular velocity is in the body frame; the yaw rate is its world z part.
  mjtNum world[3];
  Rotate(d->qpos + qpos_adr_ + 3, d->qvel + qvel_adr_ + 3, world);
  return world[2];
}

void ThrusterDrive::Apply(const DriveController& drive, mjData* d, double dt_s) {
  const mjModel* m = model_;
  const mjtNum* quat = d->qpos + qpos_adr_ + 3;
  const mjtNum ex[3] = {1.0, 0.0, 0.0}, ez[3] = {0.0, 0.0, 1.0};
  mjtNum forward[3], up[3];
  Rotate(quat, ex, forward);
  Rotate(quat, ez, up);
  const double izz = std::max(m->body_inertia[3 * root_body_ + 2], 1e-6);

  // Surge: PI on the body's forward speed, within the thrust.
  const double surge_error = drive.linear_mps() - SurgeMps(d);
  const double surge_limit = thrusters_.max_surge_thrust_n;
  surge_integral_n_ = std::clamp(surge_integral_n_ + kSurgeI * mass_kg_ * surge_error * dt_s,
                                 -surge_limit, surge_limit);
  const double surge_n =
      std::clamp(kSurgeP * mass_kg_ * surge_error + surge_integral_n_, -surge_limit, surge_limit);
  // Yaw: PI on the world yaw rate, within the torque.
  const double yaw_error = drive.angular_radps() - YawRateRadps(d);
  const double yaw_limit = thrusters_.max_yaw_torque_nm;
  yaw_integral_nm_ =
      std::clamp(yaw_integral_nm_ + kYawI * izz * yaw_error * dt_s, -yaw_limit, yaw_limit);
  const double yaw_nm =
      std::clamp(kYawP * izz * yaw_error + yaw_integral_nm_, -yaw_limit, yaw_limit);
  // Depth: a critically damped spring to the height it was placed at, within the heave thrust.
  const mjtNum* lin = d->qvel + qvel_adr_;
  const double heave_n =
      std::clamp(-mass_kg_ * (kDepthOmega * kDepthOmega * (d->qpos[qpos_adr_ + 2] - depth_m_) +
                              2.0 * kDepthOmega * lin[2]),
                 -thrusters_.max_heave_thrust_n, thrusters_.max_heave_thrust_n);
  // Buoyancy: the weight, upwards, at the centre of buoyancy.
  const double weight_n = -mass_kg_ * m->opt.gravity[2];
  const mjtNum buoyancy[3] = {0.0, 0.0, weight_n};
  const mjtNum lever[3] = {up[0] * thrusters_.buoyancy_centre_m,
                           up[1] * thrusters_.buoyancy_centre_m,
                           up[2] * thrusters_.buoyancy_centre_m};
  mjtNum couple[3];
  mju_cross(couple, lever, buoyancy);
  // Roll and pitch damping: critical for the buoyancy couple on the hull's own inertia.
  const double ixx = std::max(m->body_inertia[3 * root_body_ + 0], 1e-6);
  const double iyy = std::max(m->body_inertia[3 * root_body_ + 1], 1e-6);
  const double righting = std::max(std::abs(weight_n * thrusters_.buoyancy_centre_m), 1e-3);
  const mjtNum* ang = d->qvel + qvel_adr_ + 3;  // body frame
  const mjtNum damp_body[3] = {-2.0 * std::sqrt(righting * ixx) * ang[0],
                               -2.0 * std::sqrt(righting * iyy) * ang[1], 0.0};
  mjtNum damp[3];
  Rotate(quat, damp_body, damp);

  mjtNum* f = d->xfrc_applied + 6 * root_body_;
  for (int i = 0; i < 3; ++i) {
    f[i] = forward[i] * surge_n + buoyancy[i];
    f[3 + i] = up[i] * yaw_nm + couple[i] + damp[i];
  }
  f[2] += heave_n;
}

StepMotion ThrusterDrive::Measure(const mjData* d, double dt_s) {
  // A DVL's surge and sway speeds and a gyro's yaw rate: surge and yaw as the wheels of a
  // unicycle of radius 1 m, sway as the sideways travel (a hull slips sideways in a turn).
  const double v = SurgeMps(d);
  const double w = YawRateRadps(d);
  const mjtNum left[3] = {0.0, 1.0, 0.0};
  mjtNum axis[3];
  Rotate(d->qpos + qpos_adr_ + 3, left, axis);
  const double sway_mps = axis[0] * d->qvel[qvel_adr_] + axis[1] * d->qvel[qvel_adr_ + 1];
  return StepMotion{dt_s, (v - 0.5 * w * track_m_) * dt_s, (v + 0.5 * w * track_m_) * dt_s,
                    sway_mps * dt_s};
}

void ThrusterDrive::Reset(const mjData* d) {
  depth_m_ = d->qpos[qpos_adr_ + 2];
  surge_integral_n_ = 0.0;
  yaw_integral_nm_ = 0.0;
}

// --- factory -----------------------------------------------------------------------------------

std::unique_ptr<DriveModel> MakeDriveModel(const DriveSite& site) {
  if (site.robot->drive == common::DriveKind::kAuv) return std::make_unique<ThrusterDrive>(site);
  return std::make_unique<WheelDrive>(site);
}

}  // namespace cairn::sim
