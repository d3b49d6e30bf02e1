#pragma once

// Reading an obstacle registry off the bus in integration tests: a profile's verdict, the
// obstacle of a kind in a box, and a one-line-per-obstacle description for failure messages.

#include <cmath>
#include <functional>
#include <optional>
#include <sstream>
#include <string>

#include "cairn/lcmt_obstacle_registry.hpp"

namespace cairn::testing {

inline const cairn::lcmt_obstacle_verdict* Verdict(const cairn::lcmt_obstacle& o,
                                                   const std::string& profile) {
  for (const auto& v : o.verdicts) {
    if (v.profile == profile) return &v;
  }
  return nullptr;
}

inline bool CentroidIn(const cairn::lcmt_obstacle& o, double x0, double x1, double y0, double y1) {
  return o.centroid_m[0] >= x0 && o.centroid_m[0] <= x1 && o.centroid_m[1] >= y0 &&
         o.centroid_m[1] <= y1;
}

// The first obstacle of `kind` whose centroid lies in [x0, x1] x [y0, y1] (and satisfies `ok`).
inline std::optional<cairn::lcmt_obstacle> Find(
    const cairn::lcmt_obstacle_registry& r, int8_t kind, double x0, double x1, double y0, double y1,
    const std::function<bool(const cairn::lcmt_obstacle&)>& ok = nullptr) {
  for (const auto& o : r.obstacles) {
    if (o.kind != kind || !CentroidIn(o, x0, x1, y0, y1)) continue;
    if (ok && !ok(o)) continue;
    return o;
  }
  return std::nullopt;
}

inline std::string Describe(const cairn::lcmt_obstacle_registry& r) {
  std::ostringstream s;
  for (const auto& o : r.obstacles) {
    s << "  kind " << int(o.kind) << " at (" << o.centroid_m[0] << ", " << o.centroid_m[1] << ") h "
      << o.height_m << " w " << o.width_m << " d " << o.depth_m << " slope "
      << o.slope_rad * 180 / M_PI;
    for (const auto& v : o.verdicts) {
      s << " " << v.profile << ":" << (v.crossable ? "yes" : v.reason);
    }
    s << "\n";
  }
  return s.str();
}

}  // namespace cairn::testing
