#pragma once

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "common/types.h"

/// @file
/// The obstacle registry: connected terrain features found by the mapper, each with its
/// measurements and, per robot profile, whether that profile can cross it. This is what another
/// robot reads from a stored map.

namespace cairn::common {

enum class ObstacleKind : int8_t {
  kRamp = 1,
  kStepUp = 2,
  kStepDown = 3,
  kDitch = 4,
  kWallOrObject = 5,
  /// A raised platform with the ramps and faces around it (ramp, platform and drop), listed once
  /// with its parts (Obstacle::parts).
  kTerrace = 6,
};

const char* ObstacleKindName(ObstacleKind kind);  ///< "ramp", "step_up", ...

struct ObstacleVerdict {
  std::string profile;
  std::string profile_hash;
  bool crossable{false};
  /// Why not ("slope 10.1 deg > 8.0 deg"); empty when crossable. A feature the profile may cross
  /// one way only (an 8 cm drop for a robot stepping 3 cm up and 10 cm down: the directed layer
  /// lets it drive down) is not crossable, and its reason ends with kOneWayMarker and the way
  /// ("; one-way: crossable downwards only (<= 0.100 m step down)").
  std::string reason;
  bool operator==(const ObstacleVerdict& o) const {
    return profile == o.profile && profile_hash == o.profile_hash && crossable == o.crossable &&
           reason == o.reason;
  }
};

/// What a one-way verdict's reason carries (see ObstacleVerdict::reason).
inline constexpr char kOneWayMarker[] = "; one-way: ";
/// True for a verdict that lets the profile cross the feature one way only.
inline bool IsOneWay(const ObstacleVerdict& v) {
  return !v.crossable && v.reason.find(kOneWayMarker) != std::string::npos;
}
/// "crossable", "one-way" or "blocked".
inline const char* VerdictWord(const ObstacleVerdict& v) {
  return v.crossable ? "crossable" : (IsOneWay(v) ? "one-way" : "blocked");
}

/// One part of a terrace: a ramp or a face that leads onto the terrace's platform, judged per
/// profile both ways (onto the platform and off it). The verdict is crossable when the profile
/// may drive it both ways; a part it may drive one way only has a one-way verdict ("; one-way:
/// off the platform only, heading 0 deg"); otherwise it is blocked.
struct ObstaclePart {
  ObstacleKind kind{ObstacleKind::kStepUp};  ///< kRamp, or kStepUp: a face rising onto the platform
  Vector2 centroid_m{Vector2::Zero()};
  std::vector<Vector2> outline_m;  ///< polygon, world frame
  double slope_rad{0.0};           ///< a ramp's slope
  double height_m{0.0};            ///< what it rises onto the platform
  double width_m{0.0};
  double length_m{0.0};
  double area_m2{0.0};
  int32_t num_cells{0};
  /// The heading (rad, world frame, counter-clockwise from +x) of travel onto the platform over
  /// this part; off it is the opposite heading.
  double heading_in_rad{0.0};
  std::vector<ObstacleVerdict> verdicts;

  const ObstacleVerdict* VerdictFor(const std::string& profile) const {
    for (const auto& v : verdicts) {
      if (v.profile == profile) return &v;
    }
    return nullptr;
  }
};

/// The most parts one terrace may carry (a registry read from a file or the bus is checked
/// against it).
inline constexpr int kMaxObstacleParts = 64;

struct Obstacle {
  int32_t id{0};
  ObstacleKind kind{ObstacleKind::kWallOrObject};
  Vector2 centroid_m{Vector2::Zero()};
  std::vector<Vector2> outline_m;  ///< polygon, world frame
  double slope_rad{0.0};
  double height_m{0.0};  ///< NaN for a sonar contact: a sonar measures no height
  double width_m{0.0};
  double length_m{0.0};
  double depth_m{0.0};  ///< NaN when the bottom was never seen
  double area_m2{0.0};
  int32_t num_cells{0};
  /// Of a ramp or a step: the heading (rad, world frame, counter-clockwise from +x) of travel down
  /// it, from its high side to its low side; NaN for other kinds, or where the feature falls
  /// every way (a step around a block). A one-way verdict names it ("crossable downhill only,
  /// heading 90 deg +- 45 deg").
  double downhill_heading_rad{std::numeric_limits<double>::quiet_NaN()};
  std::vector<ObstacleVerdict> verdicts;
  /// A terrace's parts (empty for every other kind). The terrace's verdict is what the planner
  /// does with the whole: crossable (two parts lead onto the platform and off it both ways),
  /// one-way (onto it over one part and off over another, not back), or blocked.
  std::vector<ObstaclePart> parts;

  /// The verdict for a profile, or nullptr.
  const ObstacleVerdict* VerdictFor(const std::string& profile) const {
    for (const auto& v : verdicts) {
      if (v.profile == profile) return &v;
    }
    return nullptr;
  }
};

struct ObstacleRegistry {
  int64_t map_version{0};
  std::vector<Obstacle> obstacles;
};

}  // namespace cairn::common
