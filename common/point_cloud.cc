#include "common/point_cloud.h"

#include <cmath>

namespace cairn::common {

bool HasRangeGrid(const LidarSlice& slice) {
  const LidarGrid& grid = slice.grid;
  return grid.columns >= 1 && grid.columns <= 65535 && grid.range_resolution_m > 0.0 &&
         std::isfinite(grid.range_resolution_m) && !grid.ring_elevation_rad.empty() &&
         grid.ring_elevation_rad.size() <= 127;
}

bool HasRangeImage(const LidarSlice& slice) {
  const LidarGrid& grid = slice.grid;
  if (!HasRangeGrid(slice) || grid.range_resolution_m > 1.0) return false;
  const size_t rays = static_cast<size_t>(grid.columns) * grid.ring_elevation_rad.size();
  return slice.range_steps.size() == rays && slice.range_intensity.size() == rays;
}

void ExpandRangeImage(LidarSlice* slice) {
  if (!HasRangeImage(*slice)) return;
  const LidarGrid& grid = slice->grid;
  const int rings = static_cast<int>(grid.ring_elevation_rad.size());
  std::vector<double> cos_el(rings), sin_el(rings);
  for (int r = 0; r < rings; ++r) {
    cos_el[r] = std::cos(static_cast<double>(grid.ring_elevation_rad[r]));
    sin_el[r] = std::sin(static_cast<double>(grid.ring_elevation_rad[r]));
  }
  size_t returns = 0;
  for (const uint16_t steps : slice->range_steps) returns += steps != 0 ? 1 : 0;
  slice->points.reserve(slice->points.size() + returns);
  for (int c = 0; c < grid.columns; ++c) {
    const double azimuth = slice->azimuth_start_rad + c * grid.azimuth_step_rad;
    const double ca = std::cos(azimuth), sa = std::sin(azimuth);
    const uint16_t* ranges = slice->range_steps.data() + static_cast<size_t>(c) * rings;
    const uint8_t* intensity = slice->range_intensity.data() + static_cast<size_t>(c) * rings;
    for (int r = 0; r < rings; ++r) {
      if (ranges[r] == 0) continue;
      const double range_m = ranges[r] * grid.range_resolution_m;
      LidarPoint p;
      p.x_m = static_cast<float>(cos_el[r] * ca * range_m);
      p.y_m = static_cast<float>(cos_el[r] * sa * range_m);
      p.z_m = static_cast<float>(sin_el[r] * range_m);
      p.intensity = intensity[r];
      p.ring = static_cast<int16_t>(r);
      p.column = static_cast<uint16_t>(c);
      slice->points.push_back(p);
    }
  }
  slice->range_steps = {};
  slice->range_intensity = {};
}

}  // namespace cairn::common
