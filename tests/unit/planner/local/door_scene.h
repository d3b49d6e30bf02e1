#pragma once

#include <memory>
#include <vector>

#include "common/velocity_limits.h"
#include "planner/cost_map.h"
#include "planner/path.h"
#include "tests/unit/planner/test_maps.h"

/// The apartment's bathroom door as a laser-only Kobuki met it, for the local planner's tests.

namespace cairn::planner::testing {

// A Kobuki (round, 0.176 m) at rest in the apartment's corridor, just west of the bathroom's
// 0.8 m door, facing 30 deg off the corridor: the path runs on east and bends north through the
// door, 5 cm from its western frame (the map as the navigator had it when it stalled there).
// Every constant arc that reaches the door clips the frame, and the rest gain less than
// standing still costs, so the dynamic window alone stands still for ever; the path-tracking
// candidates follow the bend.
struct KobukiDoorScene {
  KobukiDoorScene() : layer(100, 100, 0.05, 0.0f, common::Pose2{5.0, 4.0, 0.0}) {
    layer.Rect(5.0, 5.68, 7.5, 5.86, 100.0f).Rect(8.32, 5.68, 10.0, 5.86, 100.0f);  // the door
    round = KobukiFootprint();
    map = layer.Build(round);
    kobuki.max_vel_x_mps = 0.5;
    kobuki.min_vel_x_mps = -0.1;
    kobuki.max_vel_theta_radps = 1.5;
    kobuki.acc_lim_x_mps2 = 1.0;
    kobuki.acc_lim_theta_radps2 = 2.0;
  }
  TestLayer layer;
  std::vector<common::Vector2> round;
  std::shared_ptr<const CostMap> map;
  common::VelocityLimits kobuki;
};

// The path from the corridor through the bathroom door, as the navigator had it.
inline Path DoorPath() {
  return Path({{7.07, 5.39, 0.2},
               {7.36, 5.44, 0.2},
               {7.64, 5.50, 0.5},
               {7.68, 5.56, 1.0},
               {7.74, 5.71, 1.2},
               {7.77, 5.79, 1.57},
               {7.74, 5.98, 1.6},
               {7.71, 6.17, 1.6},
               {7.7, 7.0, 1.6}});
}

}  // namespace cairn::planner::testing
