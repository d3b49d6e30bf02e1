#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "common/robot_profile.h"
#include "common/yaml_reader.h"
#include "simulator/sensor_registry.h"

/// @file
/// What cairn-sim simulates: a world (a shipped name or any MJCF file) and robots, each with a
/// model (simulator/robots/<model>.xml + .yaml), a profile (config/profiles/<profile>.yaml) for
/// its velocity limits, a spawn pose and a sensor set. Loaded strictly from a scenario YAML
/// (config/sim/*.yaml) or built from command-line robot specs.

namespace cairn::sim {

/// Where shipped worlds, robot models and profiles live.
struct SimPaths {
  std::string data_dir;    ///< the simulator folder: worlds/, robots/
  std::string config_dir;  ///< the config folder: profiles/

  /// The folders of a tree rooted at `root`: root/simulator and root/config (the source tree;
  /// cairn-sim's defaults, which --data-dir and --config-dir override).
  static SimPaths InTree(const std::string& root);

  /// A shipped world name ("tunnel") or a path to an MJCF file.
  /// @throws std::invalid_argument listing the shipped worlds for an unknown name.
  std::string WorldPath(const std::string& name_or_path) const;
  /// A profile name ("pioneer3at") or a path to a profile YAML file.
  std::string ProfilePath(const std::string& name_or_path) const;
  std::vector<std::string> ShippedWorlds() const;
  std::vector<std::string> ShippedRobots() const;
  /// First line of a shipped world's or robot's description (for --help).
  std::string WorldSummary(const std::string& name) const;
};

/// A robot model: its MJCF and the facts the simulator needs about it.
struct RobotModel {
  std::string name;
  std::string description;
  std::string xml_path;
  std::string xml;
  common::DriveKind drive{common::DriveKind::kDifferential};
  double wheel_radius_m{0.1};
  /// Kinematic track used to mix (v, w) into wheel speeds and for odometry; for skid steer it is
  /// larger than the geometric one (calibrated so commanded turn rates are met).
  double track_m{0.4};
  /// Wheel hinge joints; each has a velocity actuator of the same name.
  std::vector<std::string> left_wheels;
  std::vector<std::string> right_wheels;
  std::string default_profile;
  SensorSet default_sensors;

  /// drive: auv. The thrusters' limits and the hull's buoyancy (ThrusterDrive). wheel_radius_m is
  /// then 1 and track_m the unicycle track its odometry reports wheel motion with.
  struct Thrusters {
    double max_surge_thrust_n{60.0};
    double max_yaw_torque_nm{20.0};
    double max_heave_thrust_n{60.0};  ///< the depth hold's
    double buoyancy_centre_m{0.02};   ///< centre of buoyancy above the centre of mass
  } thrusters;
};

/// Loads simulator/robots/<model>.yaml and .xml.
/// @throws std::invalid_argument for an unknown model (listing the known ones), ConfigError for
/// a malformed description.
RobotModel LoadRobotModel(const SimPaths& paths, const std::string& model);

/// A velocity command the simulator applies itself during [at_s, at_s + duration_s).
struct ScriptedCommand {
  double at_s{0.0};
  double duration_s{0.0};
  double linear_mps{0.0};
  double angular_radps{0.0};
};

struct SpawnPose {
  double x_m{0.0};
  double y_m{0.0};
  double yaw_rad{0.0};
  /// Height of the base origin; when absent the robot is placed on the surface below (x, y).
  std::optional<double> z_m;
};

struct RobotSpec {
  std::string id;
  RobotModel model;
  common::RobotProfile profile;
  SpawnPose spawn;
  SensorSet sensors;
  std::vector<ScriptedCommand> commands;
};

struct PhysicsParams {
  double timestep_s{0.002};
  std::string integrator{"euler"};  ///< euler, rk4 or implicit (MuJoCo 2.2)
  /// A constant water current (world frame): the medium's velocity (MuJoCo's option wind), which
  /// drags what moves in it. Needs a world with water (option density > 0).
  double current_x_mps{0.0};
  double current_y_mps{0.0};

  void Validate() const;
};

/// A scenario's `physics:` map (every key optional). @throws common::ConfigError.
PhysicsParams LoadPhysicsParams(common::YamlMap& map);

struct Scenario {
  std::string world;       ///< as given
  std::string world_path;  ///< resolved MJCF file
  /// MJCF text of the world; when set it is used instead of reading world_path (which then
  /// only names the world in messages and anchors relative asset paths).
  std::string world_xml;
  uint64_t seed{1};
  PhysicsParams physics;
  int ray_threads{1};           ///< threads casting lidar rays (1 = the simulation thread only)
  int spawn_slots{16};          ///< objects that can exist at once through SIM.CONTROL spawn
  double clock_rate_hz{100.0};  ///< SIM.CLOCK messages per simulated second
  std::vector<RobotSpec> robots;

  /// @throws std::invalid_argument naming the first problem (duplicate ids, bad values).
  void Validate() const;
};

/// Reads a scenario (see config/sim/*.yaml for the format); robots' `sensors:` maps name kinds
/// of `sensors`. @throws common::ConfigError with file and line for unknown keys or bad values,
/// and for unknown worlds, robot models, profiles and sensors.
Scenario LoadScenario(common::YamlMap& map, const SimPaths& paths,
                      const SensorRegistry& sensors = BuiltinSensors());
Scenario LoadScenarioFile(const std::string& path, const SimPaths& paths,
                          const SensorRegistry& sensors = BuiltinSensors());

/// A scenario of a world (a shipped name or an MJCF path) and robots given as --robot flags
/// (below), with every other setting at its default.
/// @throws std::invalid_argument for an unknown world or a bad robot flag.
Scenario MakeScenario(const std::string& world, const std::vector<std::string>& robot_flags,
                      const SimPaths& paths);

/// "id:model[:profile[:x,y[,yaw_deg]]]" as given to cairn-sim --robot. Empty profile = the
/// model's default. @throws std::invalid_argument saying what is wrong.
RobotSpec ParseRobotFlag(const std::string& text, const SimPaths& paths);

/// A robot with the model's default profile and sensors.
RobotSpec MakeRobotSpec(const std::string& id, const std::string& model, const std::string& profile,
                        const SpawnPose& spawn, const SimPaths& paths);

}  // namespace cairn::sim
