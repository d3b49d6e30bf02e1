#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "common/status.h"
#include "common/types.h"
#include "simulator/drive.h"
#include "simulator/drive_model.h"
#include "simulator/mujoco_model.h"
#include "simulator/scenario.h"
#include "simulator/scene_rays.h"
#include "simulator/sim_outputs.h"
#include "simulator/sim_sensor.h"

/// @file
/// MujocoSim: the transport-free simulator. It owns the MuJoCo model and data of one scenario,
/// steps the physics, drives the robots' wheels from velocity commands and asks each robot's
/// sensors (SimSensor, built from the robot's SensorSet) for the readings that fell due,
/// stamped with simulation time. cairn-sim publishes what it produces.

namespace cairn::sim {

/// Shapes of spawnable objects.
enum class ObjectShape { kBox, kCylinder, kSphere };

/// A request to spawn an object. Sizes: box half sizes; cylinder radius and half height;
/// sphere radius. Position is the object's centre in the world.
struct ObjectSpec {
  std::string name;
  ObjectShape shape{ObjectShape::kBox};
  common::Vector3 size_m{0.1, 0.1, 0.1};
  common::Vector3 position_m{common::Vector3::Zero()};
  double yaw_rad{0.0};
};

/// Time spent and work done, for benchmarks.
struct SimStats {
  int64_t physics_steps{0};
  int64_t rays_cast{0};
  double physics_s{0.0};
  double sensors_s{0.0};
  double ray_s{0.0};
  /// Steps whose accelerations MuJoCo found bad (NaN or beyond 1e10: a robot put inside solid
  /// geometry, an exploding contact); each was undone (UndoBadStep).
  int64_t unstable_steps{0};
};

class MujocoSim {
 public:
  /// Composes the scenario's world with its robots and the spawn pool, compiles it and places
  /// the robots. @throws std::runtime_error with MuJoCo's message and the file name for a
  /// broken MJCF, std::invalid_argument for a robot model that lacks what its sensors need.
  explicit MujocoSim(const Scenario& scenario);
  ~MujocoSim();
  MujocoSim(const MujocoSim&) = delete;
  MujocoSim& operator=(const MujocoSim&) = delete;

  /// Advances one physics step and appends the readings that fell due to *out.
  void Step(SimOutputs* out);

  double time_s() const;
  /// Simulation time in microseconds (the utime of every reading).
  int64_t utime() const;
  double timestep_s() const;
  int64_t physics_steps() const { return stats_.physics_steps; }
  SimStats stats() const;
  const Scenario& scenario() const { return scenario_; }

  // --- robots ----------------------------------------------------------------------------------
  std::vector<std::string> robot_ids() const;
  bool HasRobot(const std::string& id) const;
  /// A velocity command (base frame) at the current sim time.
  /// @throws std::invalid_argument for an unknown robot.
  CommandVerdict Command(const std::string& robot, double linear_mps, double angular_radps);
  /// Puts a robot at (x, y, yaw), on the surface below when z is absent, at rest; its odometry
  /// restarts there.
  common::Status ResetRobot(const std::string& robot, double x_m, double y_m, double yaw_rad,
                            std::optional<double> z_m = std::nullopt);
  /// True pose of a robot base. @throws std::invalid_argument for an unknown robot.
  common::Pose3 RobotPose(const std::string& robot) const;
  /// Linear velocity of the base in the world frame.
  common::Vector3 RobotVelocity(const std::string& robot) const;
  const DriveController& drive(const std::string& robot) const;
  /// The robot's sensor of kind `name`, or nullptr when it has none.
  /// @throws std::invalid_argument for an unknown robot.
  const SimSensor* sensor(const std::string& robot, const std::string& name) const;
  /// The same as sensor class S (S::kName).
  template <typename S>
  const S* FindSensor(const std::string& robot) const {
    return dynamic_cast<const S*>(sensor(robot, S::kName));
  }
  /// Asks the robot's sensor of kind `sensor` for readings now (SimSensor::Trigger at the
  /// current sim time; the turret with `on_request` then makes one full sweep). kNotFound for
  /// an unknown robot or a robot without that sensor, else the sensor's answer (kInvalidArgument
  /// for a kind without an on-request mode), its message led by "robot 'r', sensor 'k': ".
  common::Status TriggerSensor(const std::string& robot, const std::string& sensor);

