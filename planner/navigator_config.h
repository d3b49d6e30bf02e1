#pragma once

#include <string>

#include "common/yaml_reader.h"
#include "planner/cost_map.h"
#include "planner/global/global_planner.h"
#include "planner/local/dwa_planner.h"
#include "planner/navigator.h"
#include "planner/occupancy_cost.h"

/// @file
/// Configuration of cairn-navigator (config/navigator/navigator.yaml) and its strict loader.

namespace cairn::planner {

/// Where the robot pose comes from.
enum class PoseSource { kPose, kOdom };

/// How commands go out: lcmt_velocity_command on <robot>.CMD_VEL, or through seed 004's velocity
/// bridge as lcmt_body_velocity_request on <robot>.BODY_VELOCITY_REQ (surge and yaw enabled,
/// frame the profile's name: what an AUV's controller takes). One message per command either way.
enum class CommandOutput { kVelocity, kBodyVelocity };

/// What paces the control loop: the wall clock (control_rate_hz of wall time), or the pose
/// stream's stamps (control_rate_hz of the robot's own time: a tick on the first pose a period
/// after the last). With `pose`, a simulation run faster than real time gets its commands as
/// often, in its own time, as at real time; while no pose comes the wall clock ticks instead
/// (a tick and a half late), so stale input still stops the robot.
enum class ControlClock { kWall, kPose };

/// Which of the mapper's layers the navigator plans on (the `map:` section).
struct MapLayerConfig {
  /// "" (default): the profile's cost layer "cost/<profile>" with encoding cost; with encoding
  /// occupancy, "" means "final" (the dynamic map server's composed layer, seed 001).
  std::string layer;
  MapEncoding encoding{MapEncoding::kCost};
  /// Occupancy encoding only: how occupancy becomes cost.
  OccupancyCostParams occupancy;
  /// Cost encoding only: also read the profile's directed layer ("directed/<profile>" beside
  /// "cost/<profile>") when the mapper publishes it, so one-way steps and slopes can be driven
  /// the way they allow (CostMap). Without it, or without directed tiles, the cost layer alone.
  bool directed{true};
  /// With a directed layer: plan through a rim marked as an unseen drop (ground that fell out of
  /// sight beyond it, not yet proven deeper than the profile's step down) as through unknown
  /// ground, so the robot drives up to look; the local planner never crosses it until the ground
  /// beyond is seen (planner/README.md, "Unseen drops": off by default, for the reasons there).
  /// False: such a rim blocks plans too.
  bool look_at_unseen_drops{false};

  /// The layer name to subscribe to for a robot profile.
  std::string LayerFor(const std::string& profile) const;
  /// The directed layer read beside it: "directed/<p>" for a cost layer "cost/<p>" when
  /// `directed` is on; "" otherwise.
  std::string DirectedLayerFor(const std::string& profile) const;
};

struct NavigatorConfig {
  PoseSource pose_source{PoseSource::kPose};  ///< <robot>.POSE (lcmt_pose) or <robot>.ODOM
  CommandOutput command_output{CommandOutput::kVelocity};
  ControlClock control_clock{ControlClock::kWall};
  double control_rate_hz{20.0};
  double status_rate_hz{2.0};
  /// Accept map tiles of this map name only ("" = any).
  std::string map_name;
  /// The layer planned on and its encoding (default: the profile's cost layer).
  MapLayerConfig map;
  /// Ask the mapper again for missing tiles at most this often.
  double resend_interval_s{0.5};
  /// After waiting this long for missing tiles, take the layer with them lethal; the navigator
  /// holds the robot until they come (it asks for them every resend_interval_s).
  double incomplete_map_timeout_s{1.0};
  /// Map tiles are assembled and cost maps built on a thread of their own, so the control loop
  /// (commands, the stale-input stop) never waits for a layer (LcmMapClientParams::own_thread).
  bool map_thread{true};
  CostMapParams cost_map;
  GlobalPlannerParams global_planner;
  DwaParams local_planner;
  NavigatorParams navigator;

  /// Copies the control period into the navigator and the DWA, then validates everything.
  /// @throws std::invalid_argument naming the bad field.
  void Finalize();
};

/// Reads the whole configuration; every key is optional (the defaults above), unknown keys
/// are errors. @throws common::ConfigError naming the file and line.
NavigatorConfig LoadNavigatorConfig(common::YamlMap& root);
NavigatorConfig LoadNavigatorConfigFile(const std::string& path);

const char* PoseSourceName(PoseSource source);
/// "velocity" or "body_velocity". @throws std::invalid_argument otherwise.
CommandOutput CommandOutputFromName(const std::string& name);
/// "pose" or "odom". @throws std::invalid_argument otherwise.
PoseSource PoseSourceFromName(const std::string& name);
/// "wall" or "pose". @throws std::invalid_argument otherwise.
ControlClock ControlClockFromName(const std::string& name);
const char* ControlClockName(ControlClock clock);

}  // namespace cairn::planner
