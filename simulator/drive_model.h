#pragma once

#include <memory>
#include <string>
#include <vector>

#include <mujoco/mujoco.h>

#include "simulator/drive.h"
#include "simulator/scenario.h"
#include "simulator/sim_sensor.h"

/// @file
/// The drive seam: how a robot's base turns the (v, w) its DriveController follows into forces in
/// MuJoCo, and what it measures of its own motion for odometry. One DriveModel per robot, chosen
/// by the model's `drive:` kind: wheels (differential, skid steer) or thrusters (auv).

namespace cairn::sim {

/// What a drive model knows about the robot in the compiled model.
struct DriveSite {
  const mjModel* model{nullptr};
  const RobotModel* robot{nullptr};
  std::string prefix;  ///< "<robot id>/": names of its joints and actuators
  std::string where;   ///< "robot 'r' (path): " for messages
  int root_body{-1};   ///< the body holding the free joint
  int qpos_adr{0};
  int qvel_adr{0};
};

class DriveModel {
 public:
  virtual ~DriveModel() = default;
  /// Before a physics step: controls and applied forces for the (v, w) `drive` follows now.
  virtual void Apply(const DriveController& drive, mjData* d, double dt_s) = 0;
  /// After the step: the motion the base measured over it (odometry's input).
  virtual StepMotion Measure(const mjData* d, double dt_s) = 0;
  /// The robot was placed (spawn, reset, undone step): loops restart, references are taken from
  /// the new state (the AUV holds the depth it was placed at).
  virtual void Reset(const mjData* d) = 0;
};

/// Wheels: hinge joints with velocity actuators of the same name, each run as a PI speed loop.
class WheelDrive final : public DriveModel {
 public:
  /// @throws std::invalid_argument for a missing wheel joint or actuator, or a joint not a hinge.
  explicit WheelDrive(const DriveSite& site);
  void Apply(const DriveController& drive, mjData* d, double dt_s) override;
  StepMotion Measure(const mjData* d, double dt_s) override;
  void Reset(const mjData* d) override;

 private:
  struct Side {
    std::vector<int> actuators, qpos, dofs;
    std::vector<double> integral;  ///< rad/s added to each servo target
    double angle{0.0};             ///< mean wheel angle at the last Measure
  };
  static double MeanAngle(const mjData* d, const Side& side);
  void Servo(Side& side, double target_radps, mjData* d, double dt_s) const;

  double wheel_radius_m_;
  double track_m_;
  Side left_, right_;
};

/// Thrusters of a hovering AUV (Sparus II-like): its autopilot turns (v, w) into a surge force
/// along the hull and a yaw torque (PI loops on the measured body velocities, limited to the
/// model's thrust), holds the depth, roll and pitch it was placed at, and the water carries it:
/// buoyancy equal to its weight at a centre of buoyancy above its centre of mass (MuJoCo 2.2 has
/// no buoyancy of its own), drag from the world's medium (<option density viscosity wind>).
/// Applied as forces on the root body (xfrc_applied). Odometry measures the surge speed and yaw
/// rate, as a DVL and gyro would, reported as the wheel motion of a unicycle of radius 1 m and
/// track `track_m`.
class ThrusterDrive final : public DriveModel {
 public:
  explicit ThrusterDrive(const DriveSite& site);
  void Apply(const DriveController& drive, mjData* d, double dt_s) override;
  StepMotion Measure(const mjData* d, double dt_s) override;
  void Reset(const mjData* d) override;

  /// Body-frame surge speed and yaw rate now.
  double SurgeMps(const mjData* d) const;
  double YawRateRadps(const mjData* d) const;

 private:
  const mjModel* model_;
  RobotModel::Thrusters thrusters_;
  double track_m_;
  int root_body_;
  int qpos_adr_;
  int qvel_adr_;
  double mass_kg_;
  double depth_m_{0.0};  ///< the height held
  double surge_integral_n_{0.0};
  double yaw_integral_nm_{0.0};
};

/// The drive model for the robot's `drive:` kind.
std::unique_ptr<DriveModel> MakeDriveModel(const DriveSite& site);

}  // namespace cairn::sim
