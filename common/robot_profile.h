#pragma once

#include <limits>
#include <string>
#include <vector>

#include "common/types.h"
#include "common/yaml_reader.h"

/// @file
/// RobotProfile: what a robot can cross and how it may move. Profiles are robot-specific; maps
/// are not. Traversability, the obstacle verdicts and the planners all read a profile.

namespace cairn::common {

/// Drive kinds. kAuv moves in surge and yaw only (sparus2).
enum class DriveKind { kDifferential, kSkidSteer, kAuv };

const char* DriveKindName(DriveKind kind);
/// @throws std::invalid_argument for an unknown name.
DriveKind DriveKindFromName(const std::string& name);

struct RobotProfile {
  std::string name;
  DriveKind drive{DriveKind::kDifferential};
  /// Footprint polygon in the base frame (x forward, y left), counter-clockwise, metres.
  std::vector<Vector2> footprint_m;

  // Terrain limits. Infinity means "no limit" (the seed's "no downhill limit").
  double max_slope_up_rad{0.1396};
  double max_slope_down_rad{std::numeric_limits<double>::infinity()};
  double max_step_up_m{0.03};
  double max_step_down_m{0.10};
  double max_ditch_width_m{0.10};
  double ground_clearance_m{0.08};
  double max_roughness_m{0.05};

  // Kinematic limits (Nav2 vocabulary).
  double max_vel_x_mps{0.5};
  double min_vel_x_mps{-0.1};  ///< most negative forward speed (reverse), <= 0
  double max_vel_theta_radps{1.0};
  double acc_lim_x_mps2{0.8};
  double acc_lim_theta_radps2{1.5};

  /// Names of the sensors the robot carries ("hdl32e", "planar_laser", "imu", ...).
  std::vector<std::string> sensors;

  /// @throws std::invalid_argument saying which field is wrong.
  void Validate() const;
  /// Hex digest of every field above in a canonical text form: the cache key of derived layers.
  std::string ContentHash() const;
  /// Radius of the circle around the base origin that contains the footprint.
  double CircumscribedRadius() const;
  /// Radius of the largest circle around the base origin inside the footprint.
  double InscribedRadius() const;
  /// Canonical YAML text (round-trips through LoadRobotProfile).
  std::string ToYaml() const;

  bool operator==(const RobotProfile& o) const;
};

/// Reads a profile from a YAML map; angles may be given as *_rad or *_deg.
/// @throws ConfigError with file and line on a missing, unknown or bad key.
RobotProfile LoadRobotProfile(YamlMap& map);
RobotProfile LoadRobotProfileFile(const std::string& path);
RobotProfile LoadRobotProfileString(const std::string& yaml, const std::string& where = "<string>");

/// A rectangle footprint centred on the base origin.
std::vector<Vector2> RectangleFootprint(double length_m, double width_m);

/// 64-bit FNV-1a, the product's non-cryptographic content hash.
uint64_t Fnv1a64(const void* data, size_t size, uint64_t seed = 1469598103934665603ULL);
std::string HexDigest(uint64_t value);

}  // namespace cairn::common
