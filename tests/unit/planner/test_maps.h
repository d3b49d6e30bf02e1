#pragma once

#include <algorithm>
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

/// A height field and the directed layer a mapper would derive from it for a profile with
/// the Pioneer's step limits (up 3 cm, down 10 cm): bit k of a cell is set when its neighbour
/// towards heading k * 45 deg is higher by more than `max_up_m` or lower by more than
/// `max_down_m`. The cost layer is lethal where the mask is non-zero (the contract of
/// common/layers.h).
struct DirectedTestLayer {
  TestLayer layer;
  common::Layer height;
  common::Layer directed;

  DirectedTestLayer(int size_x, int size_y, double resolution_m)
      : layer(size_x, size_y, resolution_m),
        height(common::Layer::Zero(size_x, size_y)),
        directed(common::Layer::Zero(size_x, size_y)) {}
  /// Raises every cell whose centre p has (p - point) · (cos h, sin h) >= 0 by `rise_m`: a
  /// straight step through `point` whose uphill side lies towards heading h.
  DirectedTestLayer& Step(const common::Vector2& point, double heading_rad, double rise_m) {
    const common::Vector2 u(std::cos(heading_rad), std::sin(heading_rad));
    for (int iy = 0; iy < layer.geometry.size_y; ++iy) {
      for (int ix = 0; ix < layer.geometry.size_x; ++ix) {
        if ((layer.geometry.CenterOf({ix, iy}) - point).dot(u) >= -1e-9) {
          height(ix, iy) += static_cast<float>(rise_m);
        }
      }
    }
    return *this;
  }
  /// Derives the directed layer from the heights and makes the cost layer lethal where it is
  /// non-zero (keeping cells already lethal or unknown as they are).
  DirectedTestLayer& Derive(double max_up_m = 0.03, double max_down_m = 0.10) {
    static const int kDx[8] = {1, 1, 0, -1, -1, -1, 0, 1};
    static const int kDy[8] = {0, 1, 1, 1, 0, -1, -1, -1};
    const int sx = layer.geometry.size_x, sy = layer.geometry.size_y;
    for (int iy = 0; iy < sy; ++iy) {
      for (int ix = 0; ix < sx; ++ix) {
        int mask = 0;
        for (int k = 0; k < 8; ++k) {
          const int nx = ix + kDx[k], ny = iy + kDy[k];
          if (nx < 0 || ny < 0 || nx >= sx || ny >= sy) continue;
          const double dh = height(nx, ny) - height(ix, iy);
          if (dh > max_up_m || -dh > max_down_m) mask |= 1 << k;
        }
        directed(ix, iy) = static_cast<float>(mask);
        if (std::isnan(layer.cost(ix, iy))) {
          directed(ix, iy) = NAN;
        } else if (layer.cost(ix, iy) >= 100.0f) {
          directed(ix, iy) = 255.0f;
        } else if (mask != 0) {
          layer.cost(ix, iy) = 100.0f;
        }
      }
    }
    return *this;
  }
  std::shared_ptr<const CostMap> Build(const std::vector<common::Vector2>& footprint,
                                       CostMapParams params = {}) const {
    return std::make_shared<const CostMap>(layer.geometry, layer.cost, directed, footprint, params);
  }
};

/// A corridor 12 m × 4 m at 0.1 m (walls 0.3 m thick along both sides) with an 8 cm step
/// across it at x = 6 m: the platform x >= 6 is higher, so the Pioneer may drive down it
/// (towards -x) and never up. With `ramp_from_y_m` < 4 the corridor is 6 m wide and the step
/// spans only y below `ramp_from_y_m`; above it the platform is reached by a ramp (the rise
/// spread over x in [3, 6], a 1.5 deg slope) whose side drops onto the lower floor.
inline DirectedTestLayer OneWayStepCorridor(double ramp_from_y_m = 10.0) {
  const bool ramp = ramp_from_y_m < 4.0;
  const double width = ramp ? 6.0 : 4.0;
  DirectedTestLayer d(120, static_cast<int>(std::lround(width / 0.1)), 0.1);
  d.layer.Rect(0.0, 0.0, 12.0, 0.3, 100.0f).Rect(0.0, width - 0.3, 12.0, width, 100.0f);
  for (int iy = 0; iy < d.layer.geometry.size_y; ++iy) {
    for (int ix = 0; ix < d.layer.geometry.size_x; ++ix) {
      const common::Vector2 c = d.layer.geometry.CenterOf({ix, iy});
      if (c.y() < ramp_from_y_m) {
        d.height(ix, iy) = c.x() >= 6.0 ? 0.08f : 0.0f;
      } else {
        d.height(ix, iy) = static_cast<float>(0.08 * std::clamp((c.x() - 3.0) / 3.0, 0.0, 1.0));
      }
    }
  }
  return std::move(d.Derive());
}

}  // namespace cairn::planner::testing