  // --- objects and doors -----------------------------------------------------------------------
  /// Places a new object (from the spawn pool). kAlreadyExists for a used name,
  /// kResourceExhausted when the pool is empty, kInvalidArgument for bad sizes or positions.
  common::Status SpawnObject(const ObjectSpec& spec);
  /// Moves a spawned object or any mocap body of the world. kNotFound for unknown names.
  common::Status MoveObject(const std::string& name, const common::Vector3& position_m,
                            double yaw_rad);
  /// Removes a spawned object or a mocap body of the world (parked out of reach).
  common::Status RemoveObject(const std::string& name);
  /// Opens (to the end of its joint range away from 0, else 90 deg) or closes (to 0) a door.
  /// Doors are hinge joints named "door_<name>" with a position actuator of the same name; they
  /// start open. Accepts "<name>" or "door_<name>".
  common::Status SetDoor(const std::string& name, bool open);
  /// "robot:<id>", "door:<name>" and "object:<name>" for everything that can be addressed.
  std::vector<std::string> ListNames() const;
  std::vector<std::string> DoorNames() const;
  std::vector<std::string> ObjectNames() const;

  // --- internals for tests and benchmarks ------------------------------------------------------
  const mjModel* model() const { return model_.get(); }
  const mjData* data() const { return data_.get(); }
  const RayScene& ray_scene() const { return rays_->scene(); }
  /// Casts sensor rays with a plain mj_ray loop instead of the ray caster (benchmark baseline).
  void set_use_mj_ray(bool use) { rays_->set_use_mj_ray(use); }
  /// The composed MJCF text that was compiled.
  const std::string& composed_xml() const { return composed_xml_; }

 private:
  struct Robot;
  struct Object;

  void Compose();
  void SetupSpawnPool();
  void CollectMocapObjects();
  void OpenDoors();
  void SetupRobots();
  Robot& FindRobot(const std::string& id);
  const Robot& FindRobot(const std::string& id) const;
  void SetupRobot(Robot& robot, int index);
  void CreateSensors(Robot& robot);
  double GroundHeight(double x_m, double y_m) const;
  void PlaceRobot(Robot& robot, double x_m, double y_m, double yaw_rad, std::optional<double> z_m);
  void ApplyDrive(double now_s, double dt_s, SimOutputs* out);
  void AfterPhysicsStep(double dt_s);
  /// After a step MuJoCo found unstable (it then resets all of mjData to the model's initial
  /// state, time 0 and every robot at the model's origin): back to the state before the step,
  /// at rest, the clock one step on, and one event line.
  void UndoBadStep(double time_before_s, double dt_s, SimOutputs* out);
  void ProduceReadings(SimOutputs* out);
  void SetGeomEnabled(int geom, bool enabled);
  Object* FindObject(const std::string& name);

  Scenario scenario_;
  std::string composed_xml_;
  MjModelPtr model_;
  MjDataPtr data_;
  std::unique_ptr<SceneRays> rays_;
  std::vector<std::unique_ptr<Robot>> robots_;
  std::map<std::string, std::unique_ptr<Object>> objects_;
  std::vector<int> free_slots_;  ///< spawn pool geoms not in use
  SimStats stats_;
  bool buffer_full_reported_[2] = {false, false};  ///< contact, constraint
  // The state before the current step (qpos, act, mocap), for UndoBadStep.
  std::vector<double> saved_qpos_;
  std::vector<double> saved_act_;
  std::vector<double> saved_mocap_pos_;
  std::vector<double> saved_mocap_quat_;
  double last_unstable_log_s_{-1e300};
  int64_t unstable_unlogged_{0};  ///< unstable steps since the last event line
};

}  // namespace cairn::sim
