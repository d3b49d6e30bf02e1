#include "services/mapping/terrain_map.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <random>

#include <gtest/gtest.h>

#include "common/layers.h"
#include "services/mapping/derive.h"
#include "services/mapping/elevation_filter.h"
#include "tests/unit/services/mapping/synthetic_scan.h"
#include "tests/unit/services/mapping/terrain_fixtures.h"

namespace cairn::mapping {
namespace {

using common::GridMap;
using testing::kDeg;
using testing::SensorAt;
using testing::ShippedProfile;
using testing::SyntheticLidar;
using testing::SyntheticRevolution;

TerrainMapParams Params() {
  TerrainMapParams p;
  return p;
}

TEST(TerrainMapTest, FlatGroundFromRevolutions) {
  TerrainMap map(Params());
  EXPECT_TRUE(map.empty());
  const common::LidarSlice scan =
      SyntheticRevolution(SensorAt(1.0, 2.0, 0.5), [](double, double) { return 0.0; }, {});
  const IntegrateStats s = map.Integrate(scan.points, scan.sensor_pose, 0, 12.5);
  EXPECT_EQ(s.points, static_cast<int64_t>(scan.points.size()));
  EXPECT_GT(s.used, 1000);
  EXPECT_EQ(s.nonfinite, 0);
  EXPECT_FALSE(map.empty());
  const GridMap out = map.Export(TerrainMap::BaseLayers());
  const auto cell = out.IndexOf({3.05, 2.05});
  ASSERT_TRUE(cell.has_value());
  EXPECT_NEAR(out.at(layers::kElevation)(cell->ix, cell->iy), 0.0, 1e-5);
  EXPECT_GE(out.at(layers::kObservationCount)(cell->ix, cell->iy), 1.f);
  EXPECT_FLOAT_EQ(out.at(layers::kLastSeen)(cell->ix, cell->iy), 12.5f);
  EXPECT_GT(out.at(layers::kElevationVariance)(cell->ix, cell->iy), 0.f);
  // Export is tile-aligned with an empty tile of margin: origin on a 20 m grid.
  EXPECT_DOUBLE_EQ(std::fmod(out.geometry().origin.x_m, 20.0), 0.0);
  EXPECT_EQ(out.size_x() % 100, 0);
}

// A robot at rest at `robot_xy`: `revolutions` revolutions of `lidar` from `sensor` with
// Gaussian range noise of `sigma_m` along each beam (seeded), each integrated and derived.
void IntegrateNoisyRevolutionsAtRest(TerrainMap* map, const common::Pose3& sensor,
                                     const common::Vector2& robot_xy,
                                     const std::function<double(double, double)>& ground,
                                     const SyntheticLidar& lidar, int revolutions, double sigma_m,
                                     uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, sigma_m);
  for (int rev = 0; rev < revolutions; ++rev) {
    common::LidarSlice scan = SyntheticRevolution(sensor, ground, lidar, rev);
    for (auto& point : scan.points) {
      common::Vector3 v(point.x_m, point.y_m, point.z_m);
      v *= 1.0 + noise(rng) / v.norm();
      point.x_m = static_cast<float>(v.x());
      point.y_m = static_cast<float>(v.y());
      point.z_m = static_cast<float>(v.z());
    }
    map->Integrate(scan.points, scan.sensor_pose, rev + 1, rev * 0.1);
    RobotContext robot;
    robot.xy_m = robot_xy;
    map->UpdateDerived(robot);
  }
}

// A robot at rest looks at a 10 deg ramp with a noisy lidar; returns the RMS error of the
// published heights against the ramp's true height at the cell centres, over the ramp's
// well-observed inner cells (the map built with `params`).
double RampErrorAtCellCentres(const TerrainMapParams& params) {
  const double tan10 = std::tan(10 * kDeg);
  auto ground = [&](double x, double) { return std::clamp(x - 2.0, 0.0, 2.0) * tan10; };
  TerrainMap map(params);
  SyntheticLidar lidar;
  lidar.rings = 16;
  lidar.azimuths = 240;
  lidar.max_range_m = 6.0;
  IntegrateNoisyRevolutionsAtRest(&map, SensorAt(0.3, 0.05, 0.5), common::Vector2(0.3, 0.05),
                                  ground, lidar, 25, 0.018, 11);
  const GridMap out = map.Export({layers::kElevation, layers::kObservationCount});
  double sum_sq = 0.0;
  int cells = 0;
  for (double x = 2.3; x < 3.7; x += 0.2) {
    for (double y = -0.5; y <= 0.5; y += 0.2) {
      const auto c = out.IndexOf({x, y});
      if (!c) continue;
      const float h = out.at(layers::kElevation)(c->ix, c->iy);
      // Cells only the noise of a neighbouring ring line reached hold a point or two.
      if (std::isnan(h) || out.at(layers::kObservationCount)(c->ix, c->iy) < 20) continue;
      const common::Vector2 centre = out.geometry().CenterOf(*c);
      const double error = h - ground(centre.x(), centre.y());
      sum_sq += error * error;
      ++cells;
    }
  }
  EXPECT_GT(cells, 20) << "too little of the ramp seen";
  return std::sqrt(sum_sq / std::max(1, cells));
}

// A cell on a ramp holds points of several true heights, sampled along a few ring lines off
// its centre. The filter widens its gate by the slope's rise across the cell and carries the
// height to the centre, so the ramp reads even. Upstream (gate on the point noise alone, height
// where the points lay) is about three times further off (3.4 mm RMS against 9.1 mm here).
TEST(TerrainMapTest, ARampSeenFromRestReadsEvenAtTheCellCentres) {
  TerrainMapParams params;
  params.filter.min_variance_m2 = 1e-7;  // as config/mapping/mapper.yaml
  params.filter.increase_height_alpha = 0.5;
  const double ours = RampErrorAtCellCentres(params);
  params.filter.max_spread_slope_rad = 0.0;
  const double upstream = RampErrorAtCellCentres(params);
  std::printf("ramp height error at the cell centres, RMS: %.4f m (upstream filter %.4f m)\n", ours,
              upstream);
  EXPECT_LT(ours, 0.005);
  EXPECT_GT(upstream, 0.007);
}

// The carry to the cell centre follows a plane fitted over 0.3 m, which across an 8 cm face is a
// false ramp (about 20 deg here). Cells on either side of the face whose points lie near it must
// not be carried along that plane: the floor cell would sink and the top cell rise by the plane's
// rise over the points' offset (2 cm here), and a face seen at a grazing angle, its points off
// the cell centres, smeared into sub-limit steps over several cells. On an even ramp the carry
// stands (ARampSeenFromRestReadsEvenAtTheCellCentres).
TEST(TerrainMapTest, CellsBesideAStepFaceAreNotCarriedAlongTheFaceFit) {
  TerrainMapParams params = Params();
  params.filter.min_variance_m2 = 1e-7;  // as config/mapping/mapper.yaml
  TerrainMap map(params);
  auto ground = [](double x) { return x >= 2.6 ? 0.08 : 0.0; };  // the face on a cell border
  const common::Pose3 sensor = SensorAt(0.0, 0.0, 1.0);
  auto point_at = [&](double x, double y) {
    common::LidarPoint p;
    p.x_m = static_cast<float>(x);
    p.y_m = static_cast<float>(y);
    p.z_m = static_cast<float>(ground(x) - 1.0);
    return p;
  };
  // Every cell of x 1.0..4.0, y -1..1 at its centre, then derived (the normals).
  std::vector<common::LidarPoint> centres;
  for (double x = 1.1; x < 4.0; x += 0.2) {
    for (double y = -0.9; y < 1.0; y += 0.2) centres.push_back(point_at(x, y));
  }
  map.Integrate(centres, sensor, 1, 0.1);
  map.UpdateDerived();
  // Then points near the face only: 8 cm off the centres of the cells on either side of it.
  std::vector<common::LidarPoint> near_face;
  for (int k = 0; k < 20; ++k) {
    for (double y = -0.5; y < 0.6; y += 0.2) {
      near_face.push_back(point_at(2.58, y));
      near_face.push_back(point_at(2.62, y));
    }
  }
  map.Integrate(near_face, sensor, 2, 0.2);
  const GridMap out = map.Export({layers::kElevation, layers::kSlope});
  for (double y = -0.5; y < 0.6; y += 0.2) {
    const auto foot = out.IndexOf({2.5, y});
    const auto top = out.IndexOf({2.7, y});
    ASSERT_TRUE(foot && top);
    EXPECT_GT(out.at(layers::kSlope)(foot->ix, foot->iy), 10 * kDeg) << "the fit across the face";
    EXPECT_NEAR(out.at(layers::kElevation)(foot->ix, foot->iy), 0.0, 0.005) << "y " << y;
    EXPECT_NEAR(out.at(layers::kElevation)(top->ix, top->iy), 0.08, 0.005) << "y " << y;
  }
}

// A hillside seen once, before any normal existed (the first revolution, or cells a ring line
// crossed and never again), holds the heights of where its points lay: along a ring's contour,
// every cell off its centre the same way, so the ramp reads as terraces. The next update commits
// such cells again with the normals derived since, carried to their centres like every cell
// seen later.
TEST(TerrainMapTest, CellsSeenBeforeTheirNormalAreCarriedOnceItIsDerived) {
  TerrainMapParams params = Params();
  params.filter.min_variance_m2 = 1e-7;  // as config/mapping/mapper.yaml
  TerrainMap map(params);
  const double t = std::tan(10 * kDeg);
  const common::Pose3 sensor = SensorAt(0.0, 0.0, 1.0);
  // One point per cell of x 1.0..4.0, y -1..1, 8 cm uphill of its centre (1.4 cm higher).
  std::vector<common::LidarPoint> points;
  for (double x = 1.1; x < 4.0; x += 0.2) {
    for (double y = -0.9; y < 1.0; y += 0.2) {
      common::LidarPoint p;
      p.x_m = static_cast<float>(x + 0.08);
      p.y_m = static_cast<float>(y);
      p.z_m = static_cast<float>(t * (x + 0.08) - 1.0);
      points.push_back(p);
    }
  }
  map.Integrate(points, sensor, 1, 0.1);
  auto worst_error = [&] {
    const GridMap out = map.Export({layers::kElevation});
    double worst = 0.0;
    int cells = 0;
    for (double x = 1.7; x < 3.4; x += 0.2) {  // inner cells: their normals interpolate
      for (double y = -0.5; y < 0.6; y += 0.2) {
        const auto c = out.IndexOf({x, y});
        EXPECT_TRUE(c.has_value());
        if (!c) continue;
        const double h = out.at(layers::kElevation)(c->ix, c->iy);
        worst = std::max(worst, std::fabs(h - t * out.geometry().CenterOf(*c).x()));
        ++cells;
      }
    }
    EXPECT_GT(cells, 40);
    return worst;
  };
  map.UpdateDerived();
  EXPECT_GT(worst_error(), 0.012) << "committed before any normal: where the points lay";
  map.UpdateDerived();  // nothing new seen
  EXPECT_LT(worst_error(), 0.003) << "committed again with the derived normals";
}

// A robot standing on flat floor sees a ring of it around the blind zone under it, the cells
// at the ring's inner rim only from one side. Their heights must not lean on a normal fitted over
// that one side: the carry to the cell centre would grow, revolution after revolution, into a
// false step at the robot's nose that walls it in.
TEST(TerrainMapTest, TheRimOfTheBlindZoneAroundAStandingRobotStaysFlat) {
  TerrainMapParams params = Params();
  params.filter.min_variance_m2 = 1e-7;  // as config/mapping/mapper.yaml
  params.filter.increase_height_alpha = 0.5;
  params.self_filter_radius_m = 0.5;
  TerrainMap map(params);
  map.AddProfile(ShippedProfile("pioneer3at"));
  auto ground = [](double, double) { return 0.0; };
  SyntheticLidar lidar;  // an HDL-32E at the P3-AT's lidar height
  lidar.rings = 32;
  lidar.azimuths = 720;
  lidar.max_range_m = 8.0;
  const common::Vector2 robot_xy(4.05, 8.05);
  IntegrateNoisyRevolutionsAtRest(&map, SensorAt(robot_xy.x() + 0.12, robot_xy.y(), 0.45), robot_xy,
                                  ground, lidar, 100, 0.02, 5);
  const GridMap out = map.Export({layers::kElevation, layers::CostLayer("pioneer3at")});
  int rim = 0, lethal = 0;
  double worst = 0.0;
  for (int iy = 0; iy < out.size_y(); ++iy) {
    for (int ix = 0; ix < out.size_x(); ++ix) {
      const common::Vector2 c = out.CenterOf({ix, iy});
      const double d = (c - robot_xy).norm();
      if (d > 1.5) continue;
      const float h = out.at(layers::kElevation)(ix, iy);
      if (std::isnan(h)) continue;
      worst = std::max(worst, std::fabs(double(h)));
      rim += d < 1.0;
      lethal += out.at(layers::CostLayer("pioneer3at"))(ix, iy) >= layers::kCostLethal;
    }
  }
  EXPECT_GT(rim, 20) << "too little of the rim seen";
  // The worst cell is one the noise of a few points sets off (2.7 cm here without any carry);
  // carried along normals fitted over one side, the rim reads 3.7 cm.
  EXPECT_LT(worst, 0.03) << "a cell within 1.5 m reads " << worst << " m off the floor";
  EXPECT_EQ(lethal, 0);
}

TEST(TerrainMapTest, GrowsInTilesOverASquareKilometre) {
  TerrainMap map(Params());
  // One point near each corner of a 1 km square centred on the origin (negative coordinates
  // included): four tiles, not a dense kilometre.
  for (double x : {-499.9, 499.9}) {
    for (double y : {-499.9, 499.9}) {
      common::LidarPoint p;
      p.x_m = 2.0f;
      map.Integrate({p}, SensorAt(x - 2.0, y, 0.0), 0, 0.0);
    }
  }
  EXPECT_EQ(map.Tiles().size(), 4u);
  EXPECT_LT(map.memory_bytes(), 4u * 100 * 100 * 64);
  const common::GridGeometry b = map.Bounds();
  EXPECT_GE(b.length_x_m(), 1000.0);
  EXPECT_GE(b.length_y_m(), 1000.0);
  EXPECT_LE(b.origin.x_m, -500.0);
  // A window at the far corner holds the point, in the right cell (floor, not truncation).
  common::GridGeometry w;
  w.resolution_m = 0.2;
  w.size_x = w.size_y = 10;
  w.origin = {-501.0, -501.0, 0.0};
  const GridMap win = map.Export({layers::kElevation}, w);
  EXPECT_NEAR(*win.ValueAt(layers::kElevation, {-499.9, -499.9}), 0.0, 1e-6);
  EXPECT_EQ(win.IndexOf({-499.9, -499.9})->ix, 5);
  EXPECT_EQ(map.known_cells(), 4);
}

TEST(TerrainMapTest, BadPointsAreCountedAndSkipped) {
  TerrainMap map(Params());
  std::vector<common::LidarPoint> pts(5);
  pts[0].x_m = NAN;
  pts[1].y_m = std::numeric_limits<float>::infinity();
  pts[2].x_m = 100.0f;  // beyond max range
  pts[3].x_m = 0.1f;    // the robot itself
  pts[4].x_m = 3.0f;
  pts[4].z_m = 2.0f;  // an overhang 2 m above the sensor
  const IntegrateStats s = map.Integrate(pts, SensorAt(0, 0, 0.5), 0, 0.0);
  EXPECT_EQ(s.nonfinite, 2);
  EXPECT_EQ(s.out_of_range, 2);
  EXPECT_EQ(s.overhang, 1);
  EXPECT_EQ(s.used, 0);
  common::Pose3 bad = SensorAt(0, 0, 0.5);
  bad.position_m.x() = NAN;
  pts[4].z_m = -0.5f;
  EXPECT_EQ(map.Integrate(pts, bad, 0, 0.0).nonfinite, 5);
  EXPECT_TRUE(map.empty());
}

// The ground bound: rays looking into a trench record how low they went over cells they never
// returned from; the cost layer then treats the trench as a ditch.
TEST(TerrainMapTest, TrenchSeenFromTheRimIsADitch) {
  TerrainMapParams p = Params();
  TerrainMap map(p);
  map.AddProfile(ShippedProfile("pioneer3at"));
  map.AddProfile(ShippedProfile("rover"));
  // A trench 0.6 m wide and 0.5 m deep across x in [3.0, 3.6).
  auto ground = [](double x, double) { return (x >= 3.0 && x < 3.6) ? -0.5 : 0.0; };
  SyntheticLidar lidar;
  lidar.rings = 32;
  lidar.azimuths = 720;
  for (int k = 0; k < 3; ++k) {
    const common::LidarSlice scan =
        SyntheticRevolution(SensorAt(1.4 + 0.05 * k, 0.1, 0.33), ground, lidar, k);
    map.Integrate(scan.points, scan.sensor_pose, k, k * 0.1);
  }
  RobotContext robot;
  robot.xy_m = common::Vector2(1.5, 0.1);
  map.UpdateDerived(robot);
  const GridMap out = map.Export({layers::kElevation, layers::kGroundBound, layers::kDitchDepth,
                                  layers::kDitchWidth, layers::CostLayer("pioneer3at"),
                                  layers::CostLayer("rover")});
  // Some trench cells are unseen, but the rays went below the rims there.
  int ditch = 0, lethal_both = 0;
  for (double x = 3.1; x < 3.6; x += 0.2) {
    const auto c = out.IndexOf({x, 0.1});
    ASSERT_TRUE(c.has_value());
    if (!std::isnan(out.at(layers::kDitchDepth)(c->ix, c->iy))) ++ditch;
    lethal_both += out.at(layers::CostLayer("pioneer3at"))(c->ix, c->iy) == layers::kCostLethal &&
                   out.at(layers::CostLayer("rover"))(c->ix, c->iy) == layers::kCostLethal;
  }
  EXPECT_GE(ditch, 2);
  EXPECT_GE(lethal_both, 2);
  // The registry holds the ditch in front of the robot: the far wall face fills the trench's
  // last cell, so the open gap measures 0.4 to 0.6 m; neither profile crosses it.
  const common::ObstacleRegistry registry = map.BuildRegistry();
  const common::Obstacle* front = nullptr;
  for (const auto& o : registry.obstacles) {
    if (o.kind == common::ObstacleKind::kDitch && std::fabs(o.centroid_m.y() - 0.1) < 1.0)
      front = &o;
  }
  ASSERT_NE(front, nullptr);
  EXPECT_GE(front->width_m, 0.35);
  EXPECT_LE(front->width_m, 0.65);
  EXPECT_NEAR(front->centroid_m.x(), 3.3, 0.2);
  // Along the trench, its far ends are seen only in the column the far wall stands in; a cell
  // there is no rim for its neighbours along the wall (rays crossed it as low as them).
  EXPECT_GT(front->length_m, 2.0);
  EXPECT_FALSE(front->VerdictFor("pioneer3at")->crossable);
  EXPECT_FALSE(front->VerdictFor("rover")->crossable);
  // Nothing else is listed close to the robot's side of the trench.
  for (const auto& o : registry.obstacles) {
    if (&o == front) continue;
    EXPECT_FALSE(o.centroid_m.x() < 3.0 && std::fabs(o.centroid_m.y()) < 2.0)
        << common::ObstacleKindName(o.kind) << " at " << o.centroid_m.transpose();
  }
}

// Live derived layers equal a whole-map derivation of the exported base layers: what the map
// store re-derives for the same profile is what the robot used.
TEST(TerrainMapTest, LiveDerivedLayersEqualDerivingTheExport) {
  TerrainMap map(Params());
  const common::RobotProfile pioneer = ShippedProfile("pioneer3at");
  map.AddProfile(pioneer);
  const double t = std::tan(10 * kDeg);
  auto ground = [t](double x, double y) {
    if (x >= 6.0 && x < 6.6) return -0.4;               // trench
    if (y > 3.0 && x > 2.0 && x < 3.0) return 0.2;      // block
    return x < 8.0 ? 0.0 : std::min(3.0, x - 8.0) * t;  // ramp
  };
  SyntheticLidar lidar;
  lidar.rings = 24;
  lidar.azimuths = 540;
  for (int k = 0; k < 12; ++k) {
    const double x = 0.5 + 0.7 * k;
    const common::LidarSlice scan =
        SyntheticRevolution(SensorAt(x, 1.0, 0.4 + ground(x, 1.0)), ground, lidar, k);
    map.Integrate(scan.points, scan.sensor_pose, k, 0.1 * k);
    RobotContext robot;
    robot.xy_m = common::Vector2(x, 1.0);
    map.UpdateDerived(robot);
  }
  // The final robot position decides the blind zone: derive with the same context.
  const GridMap base =
      map.Export({layers::kElevation, layers::kElevationVariance, layers::kGroundBound});
  GridMap derived = base;
  ComputeGeometricLayers(&derived, map.params().traversability);
  RobotContext robot;
  robot.xy_m = common::Vector2(0.5 + 0.7 * 11, 1.0);
  ComputeCostLayer(&derived, pioneer, map.params().traversability, robot, CellRect::All(derived));
  const GridMap live =
      map.Export({layers::kSlope, layers::kStepMax, layers::kRoughness, layers::kDitchDepth,
                  layers::kDitchWidth, layers::CostLayer("pioneer3at")});
  int64_t compared = 0, lethal = 0;
  for (const auto& name : live.layer_names()) {
    const common::Layer& a = live.at(name);
    const common::Layer& b = derived.at(name);
    for (int64_t i = 0; i < a.size(); ++i) {
      const float va = a.data()[i], vb = b.data()[i];
      ASSERT_TRUE((std::isnan(va) && std::isnan(vb)) || va == vb)
          << name << " cell " << i % a.rows() << "," << i / a.rows() << ": " << va << " vs " << vb;
      compared += !std::isnan(va);
      if (name == layers::CostLayer("pioneer3at")) lethal += va == layers::kCostLethal;
    }
  }
  EXPECT_GT(compared, 5000);
  EXPECT_GT(lethal, 50);
  // The registry too.
  const common::ObstacleRegistry live_registry = map.BuildRegistry();
  const DerivedLayers stored = DeriveProfileLayers(base, pioneer);
  ASSERT_EQ(live_registry.obstacles.size(), stored.registry.obstacles.size());
  for (size_t k = 0; k < live_registry.obstacles.size(); ++k) {
    EXPECT_EQ(live_registry.obstacles[k].kind, stored.registry.obstacles[k].kind);
    EXPECT_EQ(live_registry.obstacles[k].num_cells, stored.registry.obstacles[k].num_cells);
  }
}

TEST(TerrainMapTest, ProfilesComeAndGo) {
  TerrainMap map(Params());
  const common::LidarSlice scan =
      SyntheticRevolution(SensorAt(0, 0, 0.5), [](double, double) { return 0.0; }, {});
  map.Integrate(scan.points, scan.sensor_pose, 0, 0.0);
  map.UpdateDerived({});
  map.AddProfile(ShippedProfile("rover"));
  const GridMap out = map.Export({layers::CostLayer("rover")});
  EXPECT_EQ(*out.ValueAt(layers::CostLayer("rover"), {3.0, 0.1}), layers::kCostFree);
  EXPECT_TRUE(map.RemoveProfile("rover"));
  EXPECT_FALSE(map.RemoveProfile("rover"));
  EXPECT_THROW(map.Export({layers::CostLayer("rover")}), std::invalid_argument);
  common::RobotProfile bad = ShippedProfile("rover");
  bad.max_step_up_m = -1;
  EXPECT_THROW(map.AddProfile(bad), std::invalid_argument);
}

}  // namespace
}  // namespace cairn::mapping
