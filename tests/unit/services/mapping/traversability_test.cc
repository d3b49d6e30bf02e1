#include "services/mapping/traversability.h"

#include <cmath>
#include <random>
#include <stdexcept>

#include <gtest/gtest.h>

#include "common/layers.h"
#include "tests/unit/services/mapping/terrain_fixtures.h"

namespace cairn::mapping {
namespace {

using common::GridMap;
using common::Layer;
using testing::kDeg;
using testing::LenientProfile;
using testing::MakeTerrain;
using testing::Plane;
using testing::ShippedProfile;

constexpr double kRes = 0.2;

// Interior cells: at least 0.4 m (two cells) from every edge.
template <typename Fn>
void ForInterior(const GridMap& map, Fn fn) {
  for (int iy = 2; iy < map.size_y() - 2; ++iy) {
    for (int ix = 2; ix < map.size_x() - 2; ++ix) fn(ix, iy);
  }
}

float Cost(const GridMap& map, const std::string& profile, int ix, int iy) {
  return map.at(layers::CostLayer(profile))(ix, iy);
}

float Mask(const GridMap& map, const std::string& profile, int ix, int iy) {
  return map.at(layers::DirectedLayer(profile))(ix, iy);
}

// Seed 000 test 1: slope = acos(n_z) of the PCA normal over 0.3 m, within 0.05 deg.
TEST(TraversabilityTest, SlopeOfTiltedPlanes) {
  for (double deg : {0.0, 5.0, 8.0, 10.0, 11.0}) {
    for (double azimuth : {0.0, 0.7, 2.5}) {
      GridMap map = MakeTerrain(20, 16, kRes, Plane(deg * kDeg, azimuth));
      ComputeGeometricLayers(&map, {});
      ForInterior(map, [&](int ix, int iy) {
        EXPECT_NEAR(map.at(layers::kSlope)(ix, iy) / kDeg, deg, 0.05)
            << deg << " deg at azimuth " << azimuth << " cell " << ix << "," << iy;
        EXPECT_NEAR(map.at(layers::kRoughness)(ix, iy), 0.0, 1e-4);
      });
    }
  }
}

// Seed 000 test 2: at r = 0.15 m the window is one cell, so the normal falls back to vertical.
TEST(TraversabilityTest, NormalWindowSmallerThanACellGivesVerticalNormal) {
  GridMap map = MakeTerrain(12, 12, kRes, Plane(10 * kDeg));
  TraversabilityParams p;
  p.normal_radius_m = 0.15;
  ComputeGeometricLayers(&map, p);
  ForInterior(map, [&](int ix, int iy) { EXPECT_EQ(map.at(layers::kSlope)(ix, iy), 0.f); });
  // At 0.3 m the window holds the 3 x 3 block: a single raised neighbour tilts the normal.
  GridMap bump = MakeTerrain(12, 12, kRes, [](double x, double y) {
    return (std::floor(x / kRes) == 6 && std::floor(y / kRes) == 7) ? 0.05 : 0.0;
  });
  ComputeGeometricLayers(&bump, {});
  EXPECT_GT(bump.at(layers::kSlope)(6, 6), 0.01);  // (6, 7) is inside (6, 6)'s window
  EXPECT_GT(bump.at(layers::kSlope)(7, 6), 0.01);  // diagonal, 0.283 m < 0.3 m
  EXPECT_EQ(bump.at(layers::kSlope)(6, 5), 0.f);   // 0.4 m away: outside the window
}

TEST(TraversabilityTest, FewerThanThreePointsGiveVerticalNormal) {
  GridMap map = MakeTerrain(8, 8, kRes, [](double x, double y) {
    const int ix = static_cast<int>(std::floor(x / kRes)),
              iy = static_cast<int>(std::floor(y / kRes));
    if (iy == 4 && (ix == 4 || ix == 5)) return 0.1 * ix;  // two lonely cells, 10 cm apart
    return std::nan("");
  });
  ComputeGeometricLayers(&map, {});
  EXPECT_EQ(map.at(layers::kSlope)(4, 4), 0.f);
  EXPECT_EQ(map.at(layers::kSlope)(5, 4), 0.f);
  EXPECT_NEAR(map.at(layers::kStepMax)(4, 4), 0.1, 1e-6);
  EXPECT_TRUE(std::isnan(map.at(layers::kSlope)(0, 0)));
}

// A lidar ring seen from afar crosses a ramp as a strip one cell wide between unknown cells: the
// cells fix the slope along the strip only. On a 5 deg ramp rising in x, a strip along y (heights
// with a millimetre of noise) is level along its length; a strip along x rises at 5 deg; a
// diagonal strip at 5 deg x cos 45. None of them is a wall.
TEST(TraversabilityTest, CellsOnOneLineGiveTheSlopeAlongTheLine) {
  const double t = std::tan(5 * kDeg);
  auto cell = [](double v) { return static_cast<int>(std::floor(v / kRes)); };
  auto noise = [](int i) { return (i % 3 - 1) * 0.001; };
  GridMap across = MakeTerrain(12, 12, kRes, [&](double x, double y) {
    return cell(x) == 6 ? t * x + noise(cell(y)) : std::nan("");
  });
  GridMap along = MakeTerrain(
      12, 12, kRes, [&](double x, double y) { return cell(y) == 6 ? t * x : std::nan(""); });
  GridMap diagonal = MakeTerrain(
      12, 12, kRes, [&](double x, double y) { return cell(x) == cell(y) ? t * x : std::nan(""); });
  for (GridMap* map : {&across, &along, &diagonal}) ComputeGeometricLayers(map, {});
  for (int i = 3; i <= 8; ++i) {
    EXPECT_LT(across.at(layers::kSlope)(6, i) / kDeg, 1.0) << "cell 6," << i;
    EXPECT_NEAR(along.at(layers::kSlope)(i, 6) / kDeg, 5.0, 0.05) << "cell " << i << ",6";
    // Along the diagonal the height rises t per metre of x, over sqrt(2) m.
    EXPECT_NEAR(diagonal.at(layers::kSlope)(i, i), std::atan(t / std::sqrt(2.0)), 0.05 * kDeg)
        << "cell " << i;
  }
  // The cost layer: a 5 deg ramp is free for the pioneer3at; a strip is no wall.
  ComputeCostLayer(&across, ShippedProfile("pioneer3at"), {});
  for (int i = 3; i <= 8; ++i) EXPECT_LT(Cost(across, "pioneer3at", 6, i), 100.f) << i;
}
// Seed 000 test 3: 5 and 7.5 deg planes are crossable for an 8 deg profile, 8.5 and 10 deg not.
TEST(TraversabilityTest, SlopeThresholdAgainstPioneer) {
  const common::RobotProfile pioneer = ShippedProfile("pioneer3at");
  ASSERT_NEAR(pioneer.max_slope_up_rad / kDeg, 8.0, 1e-9);
  for (double deg : {5.0, 7.5, 8.5, 10.0}) {
    GridMap map = MakeTerrain(20, 20, kRes, Plane(deg * kDeg, 0.3));
    ComputeCostLayer(&map, pioneer, {});
    ForInterior(map, [&](int ix, int iy) {
      const float c = Cost(map, "pioneer3at", ix, iy);
      if (deg < 8.0) {
        EXPECT_LT(c, layers::kCostLethal) << deg << " deg";
        EXPECT_GT(c, layers::kCostFree) << deg << " deg uses most of the limit: graded";
      } else {
        EXPECT_EQ(c, layers::kCostLethal) << deg << " deg";
      }
    });
  }
  // The graded cost grows with the slope; flat ground is free.
  GridMap flat = MakeTerrain(12, 12, kRes, Plane(0.0));
  GridMap five = MakeTerrain(12, 12, kRes, Plane(5 * kDeg));
  GridMap seven = MakeTerrain(12, 12, kRes, Plane(7.5 * kDeg));
  for (GridMap* m : {&flat, &five, &seven}) ComputeCostLayer(m, pioneer, {});
  EXPECT_EQ(Cost(flat, "pioneer3at", 6, 6), layers::kCostFree);
  EXPECT_LT(Cost(five, "pioneer3at", 6, 6), Cost(seven, "pioneer3at", 6, 6));
}

// Graded costs are whole numbers from 1 up (a ROS occupancy grid's values), so a cost layer
// packs into one byte per cell; a cost of the share just above free_fraction rounds up to 1.
TEST(TraversabilityTest, GradedCostsAreWholeNumbers) {
  const common::RobotProfile pioneer = ShippedProfile("pioneer3at");
  for (double deg : {2.5, 2.6, 3.0, 5.0, 6.1, 7.5, 7.9}) {
    GridMap map = MakeTerrain(12, 12, kRes, Plane(deg * kDeg, 0.2));
    ComputeCostLayer(&map, pioneer, {});
    ForInterior(map, [&](int ix, int iy) {
      const float c = Cost(map, "pioneer3at", ix, iy);
      EXPECT_EQ(c, std::round(c)) << deg << " deg";
      EXPECT_TRUE(c == layers::kCostFree || (c >= 1.f && c <= 90.f)) << deg << " deg: " << c;
    });
  }
  // 2.41 deg is just over free_fraction (0.3) of 8 deg: graded, the smallest graded cost.
  GridMap barely = MakeTerrain(12, 12, kRes, Plane(2.41 * kDeg));
  ComputeCostLayer(&barely, pioneer, {});
  EXPECT_EQ(Cost(barely, "pioneer3at", 6, 6), 1.f);
}

// The slope rule alone (steps and roughness unlimited) at 8.5 deg, and the boundary value.
TEST(TraversabilityTest, SlopeRuleAloneIsInclusiveOfTheLimit) {
  common::RobotProfile p = LenientProfile();
  p.max_slope_up_rad = 8.0 * kDeg;
  GridMap steep = MakeTerrain(12, 12, kRes, Plane(8.5 * kDeg));
  GridMap gentle = MakeTerrain(12, 12, kRes, Plane(7.5 * kDeg));
  ComputeCostLayer(&steep, p, {});
  ComputeCostLayer(&gentle, p, {});
  EXPECT_EQ(Cost(steep, "test", 6, 6), layers::kCostLethal);
  EXPECT_LT(Cost(gentle, "test", 6, 6), layers::kCostLethal);
  // The down limit counts too: the slope is unsigned on a non-directional grid.
  p.max_slope_up_rad = 20 * kDeg;
  p.max_slope_down_rad = 8.0 * kDeg;
  ComputeCostLayer(&steep, p, {});
  EXPECT_EQ(Cost(steep, "test", 6, 6), layers::kCostLethal);
}

// A map with a straight step along x = 1.0 m: h = 0 for x < 1, `rise` beyond.
GridMap StepMap(double rise) {
  return MakeTerrain(10, 8, kRes, [rise](double x, double) { return x < 1.0 ? 0.0 : rise; });
}

// Seed 000 test 4: step up of exactly 3 cm is free, 3.1 cm lethal (on the low side).
TEST(TraversabilityTest, StepUpBoundaryIsInclusive) {
  common::RobotProfile p = LenientProfile();
  p.max_step_up_m = 0.03;
  GridMap at_limit = StepMap(0.030), over = StepMap(0.031);
  ComputeCostLayer(&at_limit, p, {});
  ComputeCostLayer(&over, p, {});
  for (int iy = 1; iy < 7; ++iy) {
    EXPECT_LT(Cost(at_limit, "test", 4, iy), layers::kCostLethal);  // low side, next to the edge
    EXPECT_LT(Cost(at_limit, "test", 5, iy), layers::kCostLethal);
    EXPECT_EQ(Cost(over, "test", 4, iy), layers::kCostLethal);
    EXPECT_LT(Cost(over, "test", 5, iy), layers::kCostLethal);  // going down 3.1 cm is fine
    EXPECT_LT(Cost(over, "test", 3, iy), layers::kCostLethal);  // one cell further is flat
  }
}

// The same boundary on a high base (float elevations far from zero) still holds.
TEST(TraversabilityTest, StepBoundaryHoldsAtHighElevation) {
  common::RobotProfile p = LenientProfile();
  p.max_step_up_m = 0.03;
  GridMap map = MakeTerrain(10, 8, kRes, [](double x, double) { return x < 1.0 ? 123.5 : 123.53; });
  ComputeCostLayer(&map, p, {});
  EXPECT_LT(Cost(map, "test", 4, 4), layers::kCostLethal);
}

// A lethal step edge is at least two cells long (min_step_edge_cells = 2): one cell 4 cm above
// its neighbours on a flat floor is elevation noise, a straight 4 cm edge is a step. With 1 (the
// seed's per-pair rule) the lone cell makes its neighbours lethal.
TEST(TraversabilityTest, LoneHighCellIsNoStepButAnEdgeIs) {
  common::RobotProfile p = LenientProfile();
  p.max_step_up_m = 0.03;
  GridMap lone = MakeTerrain(10, 10, kRes, [](double x, double y) {
    return (x >= 1.0 && x < 1.2 && y >= 1.0 && y < 1.2) ? 0.04 : 0.0;
  });
  TraversabilityParams params;
  ComputeCostLayer(&lone, p, params);
  EXPECT_LT(Cost(lone, "test", 4, 5), layers::kCostLethal);  // beside the lone cell
  EXPECT_LT(Cost(lone, "test", 5, 4), layers::kCostLethal);
  EXPECT_GT(Cost(lone, "test", 4, 5), layers::kCostFree);  // at the limit: graded, not free
  GridMap edge = StepMap(0.04);
  ComputeCostLayer(&edge, p, params);
  for (int iy = 1; iy < 7; ++iy) EXPECT_EQ(Cost(edge, "test", 4, iy), layers::kCostLethal);
  params.min_step_edge_cells = 1;
  ComputeCostLayer(&lone, p, params);
  EXPECT_EQ(Cost(lone, "test", 4, 5), layers::kCostLethal);
  EXPECT_EQ(Cost(lone, "test", 5, 4), layers::kCostLethal);
}

// Seed 000 test 5: from the high cell, a drop of exactly 10 cm is free, 10.1 cm lethal.
TEST(TraversabilityTest, StepDownBoundaryIsInclusive) {
  common::RobotProfile p = LenientProfile();
  p.max_step_down_m = 0.10;
  GridMap at_limit = StepMap(0.100), over = StepMap(0.101);
  ComputeCostLayer(&at_limit, p, {});
  ComputeCostLayer(&over, p, {});
  for (int iy = 1; iy < 7; ++iy) {
    EXPECT_LT(Cost(at_limit, "test", 5, iy), layers::kCostLethal);  // high side
    EXPECT_EQ(Cost(over, "test", 5, iy), layers::kCostLethal);
    EXPECT_LT(Cost(over, "test", 4, iy), layers::kCostLethal);  // climbing is unlimited here
  }
}

// Seed 000 test 6: a 5 cm step for the P3-AT: low side lethal (step up), high side crossable.
TEST(TraversabilityTest, StepDirectionAsymmetryForPioneer) {
  const common::RobotProfile pioneer = ShippedProfile("pioneer3at");
  GridMap map = StepMap(0.05);
  ComputeCostLayer(&map, pioneer, {});
  for (int iy = 1; iy < 7; ++iy) {
    EXPECT_EQ(Cost(map, "pioneer3at", 4, iy), layers::kCostLethal);
    EXPECT_LT(Cost(map, "pioneer3at", 5, iy), layers::kCostLethal);
    EXPECT_LT(Cost(map, "pioneer3at", 2, iy), layers::kCostLethal);
    EXPECT_LT(Cost(map, "pioneer3at", 7, iy), layers::kCostLethal);
  }
}

// Seed 000 test 7: at 0.2 m, a 9 deg plane rises 3.17 cm per cell: lethal by the step rule
// alone; an 8.3 deg plane (2.92 cm) passes the step rule but fails the slope rule.
TEST(TraversabilityTest, ResolutionCouplesStepAndSlope) {
  common::RobotProfile steps_only = LenientProfile("steps");
  steps_only.max_step_up_m = 0.03;
  GridMap nine = MakeTerrain(12, 12, kRes, Plane(9 * kDeg));
  ComputeCostLayer(&nine, steps_only, {});
  ForInterior(nine,
              [&](int ix, int iy) { EXPECT_EQ(Cost(nine, "steps", ix, iy), layers::kCostLethal); });

  GridMap eight3 = MakeTerrain(12, 12, kRes, Plane(8.3 * kDeg));
  ComputeCostLayer(&eight3, steps_only, {});
  ComputeCostLayer(&eight3, ShippedProfile("pioneer3at"), {});
  ForInterior(eight3, [&](int ix, int iy) {
    EXPECT_LT(Cost(eight3, "steps", ix, iy), layers::kCostLethal);
    EXPECT_EQ(Cost(eight3, "pioneer3at", ix, iy), layers::kCostLethal);
  });
}

// Seed 000 test 8: unknown elevation gives unknown cost; border cells are unknown.
TEST(TraversabilityTest, UnknownAndBorderCells) {
  GridMap map = MakeTerrain(10, 10, kRes, [](double x, double y) {
    return (x > 1.0 && x < 1.4 && y > 1.0 && y < 1.4) ? std::nan("") : 0.0;
  });
  const common::RobotProfile p = LenientProfile();
  ComputeCostLayer(&map, p, {});
  EXPECT_TRUE(std::isnan(Cost(map, "test", 5, 5)));
  EXPECT_TRUE(std::isnan(Cost(map, "test", 6, 6)));
  EXPECT_EQ(Cost(map, "test", 4, 5), layers::kCostFree);  // next to unknown: judged on the rest
  for (int i = 0; i < 10; ++i) {
    EXPECT_TRUE(std::isnan(Cost(map, "test", 0, i)));
    EXPECT_TRUE(std::isnan(Cost(map, "test", 9, i)));
    EXPECT_TRUE(std::isnan(Cost(map, "test", i, 0)));
    EXPECT_TRUE(std::isnan(Cost(map, "test", i, 9)));
  }
  TraversabilityParams lethal_unknown;
  lethal_unknown.unknown_is_lethal = true;
  ComputeCostLayer(&map, p, lethal_unknown);
  EXPECT_EQ(Cost(map, "test", 5, 5), layers::kCostLethal);
  EXPECT_EQ(Cost(map, "test", 0, 3), layers::kCostLethal);
}

// Seed 000 test 9: with a 1.6 m unknown square around the robot, the 16 cells whose centres lie
// strictly within +-0.5 m are free, the other unknown cells stay unknown. The zone follows the
// robot, not the map centre.
TEST(TraversabilityTest, BlindZoneAroundTheRobot) {
  GridMap map = MakeTerrain(60, 60, kRes, [](double x, double y) {
    return (std::fabs(x - 6.0) < 0.8 && std::fabs(y - 6.0) < 0.8) ? std::nan("") : 0.0;
  });
  const common::RobotProfile p = LenientProfile();
  ComputeCostLayer(&map, p, {}, common::Vector2(6.0, 6.0));
  int free_cells = 0, unknown_cells = 0;
  for (int iy = 26; iy < 34; ++iy) {
    for (int ix = 26; ix < 34; ++ix) {
      const float c = Cost(map, "test", ix, iy);
      const bool inside = ix >= 28 && ix < 32 && iy >= 28 && iy < 32;
      if (inside) {
        EXPECT_EQ(c, layers::kCostFree) << ix << "," << iy;
        ++free_cells;
      } else {
        EXPECT_TRUE(std::isnan(c)) << ix << "," << iy;
        ++unknown_cells;
      }
    }
  }
  EXPECT_EQ(free_cells, 16);
  EXPECT_EQ(unknown_cells, 48);
  // Without a robot position nothing is forced free.
  ComputeCostLayer(&map, p, {});
  EXPECT_TRUE(std::isnan(Cost(map, "test", 29, 29)));
  // Elsewhere on the map, around a robot standing at (2, 9): the zone moves with it.
  GridMap other = MakeTerrain(60, 60, kRes, [](double x, double y) {
    return (std::fabs(x - 2.0) < 0.8 && std::fabs(y - 9.0) < 0.8) ? std::nan("") : 0.0;
  });
  ComputeCostLayer(&other, p, {}, common::Vector2(2.0, 9.0));
  EXPECT_EQ(Cost(other, "test", 10, 45), layers::kCostFree);
  EXPECT_TRUE(std::isnan(Cost(other, "test", 7, 42)));
}

// Seed 000 test 10: a 6 deg plane (relative to a pitched robot) with pitch +5 deg reads 11 deg:
// lethal for 8 deg; pitch 0 or compensation off: crossable.
TEST(TraversabilityTest, ImuPitchCompensation) {
  const common::RobotProfile pioneer = ShippedProfile("pioneer3at");
  GridMap map = MakeTerrain(12, 12, kRes, Plane(6 * kDeg));
  TraversabilityParams on;
  on.imu_pitch_compensation = true;
  ComputeCostLayer(&map, pioneer, on, std::nullopt, 5 * kDeg);
  EXPECT_EQ(Cost(map, "pioneer3at", 6, 6), layers::kCostLethal);
  ComputeCostLayer(&map, pioneer, on, std::nullopt, 0.0);
  EXPECT_LT(Cost(map, "pioneer3at", 6, 6), layers::kCostLethal);
  ComputeCostLayer(&map, pioneer, TraversabilityParams{}, std::nullopt, 5 * kDeg);  // world frame
  EXPECT_LT(Cost(map, "pioneer3at", 6, 6), layers::kCostLethal);

  // With the heading known the normals are tilted exactly: the rising plane still reads 11 deg,
  // and level ground ahead of a robot pitched up on a 5 deg ramp (seen as -5 deg) reads 0 deg
  // instead of the seed's 10 deg.
  RobotContext robot;
  robot.yaw_rad = 0.0;
  robot.pitch_rad = 5 * kDeg;
  ComputeCostLayer(&map, pioneer, on, robot, CellRect::All(map));
  EXPECT_EQ(Cost(map, "pioneer3at", 6, 6), layers::kCostLethal);
  GridMap level_ahead = MakeTerrain(12, 12, kRes, Plane(-5 * kDeg));
  ComputeGeometricLayers(&level_ahead, on);
  ComputeCostLayer(&level_ahead, pioneer, on, robot, CellRect::All(level_ahead));
  EXPECT_EQ(Cost(level_ahead, "pioneer3at", 6, 6), layers::kCostFree);
  ComputeCostLayer(&level_ahead, pioneer, on, std::nullopt, 5 * kDeg);
  EXPECT_EQ(Cost(level_ahead, "pioneer3at", 6, 6), layers::kCostLethal);
}

// Seed 000 test 11: geometry on an asymmetric pattern. A 20 cm block at one off-centre cell of a
// non-square grid with an offset origin: the cells around it, found by world position and by
// storage order, are the ones that turn lethal.
TEST(TraversabilityTest, GridIndexGeometryOnAnAsymmetricPattern) {
  const common::Pose2 origin{-1.3, 2.1, 0.0};
  const int nx = 17, ny = 11;
  const int bx = 12, by = 3;  // the block
  GridMap map = MakeTerrain(
      nx, ny, kRes,
      [&](double x, double y) {
        const int ix = static_cast<int>(std::floor((x + 1.3) / kRes));
        const int iy = static_cast<int>(std::floor((y - 2.1) / kRes));
        return (ix == bx && iy == by) ? 0.2 : 0.0;
      },
      origin);
  const common::RobotProfile pioneer = ShippedProfile("pioneer3at");
  ComputeCostLayer(&map, pioneer, {});
  const Layer& cost = map.at(layers::CostLayer("pioneer3at"));
  // Storage order: x fastest from the minimum corner.
  EXPECT_EQ(cost.data()[(bx - 1) + by * nx], layers::kCostLethal);
  EXPECT_EQ(cost.data()[bx + (by + 1) * nx], layers::kCostLethal);
  // The world position of the block's west neighbour maps to that cell.
  const common::Vector2 west(-1.3 + (bx - 1 + 0.5) * kRes, 2.1 + (by + 0.5) * kRes);
  EXPECT_EQ(map.ValueAt(layers::CostLayer("pioneer3at"), west), layers::kCostLethal);
  // Transposed and mirrored positions are far from the block and stay free.
  EXPECT_EQ(cost(by, bx - 4), layers::kCostFree);  // transposed (x <-> y), inside the grid
  EXPECT_EQ(cost(nx - 1 - bx, by), layers::kCostFree);
  EXPECT_EQ(cost(bx, ny - 1 - by), layers::kCostFree);
  // Every lethal cell is within one cell of the block.
  for (int iy = 0; iy < ny; ++iy) {
    for (int ix = 0; ix < nx; ++ix) {
      if (cost(ix, iy) == layers::kCostLethal) {
        EXPECT_LE(std::abs(ix - bx) + std::abs(iy - by), 2) << ix << "," << iy;
      }
    }
  }
}

// A trench 0.6 m wide across the map whose bottom the sensor looked into (ground bound 0.2 m
// below the rims) but never saw: a ditch, lethal for both shipped ground profiles.
GridMap TrenchMap(double width_m, double bound_m, bool with_bound = true) {
  GridMap map = MakeTerrain(30, 12, kRes, [width_m](double x, double) {
    return (x > 2.0 && x < 2.0 + width_m) ? std::nan("") : 0.0;
  });
  if (with_bound) {
    Layer& b = map.AddLayer(layers::kGroundBound);
    const Layer& h = map.at(layers::kElevation);
    for (int iy = 0; iy < map.size_y(); ++iy) {
      for (int ix = 0; ix < map.size_x(); ++ix) {
        if (std::isnan(h(ix, iy))) b(ix, iy) = static_cast<float>(bound_m);
      }
    }
  }
  return map;
}

TEST(TraversabilityTest, UnseenTrenchIsADitch) {
  GridMap map = TrenchMap(0.6, -0.2);
  const common::RobotProfile pioneer = ShippedProfile("pioneer3at");
  const common::RobotProfile rover = ShippedProfile("rover");
  ComputeCostLayer(&map, pioneer, {});
  ComputeCostLayer(&map, rover, {});
  for (int ix = 10; ix < 13; ++ix) {
    EXPECT_NEAR(map.at(layers::kDitchDepth)(ix, 6), 0.2, 1e-5);
    EXPECT_NEAR(map.at(layers::kDitchWidth)(ix, 6), 0.6, 1e-5);
    EXPECT_EQ(Cost(map, "pioneer3at", ix, 6), layers::kCostLethal);
    EXPECT_EQ(Cost(map, "rover", ix, 6), layers::kCostLethal);
  }
  // The rims themselves are ground.
  EXPECT_TRUE(std::isnan(map.at(layers::kDitchDepth)(9, 6)));
  EXPECT_LT(Cost(map, "rover", 8, 6), layers::kCostLethal);
}

// Issue 17: a shadow behind a crest in a valley between two 5 deg flanks. The rays over the
// shadow passed just above its bottom, more than 5 cm below both rims (the valley is real), but
// the flanks continued at their own slopes meet above the rays, and its walls are gentle: natural
// ground, no ditch. The same gap between level rims is one.
TEST(TraversabilityTest, AShadowInAValleyIsNoDitch) {
  const double t = std::tan(5 * kDeg);
  auto ground = [t](double x) { return std::fabs(x - 3.8) * t; };
  GridMap map = MakeTerrain(40, 12, kRes, [&](double x, double) {
    return (x > 3.0 && x < 4.6) ? std::nan("") : ground(x);  // the shadow
  });
  Layer& b = map.AddLayer(layers::kGroundBound);
  const Layer& h = map.at(layers::kElevation);
  for (int iy = 0; iy < map.size_y(); ++iy) {
    for (int ix = 0; ix < map.size_x(); ++ix) {
      if (std::isnan(h(ix, iy))) b(ix, iy) = static_cast<float>(ground((ix + 0.5) * kRes) + 0.005);
    }
  }
  ASSERT_GT(h(14, 6) - b(18, 6), 0.05);  // the old rule's ditch
  ComputeCostLayer(&map, ShippedProfile("pioneer3at"), {});
  for (int ix = 15; ix < 23; ++ix) {
    EXPECT_TRUE(std::isnan(map.at(layers::kDitchDepth)(ix, 6))) << ix;
    EXPECT_TRUE(std::isnan(Cost(map, "pioneer3at", ix, 6))) << ix;
  }
  GridMap level = TrenchMap(1.2, -0.06);
  ComputeCostLayer(&level, ShippedProfile("pioneer3at"), {});
  EXPECT_FALSE(std::isnan(level.at(layers::kDitchDepth)(12, 6)));
}

// Issue 17: the shadow at the foot of a rock, seen from beside it, between the rock's flat top
// (25 cm, 1 m across) and the hillside rising gently (4 deg) beyond the shadow. The rock's top
// passes for a bank and the hillside reaches 5 cm above the rays within a metre, but only the
// rock side has a wall: natural ground, no ditch. With a 6 cm bank standing where the hillside
// rose, both sides have walls and the gap is a ditch.
TEST(TraversabilityTest, TheShadowBetweenARockAndAGentleRiseIsNoDitch) {
  const double t = std::tan(4 * kDeg);
  for (const bool bank : {false, true}) {
    auto ground = [&](double x) {
      if (x >= 2.0 && x < 3.0) return 0.25;  // the rock's top
      if (x < 3.0) return 0.0;
      return bank ? (x >= 3.4 ? 0.06 : 0.0) : (x - 3.0) * t;
    };
    GridMap map = MakeTerrain(40, 12, kRes, [&](double x, double) {
      return (x >= 3.0 && x < 3.2) ? std::nan("") : ground(x);  // the shadow
    });
    Layer& b = map.AddLayer(layers::kGroundBound);
    const Layer& h = map.at(layers::kElevation);
    for (int iy = 0; iy < map.size_y(); ++iy) {
      for (int ix = 0; ix < map.size_x(); ++ix) {
        if (std::isnan(h(ix, iy)))
          b(ix, iy) = static_cast<float>(ground((ix + 0.5) * kRes) + 0.005);
      }
    }
    ComputeCostLayer(&map, ShippedProfile("pioneer3at"), {});
    EXPECT_EQ(std::isnan(map.at(layers::kDitchDepth)(15, 6)), !bank) << "bank " << bank;
  }
}

// Issue 17: the floor in a concave corner, where a platform's 8 cm drop (x < 2) meets the side
// of a raised lane half (y >= 2.4), with the cells at the foot of both faces unseen (rays bound
// them at the floor). Only the diagonal between the two faces has a rim on each side: open floor
// along both axes, no ditch. With a bank at x >= 2.8 too, the floor is bounded along x: a
// trench, and a ditch.
TEST(TraversabilityTest, TheFloorInAConcaveCornerIsNoDitch) {
  for (const bool bank : {false, true}) {
    auto ground = [&](double x, double y) {
      if (x < 2.0 || y >= 2.4) return 0.08;
      return bank && x >= 2.8 ? 0.08 : 0.0;
    };
    GridMap map = MakeTerrain(40, 30, kRes, [&](double x, double y) {
      const bool foot = x >= 2.0 && x < 2.4 && y < 2.4 && y >= 0.8;  // along the drop's face
      const bool side = y >= 2.0 && y < 2.4 && x >= 2.0 && x < 3.6;  // along the raised half
      return (foot || side) ? std::nan("") : ground(x, y);
    });
    Layer& b = map.AddLayer(layers::kGroundBound);
    const Layer& h = map.at(layers::kElevation);
    for (int iy = 0; iy < map.size_y(); ++iy) {
      for (int ix = 0; ix < map.size_x(); ++ix) {
        if (std::isnan(h(ix, iy))) b(ix, iy) = static_cast<float>(0.005);
      }
    }
    ComputeCostLayer(&map, ShippedProfile("pioneer3at"), {});
    const Layer& depth = map.at(layers::kDitchDepth);
    int ditch_cells = 0;
    for (int iy = 0; iy < map.size_y(); ++iy) {
      for (int ix = 0; ix < map.size_x(); ++ix) ditch_cells += std::isnan(depth(ix, iy)) ? 0 : 1;
    }
    if (bank) {
      EXPECT_GT(ditch_cells, 0);
      EXPECT_FALSE(std::isnan(depth(10, 6)));  // (2.1, 1.3): between the drop and the bank
    } else {
      EXPECT_EQ(ditch_cells, 0);
    }
  }
}

// Issue 17: a 6 deg slope seen as sparse noisy rings (every other row of cells known, heights
// off by up to 6 mm). The 3 x 3 window holds one line of cells; the fit takes the wider window
// and reads the slope within 1 deg.
TEST(TraversabilityTest, SparseNoisyGroundIsFittedOverTheWiderWindow) {
  const double t = std::tan(6 * kDeg);
  const float noise[5] = {0.006f, -0.005f, 0.002f, -0.006f, 0.004f};
  GridMap map = MakeTerrain(30, 30, kRes, [&](double x, double y) {
    const int iy = static_cast<int>(std::floor(y / kRes));
    const int ix = static_cast<int>(std::floor(x / kRes));
    if (iy % 2) return std::nan("");
    return x * t + noise[(ix * 3 + iy) % 5];
  });
  TraversabilityParams narrow_only;
  narrow_only.wide_normal_radius_m = 0.0;
  GridMap narrow = map;
  ComputeGeometricLayers(&narrow, narrow_only);
  ComputeGeometricLayers(&map, {});
  double worst = 0, worst_narrow = 0;
  for (int iy = 4; iy < 26; iy += 2) {
    for (int ix = 4; ix < 26; ++ix) {
      worst = std::max(worst, std::fabs(map.at(layers::kSlope)(ix, iy) - 6 * kDeg));
      worst_narrow =
          std::max(worst_narrow, std::fabs(narrow.at(layers::kSlope)(ix, iy) - 6 * kDeg));
    }
  }
  EXPECT_GT(worst_narrow, 1.5 * kDeg);
  EXPECT_LT(worst, 1 * kDeg);
}

TEST(TraversabilityTest, NarrowDitchIsBridgedByAWideEnoughRobot) {
  GridMap map = TrenchMap(0.2, -0.2);                                 // one cell
  const common::RobotProfile pioneer = ShippedProfile("pioneer3at");  // 0.10 m
  const common::RobotProfile rover = ShippedProfile("rover");         // 0.30 m
  ComputeCostLayer(&map, pioneer, {});
  ComputeCostLayer(&map, rover, {});
  EXPECT_NEAR(map.at(layers::kDitchWidth)(10, 6), 0.2, 1e-5);
  EXPECT_EQ(Cost(map, "pioneer3at", 10, 6), layers::kCostLethal);
  EXPECT_LT(Cost(map, "rover", 10, 6), layers::kCostLethal);
  EXPECT_LT(Cost(map, "rover", 9, 6), layers::kCostLethal);       // no drop rule into a bridged gap
  EXPECT_EQ(Cost(map, "pioneer3at", 9, 6), layers::kCostLethal);  // drop of 0.2 m > 0.1 m
}

TEST(TraversabilityTest, GapsNobodyLookedIntoStayUnknown) {
  const common::RobotProfile pioneer = ShippedProfile("pioneer3at");
  // No bound at all, and a bound above the rims (the gap between two lidar rings).
  GridMap never = TrenchMap(0.6, 0.0, /*with_bound=*/false);
  GridMap between_rings = TrenchMap(0.6, 0.04);
  for (GridMap* m : {&never, &between_rings}) {
    ComputeCostLayer(m, pioneer, {});
    EXPECT_TRUE(std::isnan(m->at(layers::kDitchDepth)(11, 6)));
    EXPECT_TRUE(std::isnan(Cost(*m, "pioneer3at", 11, 6)));
    EXPECT_LT(Cost(*m, "pioneer3at", 9, 6), layers::kCostLethal);
  }
}

TEST(TraversabilityTest, SeenBottomJoinsTheDitchButGroundAtRimLevelDoesNot) {
  // Trench 1.0 m wide with its last cell seen 0.3 m down.
  GridMap map = MakeTerrain(30, 12, kRes, [](double x, double) {
    if (x > 2.8 && x < 3.0) return -0.3;
    return (x > 2.0 && x < 3.0) ? std::nan("") : 0.0;
  });
  Layer& b = map.AddLayer(layers::kGroundBound);
  for (int ix = 10; ix < 14; ++ix) {
    for (int iy = 0; iy < 12; ++iy) b(ix, iy) = -0.15f;
  }
  ComputeGeometricLayers(&map, {});
  EXPECT_NEAR(map.at(layers::kDitchDepth)(14, 6), 0.3, 1e-5);  // seen bottom, true depth
  EXPECT_NEAR(map.at(layers::kDitchWidth)(14, 6), 1.0, 1e-5);
  EXPECT_NEAR(map.at(layers::kDitchDepth)(11, 6), 0.15, 1e-5);  // unseen: a lower bound
  EXPECT_TRUE(std::isnan(map.at(layers::kDitchDepth)(9, 6)));
  EXPECT_TRUE(std::isnan(map.at(layers::kDitchDepth)(15, 6)));
}

TEST(TraversabilityTest, AnUnhitCellAmongAStepsFaceCellsIsNoDitch) {
  // A 20 cm block from x = 3.0 (a cell border). Returns from its face raise the floor cells in
  // front of it (x in [2.8, 3.0)) to about 18 cm, except one that no return fell in; rays
  // crossed all of them at floor level on their way to the face (values seen by the mapper in
  // the tunnel). That cell lies between two 18 cm "rims" along the face, but they are no rims:
  // neither it nor the floor in front of it is a ditch, and the block's edge stays a step.
  GridMap map = MakeTerrain(30, 12, kRes, [](double x, double) {
    if (x > 2.8 && x < 3.0) return 0.18;
    return x > 3.0 ? 0.2 : 0.0;
  });
  Layer& h = map.at(layers::kElevation);
  h(14, 6) = std::nanf("");
  Layer& b = map.AddLayer(layers::kGroundBound);
  for (int iy = 0; iy < 12; ++iy) {
    for (int ix = 0; ix <= 14; ++ix) b(ix, iy) = 0.002f;
  }
  ComputeGeometricLayers(&map, {});
  for (int ix = 8; ix <= 16; ++ix) {
    for (int iy = 0; iy < 12; ++iy) {
      EXPECT_TRUE(std::isnan(map.at(layers::kDitchDepth)(ix, iy))) << ix << "," << iy;
    }
  }
  // The same cell between two rims that rays crossed well above the gap: a narrow ditch.
  for (int ix = 0; ix <= 14; ++ix) b(ix, 5) = b(ix, 7) = 0.25f;
  b(14, 6) = -0.1f;
  ComputeGeometricLayers(&map, {});
  EXPECT_FALSE(std::isnan(map.at(layers::kDitchDepth)(14, 6)));
}

// The terraces world's 0.6 m trench seen from 0.9 m before it (values the mapper kept): the last
// cell of the gap holds the far face's top returns (about rim height), and the rays that hit the
// face lower crossed it 12 cm down; the deck beyond is clean. That cell is part of the gap: the
// ditch spans all three cells, 0.6 m wide; without the face cell it was no ditch at all.
TEST(TraversabilityTest, AGapsFarFaceCellIsPartOfTheGap) {
  GridMap map = TrenchMap(0.6, 0.0);
  Layer& h = map.at(layers::kElevation);
  Layer& b = map.at(layers::kGroundBound);
  for (int iy = 0; iy < map.size_y(); ++iy) {
    b(10, iy) = -0.037f;
    b(11, iy) = -0.080f;
    h(12, iy) = 0.006f;
    b(12, iy) = -0.121f;
    for (int ix = 0; ix < map.size_x(); ++ix) {
      if (ix < 10 || ix > 12) b(ix, iy) = -0.004f;
    }
  }
  ComputeGeometricLayers(&map, {});
  for (int iy = 0; iy < map.size_y(); ++iy) {
    EXPECT_NEAR(map.at(layers::kDitchWidth)(11, iy), 0.6, 1e-5) << iy;
    EXPECT_NEAR(map.at(layers::kDitchDepth)(11, iy), 0.08, 0.01) << iy;
    EXPECT_FALSE(std::isnan(map.at(layers::kDitchDepth)(10, iy))) << iy;  // on the gap segment
  }
  // A face cell whose next cell is no clean rim (rays crossed it low too) ends the walk.
  for (int iy = 0; iy < map.size_y(); ++iy) b(13, iy) = -0.1f;
  ComputeGeometricLayers(&map, {});
  EXPECT_TRUE(std::isnan(map.at(layers::kDitchDepth)(11, 6)));
}

TEST(TraversabilityTest, DropIntoAnUnseenGapIsAStepDown) {
  // A platform 0.3 m high ends at x = 2; beyond it nothing was seen, but rays went down to 0.
  GridMap map =
      MakeTerrain(30, 12, kRes, [](double x, double) { return x < 2.0 ? 0.3 : std::nan(""); });
  Layer& b = map.AddLayer(layers::kGroundBound);
  for (int ix = 10; ix < 30; ++ix) {
    for (int iy = 0; iy < 12; ++iy) b(ix, iy) = 0.0f;
  }
  ComputeCostLayer(&map, ShippedProfile("pioneer3at"), {});
  ComputeCostLayer(&map, LenientProfile(), {});
  EXPECT_EQ(Cost(map, "pioneer3at", 9, 6), layers::kCostLethal);
  EXPECT_LT(Cost(map, "pioneer3at", 8, 6), layers::kCostLethal);
  // 10 m steps allowed, but nobody saw how deep it goes: lethal too. Judged by its lower bound
  // alone (unseen_drop_m 0), 0.3 m is within that profile's limit.
  EXPECT_EQ(Cost(map, "test", 9, 6), layers::kCostLethal);
  TraversabilityParams by_bound;
  by_bound.unseen_drop_m = 0.0;
  ComputeCostLayer(&map, LenientProfile(), by_bound);
  EXPECT_LT(Cost(map, "test", 9, 6), layers::kCostLethal);
}

// Seen from afar, a 20 cm drop's far side is hidden and the grazing rays prove only a few
// centimetres of it: the edge is lethal already, not once the robot is close enough for the
// rays to prove more than its step-down limit (10 cm for the pioneer3at).
TEST(TraversabilityTest, AShallowBoundOfAnUnseenDropIsLethalAlready) {
  GridMap map =
      MakeTerrain(30, 12, kRes, [](double x, double) { return x < 2.0 ? 0.2 : std::nan(""); });
  Layer& b = map.AddLayer(layers::kGroundBound);
  for (int ix = 10; ix < 30; ++ix) {
    for (int iy = 0; iy < 12; ++iy) b(ix, iy) = 0.2f - 0.06f;  // rays 6 cm below the platform
  }
  ComputeCostLayer(&map, ShippedProfile("pioneer3at"), {});
  EXPECT_EQ(Cost(map, "pioneer3at", 9, 6), layers::kCostLethal);
  EXPECT_LT(Cost(map, "pioneer3at", 8, 6), layers::kCostLethal);
  // Rays only 3 cm below (a gentle crest, or a plate's edge) prove no drop.
  for (int ix = 10; ix < 30; ++ix) {
    for (int iy = 0; iy < 12; ++iy) b(ix, iy) = 0.2f - 0.03f;
  }
  ComputeCostLayer(&map, ShippedProfile("pioneer3at"), {});
  EXPECT_LT(Cost(map, "pioneer3at", 9, 6), layers::kCostLethal);
  // Upstream rule (the profile's limit alone): 6 cm is crossable.
  for (int ix = 10; ix < 30; ++ix) {
    for (int iy = 0; iy < 12; ++iy) b(ix, iy) = 0.2f - 0.06f;
  }
  TraversabilityParams by_limit;
  by_limit.unseen_drop_m = 0.0;
  ComputeCostLayer(&map, ShippedProfile("pioneer3at"), by_limit);
  EXPECT_LT(Cost(map, "pioneer3at", 9, 6), layers::kCostLethal);
}

void ExpectMaskMatchesCost(const GridMap& map, const std::string& profile);

// An unseen drop whose bound is within the profile's step down is marked as such in the directed
// layer (a planner may go and look); one already deeper is blocked like any other lethal cell.
TEST(TraversabilityTest, AnUnseenDropIsMarkedForALookUnlessAlreadyTooDeep) {
  GridMap map =
      MakeTerrain(30, 12, kRes, [](double x, double) { return x < 2.0 ? 0.2 : std::nan(""); });
  Layer& b = map.AddLayer(layers::kGroundBound);
  auto bound_below_rim = [&](float depth_m) {
    for (int ix = 10; ix < 30; ++ix) {
      for (int iy = 0; iy < 12; ++iy) b(ix, iy) = 0.2f - depth_m;
    }
  };
  bound_below_rim(0.06f);  // more than unseen_drop_m (5 cm), less than the 10 cm step down
  ComputeCostLayer(&map, ShippedProfile("pioneer3at"), {});
  EXPECT_EQ(Cost(map, "pioneer3at", 9, 6), layers::kCostLethal);
  EXPECT_EQ(Mask(map, "pioneer3at", 9, 6), layers::kUnseenDrop);
  EXPECT_EQ(Mask(map, "pioneer3at", 8, 6), 0.f);
  ExpectMaskMatchesCost(map, "pioneer3at");
  bound_below_rim(0.14f);  // the rays prove more than the step down already
  ComputeCostLayer(&map, ShippedProfile("pioneer3at"), {});
  EXPECT_EQ(Cost(map, "pioneer3at", 9, 6), layers::kCostLethal);
  EXPECT_EQ(Mask(map, "pioneer3at", 9, 6), layers::kAllHeadingsBlocked);
}

// The cell on the edge itself is often mixed (part rim, part gap) and unknown, its bound barely
// below the rim; the rays show the drop a cell further. The rim looks through the unknown cells
// beyond it (0.4 m) for the lowest bound.
TEST(TraversabilityTest, TheRimSeesTheDropBeyondAMixedEdgeCell) {
  GridMap map =
      MakeTerrain(30, 12, kRes, [](double x, double) { return x < 2.0 ? 0.2 : std::nan(""); });
  Layer& b = map.AddLayer(layers::kGroundBound);
  for (int iy = 0; iy < 12; ++iy) {
    b(10, iy) = 0.18f;                                   // the mixed edge cell
    b(11, iy) = 0.12f;                                   // the drop, a cell on
    for (int ix = 12; ix < 30; ++ix) b(ix, iy) = 0.05f;  // beyond the reach
  }
  ComputeCostLayer(&map, ShippedProfile("pioneer3at"), {});
  EXPECT_EQ(Cost(map, "pioneer3at", 9, 6), layers::kCostLethal);
  // Without the drop a cell on, only the far bound (0.6 m away) shows it: not the rim's.
  for (int iy = 0; iy < 12; ++iy) b(11, iy) = 0.18f;
  ComputeCostLayer(&map, ShippedProfile("pioneer3at"), {});
  EXPECT_LT(Cost(map, "pioneer3at", 9, 6), layers::kCostLethal);
}

// An 8 cm step seen from below: its face's returns spill into the floor cell at its foot,
// which is published unknown (a mixed cell) with the floor's bound. A profile that bridges that
// one cell (max_ditch_width_m >= 0.2 m) judges the crossing as the step between the platform and
// the floor beyond, in each direction; so does one that does not, while no ray passed below the
// floor there (else the rim stands over an unseen drop).
TEST(TraversabilityTest, AProfileThatBridgesTheUnseenFootOfAStepJudgesTheStep) {
  GridMap map = MakeTerrain(30, 12, kRes, [](double x, double) {
    return x < 2.0 ? 0.08 : (x < 2.0 + kRes ? std::nan("") : 0.0);
  });
  Layer& b = map.AddLayer(layers::kGroundBound);
  for (int iy = 0; iy < 12; ++iy) b(10, iy) = 0.005f;  // rays over the foot cell, at floor level
  common::RobotProfile wide = ShippedProfile("pioneer3at");
  wide.name = "wide";
  wide.max_ditch_width_m = 0.3;
  ComputeCostLayer(&map, wide, {});
  ComputeCostLayer(&map, ShippedProfile("pioneer3at"), {});
  // Down 8 cm (within 10) from the rim; up 8 cm (over 3) from the floor: that way only.
  EXPECT_EQ(Mask(map, "wide", 9, 6), 0.f);
  EXPECT_LT(Cost(map, "wide", 9, 6), layers::kCostLethal);
  EXPECT_EQ(Mask(map, "wide", 11, 6), float(1u << 4)) << "bit 4: towards -x";
  ExpectMaskMatchesCost(map, "wide");
  // The same profile allowed 12 cm steps up crosses it both ways.
  wide.max_step_up_m = 0.12;
  ComputeCostLayer(&map, wide, {});
  EXPECT_EQ(Mask(map, "wide", 11, 6), 0.f);
  EXPECT_LT(Cost(map, "wide", 11, 6), layers::kCostLethal);
  // The pioneer3at bridges 0.10 m, but one unseen cell whose rays passed at the floor's level
  // is the foot of the face: the same step, down only.
  EXPECT_EQ(Mask(map, "pioneer3at", 9, 6), 0.f);
  EXPECT_EQ(Mask(map, "pioneer3at", 11, 6), float(1u << 4));
  // A ray 3 cm below the floor there: a gap, not a foot, already deeper than the 10 cm step
  // down from the rim.
  for (int iy = 0; iy < 12; ++iy) b(10, iy) = -0.03f;
  ComputeCostLayer(&map, ShippedProfile("pioneer3at"), {});
  EXPECT_EQ(Mask(map, "pioneer3at", 9, 6), layers::kAllHeadingsBlocked);
  for (int iy = 0; iy < 12; ++iy) b(10, iy) = 0.005f;
  // A 20 cm step is too much down for the wide profile as well: blocked both ways.
  map.at(layers::kElevation).setConstant(0.0f);
  for (int iy = 0; iy < 12; ++iy) {
    for (int ix = 0; ix < 10; ++ix) map.at(layers::kElevation)(ix, iy) = 0.2f;
    map.at(layers::kElevation)(10, iy) = std::nanf("");
  }
  ComputeGeometricLayers(&map, {});
  ComputeCostLayer(&map, wide, {});
  EXPECT_EQ(Mask(map, "wide", 9, 6), layers::kAllHeadingsBlocked);
}

// At range the lidar's rings skip cells of a ramp: one unseen cell between two levels that a
// slope the profile drives could join is no step, though the two levels may differ by more
// than the step limit (Pioneer 3-AT: 3 cm up, 8 deg; a 7 deg ramp rises 4.9 cm over two cells,
// 6.9 cm where the cells beside the skipped one read 1 cm low and high, as samples off their
// centres do). Flat ground on both sides of the same rise is a step.
TEST(TraversabilityTest, AnUnseenCellOnARampIsNoStep) {
  const double grade = std::tan(7.0 * M_PI / 180.0);
  for (const double skipped_x : {2.3, 3.1}) {  // the ramp's first cell past its foot; mid-ramp
    for (const double bias_m : {0.0, 0.01}) {
      GridMap map = MakeTerrain(30, 12, kRes, [&](double x, double) {
        if (std::fabs(x - skipped_x) < kRes / 2) return std::nan("");
        const double h = x < 2.0 ? 0.0 : (x - 2.0) * grade;
        if (std::fabs(x - (skipped_x - kRes)) < kRes / 2) return h - bias_m;
        if (std::fabs(x - (skipped_x + kRes)) < kRes / 2) return h + bias_m;
        return h;
      });
      Layer& b = map.AddLayer(layers::kGroundBound);
      const int ix = static_cast<int>(skipped_x / kRes);
      for (int iy = 0; iy < 12; ++iy) b(ix, iy) = static_cast<float>((skipped_x - 2.0) * grade);
      ComputeCostLayer(&map, ShippedProfile("pioneer3at"), {});
      const std::string where =
          "skipped cell at x " + std::to_string(skipped_x) + ", bias " + std::to_string(bias_m);
      EXPECT_EQ(Mask(map, "pioneer3at", ix - 1, 6), 0.f) << "up the ramp, " << where;
      EXPECT_EQ(Mask(map, "pioneer3at", ix + 1, 6), 0.f) << "down the ramp, " << where;
      EXPECT_LT(Cost(map, "pioneer3at", ix - 1, 6), layers::kCostLethal) << where;
      ExpectMaskMatchesCost(map, "pioneer3at");
    }
  }
  GridMap flat = MakeTerrain(30, 12, kRes, [&](double x, double) {
    return x < 2.2 ? 0.0 : (x < 2.4 ? std::nan("") : 0.069);
  });
  Layer& b = flat.AddLayer(layers::kGroundBound);
  for (int iy = 0; iy < 12; ++iy) b(11, iy) = 0.005f;
  ComputeCostLayer(&flat, ShippedProfile("pioneer3at"), {});
  EXPECT_EQ(Mask(flat, "pioneer3at", 10, 6), 1.f) << "bit 0: not up towards +x";
  EXPECT_EQ(Mask(flat, "pioneer3at", 12, 6), 0.f) << "down is within 10 cm";
}

// The live mapper recomputes windows of a larger map: with DependencyRadiusCells of margin the
// window's values equal the whole-map computation.
TEST(TraversabilityTest, WindowWithMarginMatchesWholeMap) {
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 0.01);
  GridMap map = MakeTerrain(80, 70, kRes, [&](double x, double y) {
    if (x > 6 && x < 6.6) return std::nan("");  // a trench
    double h = 0.1 * std::sin(x) + noise(rng);
    if (y > 8 && y < 9) h += 0.2;  // a block
    return h;
  });
  Layer& b = map.AddLayer(layers::kGroundBound);
  const Layer& h = map.at(layers::kElevation);
  for (int iy = 0; iy < 70; ++iy) {
    for (int ix = 0; ix < 80; ++ix) {
      if (std::isnan(h(ix, iy))) b(ix, iy) = -0.3f;
    }
  }
  const common::RobotProfile pioneer = ShippedProfile("pioneer3at");
  const TraversabilityParams params;
  GridMap whole = map;
  ComputeGeometricLayers(&whole, params);
  ComputeCostLayer(&whole, pioneer, params, RobotContext{}, CellRect::All(whole));

