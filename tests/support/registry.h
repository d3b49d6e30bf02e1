#pragma once

// Reading an obstacle registry off the bus in integration tests: a profile's verdict, the
// obstacle of a kind in a box, and a one-line-per-obstacle description for failure messages.

#include <cmath>
#include <functional>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

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

// A terrace's part as an obstacle of its own (the terrace's id, the part's kind, measurements and
// verdicts: crossable when the profile may drive it both ways).
inline cairn::lcmt_obstacle PartAsObstacle(const cairn::lcmt_obstacle& terrace,
                                           const cairn::lcmt_obstacle_part& p) {
  cairn::lcmt_obstacle o{};
  o.id = terrace.id;
  o.kind = p.kind;
  o.centroid_m[0] = p.centroid_m[0];
  o.centroid_m[1] = p.centroid_m[1];
  o.num_outline = p.num_outline;
  o.outline_x_m = p.outline_x_m;
  o.outline_y_m = p.outline_y_m;
  o.slope_rad = p.slope_rad;
  o.height_m = p.height_m;
  o.width_m = p.width_m;
  o.length_m = p.length_m;
  o.depth_m = 0.0;
  o.area_m2 = p.area_m2;
  o.num_cells = p.num_cells;
  o.num_verdicts = p.num_verdicts;
  o.verdicts = p.verdicts;
  o.num_parts = 0;
  return o;
}

// The first obstacle of `kind` whose centroid lies in [x0, x1] x [y0, y1] (and satisfies `ok`):
// an entry of its own, or a terrace's part (a ramp, or a face as KIND_STEP_UP: the registry lists
// a ramp with its platform and drop, or a slab with its faces, as one terrace).
inline std::optional<cairn::lcmt_obstacle> Find(
    const cairn::lcmt_obstacle_registry& r, int8_t kind, double x0, double x1, double y0, double y1,
    const std::function<bool(const cairn::lcmt_obstacle&)>& ok = nullptr) {
  for (const auto& entry : r.obstacles) {
    std::vector<cairn::lcmt_obstacle> candidates{entry};
    for (const auto& p : entry.parts) candidates.push_back(PartAsObstacle(entry, p));
    for (const auto& o : candidates) {
      if (o.kind != kind || !CentroidIn(o, x0, x1, y0, y1)) continue;
      if (ok && !ok(o)) continue;
      return o;
    }
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
    for (const auto& p : o.parts) {
      s << "    part kind " << int(p.kind) << " at (" << p.centroid_m[0] << ", " << p.centroid_m[1]
        << ") h " << p.height_m << " slope " << p.slope_rad * 180 / M_PI << " onto heading "
        << p.heading_in_rad * 180 / M_PI;
      for (const auto& v : p.verdicts) {
        s << " " << v.profile << ":" << (v.crossable ? "yes" : v.reason);
      }
      s << "\n";
    }
  }
  return s.str();
}

}  // namespace cairn::testing
