#pragma once

#include <string>
#include <vector>

#include "common/robot_profile.h"
#include "common/status.h"
#include "common/token_buckets.h"
#include "services/mapping/mapper_core.h"
#include "services/mapping/mapper_inputs.h"

/// @file
/// Configuration of cairn-mapper (config/mapping/*.yaml) and its strict loader: every key is
/// optional (the defaults below), an unknown key is an error naming the file and line.

namespace cairn::common {
class YamlMap;
}  // namespace cairn::common

namespace cairn::mapping {

/// Everything one robot's mapper process needs besides its profiles.
/// What a resend request naming no tiles (the whole layer) counts against the resend limits.
inline constexpr int kWholeLayerResendTiles = 200;

struct MapperParams {
  std::string robot;
  std::string map_name{"live"};
  MapperInputsParams inputs;
  int max_pending_revolutions{3};  ///< older waiting revolutions are dropped (counted)
  int tiles_per_burst{8};          ///< tiles sent back to back before a short pause
  double burst_pause_ms{1.0};
  std::string snapshot_dir{"var/mapper-snapshots"};  ///< OP_SNAPSHOT writes below it
  /// Destructive requests from the bus: OP_RESET (forgets every map) and OP_SNAPSHOT (writes
  /// files). Off, they are refused (STATUS_FORBIDDEN) with an audit line.
  bool allow_reset{false};
  bool allow_snapshot{false};
  /// Jobs waiting for the worker other than revolutions (scans, readings, control and resend
  /// requests); beyond, the oldest of the new job's kind goes, else the new one (counted as
  /// queue_drops).
  int max_queued_jobs{256};
  /// Tiles resent on request, per requester and for every requester together; a request
  /// beyond is dropped (resend_rate_limited). A request for every tile of a layer counts as
  /// kWholeLayerResendTiles.
  common::TokenBucketsParams resend_limits;
  /// "SITE/MAP" in cairn-mapstore where the long-term layer is remembered across runs
  /// ("" = nowhere). Needs the dynamic layer.
  std::string long_term_store;
  /// How often the long-term layer is saved there (seed 001's "every so often"; 20 s).
  double long_term_save_period_s{20.0};
  /// How long cairn-mapper waits at start for the store to send the stored layer.
  double long_term_load_timeout_s{30.0};
  MapperCoreParams core;

  /// @throws std::invalid_argument naming a bad field.
  void Validate() const;
};

struct MapperConfig {
  MapperParams params;
  /// Profiles served from the start: names (in the profiles folder) or YAML paths.
  std::vector<std::string> profiles{"pioneer3at"};
};

/// Reads a mapper file's root map. Top level: map_name, pose_source, max_pose_gap_s,
/// imu_attitude, max_imu_gap_s, lidar_mount, profiles, publish_period_s, slow_publish_period_s,
/// registry_period_s (the terrain layer's), occupancy_period_s (the occupancy and dynamic
/// layers'), max_pending_revolutions, tiles_per_burst, burst_pause_ms, snapshot_dir; then one
/// section per layer (terrain, occupancy, octomap, dynamic: mapper_layers.h), whose `enabled`
/// lists the layer or not. @throws common::ConfigError naming the file and line.
MapperConfig LoadMapperConfig(common::YamlMap& root);
MapperConfig LoadMapperConfigFile(const std::string& path);

/// A comma-separated list, items trimmed, empty items dropped.
std::vector<std::string> SplitList(const std::string& text);

/// A profile by name (`<profiles_dir>/<name>.yaml`) or by path (a name holding '/' or ending in
/// .yaml): for the command line, the operator's own choice. NOT_FOUND when no such file;
/// INVALID_ARGUMENT for a bad name or file.
common::Result<common::RobotProfile> ResolveProfile(const std::string& profiles_dir,
                                                    const std::string& name);

/// A profile named on the bus (OP_ADD_PROFILE): only `<profiles_dir>/<name>.yaml`, the name of
/// letters, digits, '_' and '-' (at most 64), never a path: a peer on the bus cannot make the
/// process read any other file, nor have its content echoed back in an error.
common::Result<common::RobotProfile> ResolveProfileByName(const std::string& profiles_dir,
                                                          const std::string& name);

}  // namespace cairn::mapping
