#include "services/mapping/occupancy_band.h"

#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "services/mapping/occupancy_grid.h"

namespace cairn::mapping {
namespace {

constexpr double kSensorZ = 1.0;  // sensor 1 m above the ground (z = 0)

// Points given in world coordinates for a sensor at (sx, sy, 1) with identity orientation.
class BandScene {
 public:
  explicit BandScene(double sx = 0.0, double sy = 0.0) : sx_(sx), sy_(sy) {}
  void Add(double azimuth_deg, double range_m, double z_m) {
    const double a = azimuth_deg * M_PI / 180.0;
    points_.push_back({static_cast<float>(range_m * std::cos(a)),
                       static_cast<float>(range_m * std::sin(a)),
                       static_cast<float>(z_m - kSensorZ), 0.f, 0});
  }
  void AddRaw(common::LidarPoint p) { points_.push_back(p); }
  common::LidarSlice Slice() const {
    common::LidarSlice slice;
    slice.sensor_pose.position_m = {sx_, sy_, kSensorZ};
    slice.points = points_;
    return slice;
  }

 private:
  double sx_, sy_;
  std::vector<common::LidarPoint> points_;
};

// Floor up to 4.5 m then a wall at 5 m ahead (+x); a 10 deg ramp to the left (+y); floor and
// a ceiling behind (-x); a 0.6 m box at 3 m to the right (-y).
common::LidarRevolution TestRevolution() {
  BandScene scene;
  for (double r = 1.0; r <= 4.51; r += 0.5) scene.Add(0.0, r, 0.0);
  for (double z = 0.05; z <= 2.5; z += 0.1) scene.Add(0.0, 5.0, z);
  for (double r = 1.0; r <= 10.01; r += 0.5) {
    scene.Add(90.0, r, std::max(0.0, r - 2.0) * std::tan(10.0 * M_PI / 180.0));
  }
  for (double r = 1.0; r <= 2.51; r += 0.5) scene.Add(180.0, r, 0.0);
  scene.Add(180.0, 3.0, 3.0);
  for (double r = 1.0; r <= 2.51; r += 0.5) scene.Add(-90.0, r, 0.0);
  for (double z = 0.0; z <= 0.61; z += 0.1) scene.Add(-90.0, 3.0, z);
  scene.AddRaw({NAN, 1.f, 0.f, 0.f, 0});
  scene.Add(45.0, 0.2, 0.0);  // the robot itself
  common::LidarRevolution revolution;
  revolution.slices.push_back(scene.Slice());
  revolution.expected_slices = 1;
  return revolution;
}

const PlanarRay* RayToward(const std::vector<PlanarRay>& rays, double azimuth_deg) {
  for (const PlanarRay& ray : rays) {
    const common::Vector2 d = ray.end_m - ray.origin_m;
    double diff = std::atan2(d.y(), d.x()) * 180.0 / M_PI - azimuth_deg;
    while (diff > 180.0) diff -= 360.0;
    while (diff < -180.0) diff += 360.0;
    if (std::abs(diff) < 0.5) return &ray;
  }
  return nullptr;
}

TEST(ObstacleBandTest, OneRayPerBinToTheNearestBandPointOrTheFarthestGround) {
  ObstacleBandParams params;
  ObstacleBandStats stats;
  const std::vector<PlanarRay> rays = ProjectObstacleBand(TestRevolution(), params, 0.0, &stats);
  EXPECT_EQ(stats.points_invalid, 1);
  EXPECT_EQ(stats.points_out_of_range, 1);
  ASSERT_EQ(rays.size(), 4u);  // four occupied bins
  EXPECT_EQ(stats.hit_rays, 2);
  EXPECT_EQ(stats.free_rays, 2);

  const PlanarRay* wall = RayToward(rays, 0.0);
  ASSERT_NE(wall, nullptr);
  EXPECT_TRUE(wall->hit);
  EXPECT_NEAR(wall->end_m.x(), 5.0, 1e-5);
  const PlanarRay* ramp = RayToward(rays, 90.0);  // 10 deg: ground, cleared to 10 m
  ASSERT_NE(ramp, nullptr);
  EXPECT_FALSE(ramp->hit);
  EXPECT_NEAR(ramp->end_m.y(), 10.0, 1e-5);
  const PlanarRay* ceiling = RayToward(rays, 180.0);  // above the band: ignored
  ASSERT_NE(ceiling, nullptr);
  EXPECT_FALSE(ceiling->hit);
  EXPECT_NEAR(ceiling->end_m.x(), -2.5, 1e-5);
  const PlanarRay* box = RayToward(rays, -90.0);
  ASSERT_NE(box, nullptr);
  EXPECT_TRUE(box->hit);
  EXPECT_NEAR(box->end_m.y(), -3.0, 1e-5);
}

TEST(ObstacleBandTest, LowObstacleBelowTheBandIsGround) {
  ObstacleBandParams params;
  params.min_height_m = 0.7;  // the 0.6 m box is now below the band
  const std::vector<PlanarRay> rays = ProjectObstacleBand(TestRevolution(), params, 0.0);
  const PlanarRay* box = RayToward(rays, -90.0);
  ASSERT_NE(box, nullptr);
  EXPECT_FALSE(box->hit);
}

TEST(ObstacleBandTest, FarWallWithHiddenFootStandsOut) {
  BandScene scene;
  for (double z = 1.5; z <= 2.51; z += 0.1) scene.Add(30.0, 20.0, z);
  common::LidarRevolution revolution;
  revolution.slices.push_back(scene.Slice());
  const std::vector<PlanarRay> rays = ProjectObstacleBand(revolution, {}, 0.0);
  ASSERT_EQ(rays.size(), 1u);
  EXPECT_TRUE(rays[0].hit);
}

TEST(ObstacleBandTest, RaysStartAtTheirSlicesSensorAndGroundFromSensorHeight) {
  common::LidarRevolution revolution;
  for (int s = 0; s < 2; ++s) {
    BandScene scene(s * 0.5, 0.0);
    for (double z = 0.05; z <= 1.0; z += 0.1) scene.Add(s == 0 ? 0.0 : 180.0, 3.0, z);
    revolution.slices.push_back(scene.Slice());
  }
  ObstacleBandParams params;
  params.sensor_height_m = kSensorZ;
  const std::vector<PlanarRay> rays = ProjectObstacleBand(revolution, params, NAN);
  ASSERT_EQ(rays.size(), 2u);
  const PlanarRay* ahead = RayToward(rays, 0.0);
  const PlanarRay* behind = RayToward(rays, 180.0);
  ASSERT_TRUE(ahead && behind);
  EXPECT_NEAR(ahead->origin_m.x(), 0.0, 1e-9);
  EXPECT_NEAR(behind->origin_m.x(), 0.5, 1e-9);
  EXPECT_NEAR(behind->end_m.x(), -2.5, 1e-5);
  EXPECT_TRUE(ahead->hit && behind->hit);
}

TEST(ObstacleBandTest, RejectsBadParams) {
  ObstacleBandParams params;
  params.max_height_m = 0.1;
  EXPECT_THROW(ProjectObstacleBand(TestRevolution(), params, 0.0), std::invalid_argument);
  params = ObstacleBandParams();
  params.azimuth_bins = 0;
  EXPECT_THROW(ProjectObstacleBand(TestRevolution(), params, 0.0), std::invalid_argument);
}

TEST(ObstacleBandTest, FeedsTheOccupancyGrid) {
  OccupancyParams grid_params;
  grid_params.size_x_cells = 800;
  grid_params.size_y_cells = 800;
  grid_params.origin_x_m = -20.0;
  grid_params.origin_y_m = -20.0;
  OccupancyGrid grid(grid_params);
  const std::vector<PlanarRay> rays = ProjectObstacleBand(TestRevolution(), {}, 0.0);
  const OccupancyInsertStats stats = grid.InsertRays(rays);
  EXPECT_EQ(stats.hits, 2);
  EXPECT_GT(grid.LogOddsAt({5.01, 0.001}), 0.0f);         // the wall
  EXPECT_LT(grid.LogOddsAt({2.5, 0.001}), 0.0f);          // free in front
  EXPECT_TRUE(std::isnan(grid.LogOddsAt({6.0, 0.001})));  // unknown behind
  EXPECT_LT(grid.LogOddsAt({0.001, 8.0}), 0.0f);          // along the ramp
}

}  // namespace
}  // namespace cairn::mapping
