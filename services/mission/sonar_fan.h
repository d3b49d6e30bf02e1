#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "common/grid_map.h"
#include "common/status.h"

/// @file
/// The picture a sonar operator looks at: the last sweep of a mechanically scanned imaging
/// sonar as a fan, every bearing showing the latest ping taken there, range outwards from the
/// head. Pure: the mission feeds it the pings it heard (lcmt_sonar_ping, checked by Add).

namespace cairn::mission {

/// One ping as the fan keeps it.
struct FanPing {
  double pan_rad{0.0};      ///< the head's angle from its mount's x axis, positive left
  double range_min_m{0.0};
  double range_max_m{50.0};
  std::vector<uint8_t> bins;  ///< nearest first
};

class SonarFan {
 public:
  /// Bearings closer than `bearing_step_rad` share a slot: the head's own step (0.005 rad).
  explicit SonarFan(double bearing_step_rad = 0.005);

  /// Keeps the ping as the latest at its bearing. kInvalidArgument (the ping is not kept) for
  /// no bins or more than kMaxBins, a pan that is not finite or outside [-pi, pi], or ranges
  /// that are not 0 <= min < max <= 1000 m.
  common::Status Add(const FanPing& ping);
  static constexpr size_t kMaxBins = 10000;

  size_t bearings() const { return latest_.size(); }
  /// Times the head turned back (the pan's direction of travel changed) over the pings kept:
  /// after two, it has swept its whole sector once.
  int reversals() const { return reversals_; }
  /// Smallest and largest bearing with a ping (rad); 0, 0 when empty.
  double min_pan_rad() const;
  double max_pan_rad() const;

  /// The fan as a grid in the head's frame (x forward along pan 0, y left), `resolution_m`
  /// cells out to the farthest range: layer kIntensityLayer holds each cell's bin intensity
  /// (0..255) from the latest ping at the nearest bearing within one step, NaN outside the
  /// swept sector. Empty grid (no layer) when no ping was kept.
  common::GridMap Image(double resolution_m = 0.1) const;
  static constexpr char kIntensityLayer[] = "sonar/intensity";

 private:
  double step_rad_;
  std::map<int64_t, FanPing> latest_;  ///< by bearing slot
  std::optional<double> last_pan_rad_;
  int direction_{0};  ///< +1 sweeping left, -1 right, 0 not known yet
  int reversals_{0};
};

}  // namespace cairn::mission
