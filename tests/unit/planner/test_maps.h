#pragma once

#include <cmath>
#include <memory>
#include <vector>

#include "common/grid_map.h"
#include "common/robot_profile.h"
#include "planner/cost_map.h"

/// Small cost layers for the planner's unit tests, built in code.

namespace cairn::planner::testing {

/// A size_x × size_y layer of `fill` at `resolution_m` with its minimum corner at origin.
struct TestLayer {
  common::GridGeometry geometry;
  common::Layer cost;

  TestLayer(int size_x, int size_y, double resolution_m, float fill = 0.0f,
            common::Pose2 origin = {}) {
    geometry.resolution_m = resolution_m;
    geometry.size_x = size_x;
    geometry.size_y = size_y;
    geometry.origin = origin;
    cost.setConstant(size_x, size_y, fill);
  }
  /// Sets every cell whose centre lies in the world rectangle [x0, x1] × [y0, y1].
  TestLayer& Rect(double x0, double y0, double x1, double y1, float value) {
    for (int iy = 0; iy < geometry.size_y; ++iy) {
      for (int ix = 0; ix < geometry.size_x; ++ix) {
        const common::Vector2 c = geometry.CenterOf({ix, iy});
        if (c.x() >= x0 && c.x() <= x1 && c.y() >= y0 && c.y() <= y1) cost(ix, iy) = value;
      }
    }
    return *this;
  }
  std::shared_ptr<const CostMap> Build(const std::vector<common::Vector2>& footprint,
                                       CostMapParams params = {}) const {
    return std::make_shared<const CostMap>(geometry, cost, footprint, params);
  }
};

/// 20 m × 10 m at 0.1 m with a wall across x = 10 m that has one 1.2 m gap at y in [6, 7.2].
inline TestLayer WallWithGap() {
  TestLayer layer(200, 100, 0.1);
  layer.Rect(9.8, 0.0, 10.2, 6.0, 100.0f).Rect(9.8, 7.2, 10.2, 10.0, 100.0f);
  return layer;
}

/// The pioneer3at footprint (0.63 m × 0.50 m).
inline std::vector<common::Vector2> PioneerFootprint() {
  return common::RectangleFootprint(0.63, 0.50);
}

/// The Kobuki's round base as the octagon of config/profiles/kobuki.yaml (radius 0.176 m).
inline std::vector<common::Vector2> KobukiFootprint() {
  std::vector<common::Vector2> out;
  for (int k = 0; k < 8; ++k) {
    out.push_back({0.176 * std::cos(k * M_PI / 4), 0.176 * std::sin(k * M_PI / 4)});
  }
  return out;
}

/// A small square robot (0.3 m × 0.3 m).
inline std::vector<common::Vector2> SmallFootprint() {
  return common::RectangleFootprint(0.3, 0.3);
}

inline common::RobotProfile PioneerProfile() {
  common::RobotProfile p;
  p.name = "pioneer3at";
  p.drive = common::DriveKind::kSkidSteer;
  p.footprint_m = PioneerFootprint();
  p.max_vel_x_mps = 0.5;
  p.min_vel_x_mps = -0.2;
  p.max_vel_theta_radps = 1.0;
  p.acc_lim_x_mps2 = 0.8;
  p.acc_lim_theta_radps2 = 1.5;
  return p;
}

}  // namespace cairn::planner::testing
