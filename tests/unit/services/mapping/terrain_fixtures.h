#pragma once

#include <cmath>
#include <functional>
#include <string>

#include "common/grid_map.h"
#include "common/layers.h"
#include "common/robot_profile.h"

/// @file
/// Synthetic elevation grids and profiles for the terrain unit tests.

namespace cairn::mapping::testing {

inline constexpr double kDeg = M_PI / 180.0;

/// A grid of `nx` x `ny` cells at `res` with an elevation layer from f(x, y) (world metres at
/// cell centres; f may return NaN).
inline common::GridMap MakeTerrain(int nx, int ny, double res,
                                   const std::function<double(double, double)>& f,
                                   common::Pose2 origin = {}) {
  common::GridGeometry g;
  g.resolution_m = res;
  g.size_x = nx;
  g.size_y = ny;
  g.origin = origin;
  common::GridMap map(g);
  common::Layer& h = map.AddLayer(layers::kElevation);
  for (int iy = 0; iy < ny; ++iy) {
    for (int ix = 0; ix < nx; ++ix) {
      const common::Vector2 c = map.CenterOf({ix, iy});
      h(ix, iy) = static_cast<float>(f(c.x(), c.y()));
    }
  }
  return map;
}

/// A plane rising by `slope_rad` along the direction `azimuth_rad`.
inline std::function<double(double, double)> Plane(double slope_rad, double azimuth_rad = 0.0) {
  const double t = std::tan(slope_rad);
  return [=](double x, double y) {
    return t * (x * std::cos(azimuth_rad) + y * std::sin(azimuth_rad));
  };
}

/// A profile that only limits what the test varies: everything else is generous.
inline common::RobotProfile LenientProfile(const std::string& name = "test") {
  common::RobotProfile p;
  p.name = name;
  p.footprint_m = common::RectangleFootprint(0.5, 0.4);
  p.max_slope_up_rad = 80 * kDeg;
  p.max_slope_down_rad = 80 * kDeg;
  p.max_step_up_m = 10.0;
  p.max_step_down_m = 10.0;
  p.max_ditch_width_m = 0.1;
  p.max_roughness_m = 10.0;
  return p;
}

/// A corridor 4 m wide (y in [0, 4)) of 0.2 m cells along x; `feature` gives the floor height
/// at x.
inline common::GridMap Corridor(const std::function<double(double)>& feature, int nx = 80) {
  return MakeTerrain(nx, 20, 0.2, [feature](double x, double) { return feature(x); });
}

/// The shipped profiles.
inline common::RobotProfile ShippedProfile(const std::string& name) {
  return common::LoadRobotProfileFile(std::string(CAIRN_SOURCE_DIR) + "/config/profiles/" + name +
                                      ".yaml");
}

}  // namespace cairn::mapping::testing