  const CellRect rect{25, 30, 45, 50};
  const int margin = DependencyRadiusCells(params, kRes);
  common::GridGeometry wg = map.geometry();
  wg.size_x = (rect.x1 - rect.x0) + 2 * margin;
  wg.size_y = (rect.y1 - rect.y0) + 2 * margin;
  wg.origin.x_m += (rect.x0 - margin) * kRes;
  wg.origin.y_m += (rect.y0 - margin) * kRes;
  GridMap window(wg);
  for (const char* name : {layers::kElevation, layers::kGroundBound}) {
    window.AddLayer(name) =
        map.at(name).block(rect.x0 - margin, rect.y0 - margin, wg.size_x, wg.size_y);
  }
  const CellRect inner{margin, margin, margin + rect.x1 - rect.x0, margin + rect.y1 - rect.y0};
  ComputeGeometricLayers(&window, params,
                         CellRect{inner.x0 - 1, inner.y0 - 1, inner.x1 + 1, inner.y1 + 1});
  ComputeCostLayer(&window, pioneer, params, RobotContext{}, inner);
  int lethal = 0, ditch = 0;
  for (int y = rect.y0; y < rect.y1; ++y) {
    for (int x = rect.x0; x < rect.x1; ++x) {
      for (const std::string& name : {std::string(layers::kSlope), std::string(layers::kDitchDepth),
                                      layers::CostLayer("pioneer3at")}) {
        const float a = whole.at(name)(x, y);
        const float w = window.at(name)(x - rect.x0 + margin, y - rect.y0 + margin);
        EXPECT_TRUE((std::isnan(a) && std::isnan(w)) || a == w) << name << " " << x << "," << y;
      }
      lethal += whole.at(layers::CostLayer("pioneer3at"))(x, y) == layers::kCostLethal;
      ditch += !std::isnan(whole.at(layers::kDitchDepth)(x, y));
    }
  }
  EXPECT_GT(lethal, 0);  // the window holds something worth comparing
  EXPECT_GT(ditch, 0);
}

// ---- The directed layer (directed/<profile>, common/layers.h) ----

// Unit vector of heading bin b (b * 45 deg counter-clockwise from +x).
common::Vector2 HeadingOf(int b) { return {std::cos(b * M_PI / 4), std::sin(b * M_PI / 4)}; }

// A step of `rise_m` through the centre of a 24 x 24 grid whose high side lies towards heading
// bin k (for odd k the edge is a staircase of cells).
GridMap StepTowardsBin(int k, double rise_m) {
  const common::Vector2 u = HeadingOf(k), centre(2.4, 2.4);
  return MakeTerrain(24, 24, kRes, [=](double x, double y) {
    return (common::Vector2(x, y) - centre).dot(u) >= -1e-9 ? rise_m : 0.0;
  });
}

// Every interior cell: the mask is NaN exactly where the cost is, non-zero exactly where the
// cost is lethal, and a whole number in [0, 255] or an unseen drop's mark.
void ExpectMaskMatchesCost(const GridMap& map, const std::string& profile) {
  ForInterior(map, [&](int ix, int iy) {
    const float c = Cost(map, profile, ix, iy), m = Mask(map, profile, ix, iy);
    ASSERT_EQ(std::isnan(c), std::isnan(m)) << ix << "," << iy;
    if (std::isnan(c)) return;
    ASSERT_EQ(m != 0.f, c >= layers::kCostLethal) << ix << "," << iy << " cost " << c;
    ASSERT_EQ(m, std::round(m));
    ASSERT_TRUE((m >= 0.f && m <= 255.f) || m == layers::kUnseenDrop);
  });
}

// An 8 cm step for the Pioneer 3-AT (up 3 cm, down 10 cm) seen from each of the 8 headings: the
// cells at its foot refuse exactly the headings that climb it, the cells above it refuse
// nothing, and no cell refuses a heading that runs along the edge or down it.
TEST(TraversabilityTest, AOneWayStepSeenFromEachOfEightHeadings) {
  const common::RobotProfile pioneer = ShippedProfile("pioneer3at");
  for (int k = 0; k < 8; ++k) {
    SCOPED_TRACE("high side towards bin " + std::to_string(k));
    GridMap map = StepTowardsBin(k, 0.08);
    ComputeCostLayer(&map, pioneer, {});
    ExpectMaskMatchesCost(map, "pioneer3at");
    const common::Vector2 u = HeadingOf(k);
    int one_way = 0;
    ForInterior(map, [&](int ix, int iy) {
      const float m = Mask(map, "pioneer3at", ix, iy);
      if (m == 0.f) return;
      // Cells on both sides of the edge: the foot for the step, and (the slope fitted across
      // the edge exceeds 8 deg) the rim for the slope, uphill only.
      ASSERT_NE(m, layers::kAllHeadingsBlocked) << ix << "," << iy;
      ++one_way;
      const unsigned bits = static_cast<unsigned>(m);
      for (int b = 0; b < 8; ++b) {
        if (bits & (1u << b)) {
          EXPECT_GT(HeadingOf(b).dot(u), 0.1) << "refuses bin " << b << " at " << ix << "," << iy;
        }
      }
    });
    // The whole foot of the edge, inside the 2-cell interior margin, is one-way.
    EXPECT_GE(one_way, k % 2 == 0 ? 18 : 17);
  }
}

// Steps alone (slopes unlimited): the foot of an axis step refuses its climbing heading alone,
// the rim nothing.
TEST(TraversabilityTest, TheDirectedBitsOfAnAxisStepAreItsClimbingHeadingAlone) {
  common::RobotProfile pioneer = LenientProfile("pioneer3at");
  pioneer.max_step_up_m = 0.03;
  pioneer.max_step_down_m = 0.10;
  for (int k = 0; k < 8; k += 2) {
    GridMap map = StepTowardsBin(k, 0.08);
    ComputeCostLayer(&map, pioneer, {});
    // The cell below the edge on the line through the centre, and the cell above it.
    const common::Vector2 u = HeadingOf(k);
    const int low_x = u.x() < -0.5 ? 12 : 11, low_y = u.y() < -0.5 ? 12 : 11;
    EXPECT_EQ(map.at(layers::kElevation)(low_x, low_y), 0.f) << "bin " << k;
    EXPECT_EQ(Mask(map, "pioneer3at", low_x, low_y), static_cast<float>(1u << k)) << "bin " << k;
    const int high_x = low_x + static_cast<int>(std::lround(u.x()));
    const int high_y = low_y + static_cast<int>(std::lround(u.y()));
    EXPECT_EQ(Mask(map, "pioneer3at", high_x, high_y), 0.f) << "bin " << k;
    EXPECT_LT(Cost(map, "pioneer3at", high_x, high_y), layers::kCostLethal);
  }
}

// A 12 cm step is over the Pioneer's 10 cm step down as well: crossable neither way, both sides
// block every heading. So does an 8 cm step for a profile stepping 3 cm either way.
TEST(TraversabilityTest, AStepCrossableNeitherWayBlocksEveryHeading) {
  const common::RobotProfile pioneer = ShippedProfile("pioneer3at");
  GridMap twelve = StepTowardsBin(0, 0.12);
  ComputeCostLayer(&twelve, pioneer, {});
  ExpectMaskMatchesCost(twelve, "pioneer3at");
  common::RobotProfile even = LenientProfile("even");
  even.max_step_up_m = 0.03;
  even.max_step_down_m = 0.03;
  GridMap eight = StepTowardsBin(0, 0.08);
  ComputeCostLayer(&eight, even, {});
  for (int iy = 3; iy < 21; ++iy) {
    EXPECT_EQ(Mask(twelve, "pioneer3at", 11, iy), layers::kAllHeadingsBlocked);
    EXPECT_EQ(Mask(twelve, "pioneer3at", 12, iy), layers::kAllHeadingsBlocked);
    EXPECT_EQ(Mask(eight, "even", 11, iy), layers::kAllHeadingsBlocked);
    EXPECT_EQ(Mask(eight, "even", 12, iy), layers::kAllHeadingsBlocked);
  }
}

// The Pioneer 3-AT has no downhill limit (seed 000): a 10 deg slope refuses the headings that
// climb it only; over max_one_way_slope_rad (20 deg) it blocks every heading. The rover (12 deg
// up, 20 deg down) descends 15 deg but not 22.
TEST(TraversabilityTest, ASlopeBetweenTheUphillAndDownhillLimitsIsOneWay) {
  const common::RobotProfile pioneer = ShippedProfile("pioneer3at");
  const common::RobotProfile rover = ShippedProfile("rover");
  const unsigned climbing_x = (1u << 0) | (1u << 1) | (1u << 7);  // headings with +x component
  for (double azimuth_deg : {0.0, 180.0}) {
    GridMap ten = MakeTerrain(16, 16, kRes, Plane(10 * kDeg, azimuth_deg * kDeg));
    ComputeCostLayer(&ten, pioneer, {});
    ExpectMaskMatchesCost(ten, "pioneer3at");
    const unsigned expect = azimuth_deg == 0.0 ? climbing_x : (1u << 3) | (1u << 4) | (1u << 5);
    ForInterior(ten, [&](int ix, int iy) {
      ASSERT_EQ(Mask(ten, "pioneer3at", ix, iy), static_cast<float>(expect)) << ix << "," << iy;
    });
  }
  GridMap steep = MakeTerrain(16, 16, kRes, Plane(22 * kDeg));
  ComputeCostLayer(&steep, pioneer, {});
  ComputeCostLayer(&steep, rover, {});
  GridMap fifteen = MakeTerrain(16, 16, kRes, Plane(15 * kDeg));
  TraversabilityParams steps_off;  // 15 deg rises 5.4 cm per cell: judge the slope alone
  common::RobotProfile rover_slopes = rover;
  rover_slopes.max_step_up_m = 1.0;
  rover_slopes.max_step_down_m = 1.0;
  ComputeCostLayer(&fifteen, rover_slopes, steps_off);
  ForInterior(steep, [&](int ix, int iy) {
    ASSERT_EQ(Mask(steep, "pioneer3at", ix, iy), layers::kAllHeadingsBlocked);
    ASSERT_EQ(Mask(steep, "rover", ix, iy), layers::kAllHeadingsBlocked);
    ASSERT_EQ(Mask(fifteen, "rover", ix, iy), static_cast<float>(climbing_x));
  });
}

// Unknown cells have no mask (NaN); blind-zone cells are free, so nothing is refused there; an
// unknown cell read as lethal blocks every heading.
TEST(TraversabilityTest, TheDirectedLayerFollowsTheCostOfUnknownCells) {
  GridMap map = MakeTerrain(30, 30, kRes, [](double x, double y) {
    return (std::fabs(x - 3.0) < 0.8 && std::fabs(y - 3.0) < 0.8) ? std::nan("") : 0.0;
  });
  RobotContext robot;
  robot.xy_m = common::Vector2(3.0, 3.0);
  ComputeGeometricLayers(&map, {});
  ComputeCostLayer(&map, LenientProfile(), {}, robot, CellRect::All(map));
  ExpectMaskMatchesCost(map, "test");
  EXPECT_EQ(Cost(map, "test", 14, 14), layers::kCostFree);  // inside the blind zone
  EXPECT_EQ(Mask(map, "test", 14, 14), 0.f);
  EXPECT_TRUE(std::isnan(Mask(map, "test", 11, 11)));  // unknown, outside it
  TraversabilityParams lethal_unknown;
  lethal_unknown.unknown_is_lethal = true;
  ComputeCostLayer(&map, LenientProfile(), lethal_unknown, robot, CellRect::All(map));
  EXPECT_EQ(Mask(map, "test", 11, 11), layers::kAllHeadingsBlocked);
  EXPECT_EQ(Mask(map, "test", 0, 5), layers::kAllHeadingsBlocked);  // the border
}

TEST(TraversabilityTest, BadInputThrows) {
  common::GridGeometry g;
  g.size_x = 4;
  g.size_y = 4;
  GridMap no_elevation(g);
  EXPECT_THROW(ComputeGeometricLayers(&no_elevation, {}), std::invalid_argument);
  EXPECT_THROW(ComputeCostLayer(&no_elevation, LenientProfile(), {}), std::invalid_argument);
  GridMap map = MakeTerrain(4, 4, kRes, Plane(0.0));
  TraversabilityParams bad;
  bad.graded_cost_max = 100;
  EXPECT_THROW(ComputeGeometricLayers(&map, bad), std::invalid_argument);
  common::RobotProfile nameless = LenientProfile();
  nameless.name = "";
  EXPECT_THROW(ComputeCostLayer(&map, nameless, {}), std::invalid_argument);
}

}  // namespace
}  // namespace cairn::mapping
