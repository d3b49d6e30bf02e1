#include "services/mission/sonar_fan.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "common/check.h"

namespace cairn::mission {

SonarFan::SonarFan(double bearing_step_rad) : step_rad_(bearing_step_rad) {
  CAIRN_THROW_UNLESS(bearing_step_rad > 1e-6 && bearing_step_rad < 1.0,
                     "the fan's bearing step must be in (1e-6, 1) rad");
}

common::Status SonarFan::Add(const FanPing& ping) {
  if (ping.bins.empty() || ping.bins.size() > kMaxBins) {
    return common::InvalidArgumentError("a ping needs 1 to " + std::to_string(kMaxBins) +
                                        " bins, not " + std::to_string(ping.bins.size()));
  }
  if (!std::isfinite(ping.pan_rad) || std::abs(ping.pan_rad) > M_PI) {
    return common::InvalidArgumentError("a ping's pan must be within +-pi rad");
  }
  if (!(ping.range_min_m >= 0.0 && ping.range_min_m < ping.range_max_m &&
        ping.range_max_m <= 1000.0)) {
    return common::InvalidArgumentError("a ping's ranges must be 0 <= min < max <= 1000 m");
  }
  if (last_pan_rad_ && ping.pan_rad != *last_pan_rad_) {
    const int direction = ping.pan_rad > *last_pan_rad_ ? 1 : -1;
    if (direction_ != 0 && direction != direction_) ++reversals_;
    direction_ = direction;
  }
  last_pan_rad_ = ping.pan_rad;
  latest_[std::llround(ping.pan_rad / step_rad_)] = ping;
  return common::Status::Ok();
}

double SonarFan::min_pan_rad() const {
  return latest_.empty() ? 0.0 : latest_.begin()->first * step_rad_;
}
double SonarFan::max_pan_rad() const {
  return latest_.empty() ? 0.0 : latest_.rbegin()->first * step_rad_;
}

common::GridMap SonarFan::Image(double resolution_m) const {
  CAIRN_THROW_UNLESS(resolution_m > 0.0, "the fan's resolution must be > 0");
  if (latest_.empty()) return common::GridMap();
  double range_m = 0.0;
  for (const auto& [slot, ping] : latest_) range_m = std::max(range_m, ping.range_max_m);
  // The sector's extent in the head's frame.
  const double lo = min_pan_rad(), hi = max_pan_rad();
  double min_x = 0.0, max_x = 0.0, min_y = 0.0, max_y = 0.0;
  for (double a = lo; a <= hi + 1e-9; a += std::max(step_rad_, (hi - lo) / 64.0)) {
    min_x = std::min(min_x, range_m * std::cos(a));
    max_x = std::max(max_x, range_m * std::cos(a));
    min_y = std::min(min_y, range_m * std::sin(a));
    max_y = std::max(max_y, range_m * std::sin(a));
  }
  for (double a : {lo, hi}) {
    min_x = std::min(min_x, range_m * std::cos(a));
    max_x = std::max(max_x, range_m * std::cos(a));
    min_y = std::min(min_y, range_m * std::sin(a));
    max_y = std::max(max_y, range_m * std::sin(a));
  }
  common::GridGeometry g;
  g.resolution_m = resolution_m;
  g.size_x = std::max(1, static_cast<int>(std::ceil((max_x - min_x) / resolution_m)));
  g.size_y = std::max(1, static_cast<int>(std::ceil((max_y - min_y) / resolution_m)));
  g.origin = {min_x, min_y, 0.0};
  common::GridMap image(g);
  common::Layer& out = image.AddLayer(kIntensityLayer);
  out.setConstant(std::numeric_limits<float>::quiet_NaN());
  for (int iy = 0; iy < g.size_y; ++iy) {
    for (int ix = 0; ix < g.size_x; ++ix) {
      const common::Vector2 p = image.CenterOf({ix, iy});
      const double r = p.norm();
      const double bearing = std::atan2(p.y(), p.x());
      const int64_t slot = std::llround(bearing / step_rad_);
      // The latest ping at the nearest bearing, within one step.
      const FanPing* best = nullptr;
      double best_d = std::numeric_limits<double>::infinity();
      for (int64_t s = slot - 1; s <= slot + 1; ++s) {
        auto it = latest_.find(s);
        if (it == latest_.end()) continue;
        const double d = std::abs(it->second.pan_rad - bearing);
        if (d <= step_rad_ && d < best_d) {
          best_d = d;
          best = &it->second;
        }
      }
      if (best == nullptr || r < best->range_min_m || r >= best->range_max_m) continue;
      const double bin_m = (best->range_max_m - best->range_min_m) / best->bins.size();
      const size_t bin = std::min(best->bins.size() - 1,
                                  static_cast<size_t>((r - best->range_min_m) / bin_m));
      out(ix, iy) = best->bins[bin];
    }
  }
  return image;
}

}  // namespace cairn::mission
