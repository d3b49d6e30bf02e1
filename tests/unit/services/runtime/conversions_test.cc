#include "services/runtime/conversions.h"

#include <cmath>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>

#include "services/runtime/tiler.h"
#include "tests/support/sample_obstacles.h"

namespace cairn::runtime {
namespace {

common::Pose3 SomePose() {
  common::Pose3 p;
  p.position_m = {1.5, -2.25, 0.4};
  p.orientation =
      common::Quaternion(Eigen::AngleAxisd(0.3, common::Vector3(0.2, 0.1, 1).normalized()));
  return p;
}

TEST(ConversionsTest, LidarSliceRoundTrip) {
  common::LidarSlice s;
  s.utime = 123456;
  s.robot = "rover1";
  s.revolution = 7;
  s.slice_index = 2;
  s.slice_count = 18;
  s.azimuth_start_rad = 0.1;
  s.azimuth_end_rad = 0.45;
  s.max_range_m = 70.0;
  s.sensor_pose = SomePose();
  s.points = {{1.f, 2.f, 3.f, 0.5f, 4}, {-1.f, 0.f, 0.25f, 1.f, 31}};
  auto back = FromLcm(ToLcm(s));
  ASSERT_TRUE(back.ok()) << back.status().ToString();
  EXPECT_EQ(back->utime, s.utime);
  EXPECT_EQ(back->robot, s.robot);
  EXPECT_EQ(back->revolution, 7);
  EXPECT_EQ(back->slice_index, 2);
  EXPECT_EQ(back->slice_count, 18);
  EXPECT_DOUBLE_EQ(back->azimuth_end_rad, 0.45);
  EXPECT_TRUE(back->sensor_pose.position_m.isApprox(s.sensor_pose.position_m));
  EXPECT_TRUE(back->sensor_pose.orientation.isApprox(s.sensor_pose.orientation));
  ASSERT_EQ(back->points.size(), 2u);
  EXPECT_EQ(back->points[1].ring, 31);
  EXPECT_EQ(back->points[1].z_m, 0.25f);
}

TEST(ConversionsTest, LidarSliceRejectsBadInput) {
  common::LidarSlice s;
  s.slice_count = 1;
  auto m = ToLcm(s);
  m.num_points = 3;  // arrays are empty
  EXPECT_FALSE(FromLcm(m).ok());
  m = ToLcm(s);
  m.sensor_orientation_wxyz[0] = NAN;
  EXPECT_FALSE(FromLcm(m).ok());
  m = ToLcm(s);
  m.slice_index = 5;
  EXPECT_FALSE(FromLcm(m).ok());
}

// A slice on a grid of 4 rings by 6 columns, as the simulator's lidar makes it: every ray but
// two returned, each point along its ray at a range of whole 2 mm steps.
common::LidarSlice GriddedSlice() {
  common::LidarSlice s;
  s.utime = 42;
  s.robot = "rover1";
  s.revolution = 3;
  s.slice_index = 1;
  s.slice_count = 20;
  s.azimuth_start_rad = 0.3;
  s.max_range_m = 70.0;
  s.sensor_pose = SomePose();
  s.grid.ring_elevation_rad = {-0.5f, -0.2f, 0.0f, 0.18f};
  s.grid.azimuth_step_rad = 0.0035;
  s.grid.columns = 6;
  s.grid.range_resolution_m = 0.002;
  s.azimuth_end_rad = s.azimuth_start_rad + 6 * s.grid.azimuth_step_rad;
  for (int c = 0; c < 6; ++c) {
    for (int r = 0; r < 4; ++r) {
      if ((c == 2 && r == 1) || (c == 5 && r == 3)) continue;  // no return
      const double el = s.grid.ring_elevation_rad[r];
      const double az = s.azimuth_start_rad + c * s.grid.azimuth_step_rad;
      const double range_m = 0.002 * (500 + 3001 * c + 17 * r);  // 1.0 m to 31.1 m
      common::LidarPoint p;
      p.x_m = static_cast<float>(std::cos(el) * std::cos(az) * range_m);
      p.y_m = static_cast<float>(std::cos(el) * std::sin(az) * range_m);
      p.z_m = static_cast<float>(std::sin(el) * range_m);
      p.intensity = static_cast<float>(10 * c + r);
      p.ring = static_cast<int16_t>(r);
      p.column = static_cast<uint16_t>(c);
      s.points.push_back(p);
    }
  }
  return s;
}

TEST(ConversionsTest, LidarRangesRoundTripThroughTheWire) {
  const common::LidarSlice s = GriddedSlice();
  const cairn::lcmt_lidar_ranges m = ToLcmRanges(s);
  EXPECT_EQ(m.num_rays, 24);
  // 3 bytes a ray, against 17 a point: the rays' bytes and a header under 256 bytes.
  EXPECT_LT(m.getEncodedSize(), 24 * 3 + 256);
  std::vector<uint8_t> bytes(static_cast<size_t>(m.getEncodedSize()));
  ASSERT_EQ(m.encode(bytes.data(), 0, static_cast<int>(bytes.size())),
            static_cast<int>(bytes.size()));
  cairn::lcmt_lidar_ranges decoded;
  ASSERT_EQ(decoded.decode(bytes.data(), 0, static_cast<int>(bytes.size())),
            static_cast<int>(bytes.size()));
  auto back = FromLcm(decoded);
  ASSERT_TRUE(back.ok()) << back.status().ToString();
  EXPECT_EQ(back->utime, 42);
  EXPECT_EQ(back->robot, "rover1");
  EXPECT_EQ(back->revolution, 3);
  EXPECT_EQ(back->slice_index, 1);
  EXPECT_EQ(back->slice_count, 20);
  EXPECT_NEAR(back->azimuth_end_rad, s.azimuth_end_rad, 1e-12);
  EXPECT_TRUE(back->sensor_pose.position_m.isApprox(s.sensor_pose.position_m));
  EXPECT_EQ(back->grid.columns, 6);
  EXPECT_EQ(back->grid.ring_elevation_rad, s.grid.ring_elevation_rad);
  // Every point comes back, in column then ring order, on its ray within a micrometre.
  ASSERT_EQ(back->points.size(), s.points.size());
  for (size_t i = 0; i < s.points.size(); ++i) {
    const common::LidarPoint& a = s.points[i];
    const common::LidarPoint& b = back->points[i];
    EXPECT_EQ(b.ring, a.ring);
    EXPECT_EQ(b.column, a.column);
    EXPECT_EQ(b.intensity, a.intensity);
    const Eigen::Vector3f d(a.x_m - b.x_m, a.y_m - b.y_m, a.z_m - b.z_m);
    EXPECT_LT(d.norm(), 1e-5f) << "point " << i;
  }
}

TEST(ConversionsTest, LidarRangesRoundAndClampWhatTheirBitsCannotHold) {
  common::LidarSlice s = GriddedSlice();
  s.points.resize(3);
  s.points[0].x_m *= 1.0003f;  // off the 2 mm steps: rounded to the nearest
  s.points[1].intensity = 300.f;
  s.points[2].x_m = NAN;  // no range: no return
  const cairn::lcmt_lidar_ranges m = ToLcmRanges(s);
  EXPECT_EQ(m.ranges[0], 500);  // about 1.0002 m
  EXPECT_EQ(m.intensity[1], 255);
  EXPECT_EQ(m.ranges[2], 0);
  s.points[0].x_m = 500.f;  // 250,000 steps: the last of 16 bits
  EXPECT_EQ(static_cast<uint16_t>(ToLcmRanges(s).ranges[0]), 65535);
  // A point off the grid, or a slice without one, is a caller's bug.
  s.points[0].column = 6;
  EXPECT_THROW(ToLcmRanges(s), std::invalid_argument);
  s.grid = {};
  EXPECT_THROW(ToLcmRanges(s), std::invalid_argument);
}

TEST(ConversionsTest, LidarRangesRejectBadInput) {
  const cairn::lcmt_lidar_ranges good = ToLcmRanges(GriddedSlice());
  ASSERT_TRUE(FromLcm(good).ok());
  auto refused = [&](auto&& change) {
    cairn::lcmt_lidar_ranges m = good;
    change(m);
    return !FromLcm(m).ok();
  };
  EXPECT_TRUE(refused([](auto& m) { m.num_rays = 25; }));
  EXPECT_TRUE(refused([](auto& m) { m.num_columns = 7; }));
  EXPECT_TRUE(refused([](auto& m) { m.ranges.pop_back(); }));
  EXPECT_TRUE(refused([](auto& m) { m.intensity.pop_back(); }));
  EXPECT_TRUE(refused([](auto& m) {
    m.num_rings = 128;
    m.ring_elevation_rad.assign(128, 0.f);
    m.num_columns = 1;
    m.num_rays = 128;
    m.ranges.assign(128, 1);
    m.intensity.assign(128, 0);
  }));
  EXPECT_TRUE(refused([](auto& m) { m.num_rings = 0; }));
  EXPECT_TRUE(refused([](auto& m) { m.range_resolution_m = 0.0; }));
  EXPECT_TRUE(refused([](auto& m) { m.range_resolution_m = NAN; }));
  EXPECT_TRUE(refused([](auto& m) { m.range_resolution_m = 5.0; }));
  EXPECT_TRUE(refused([](auto& m) { m.ring_elevation_rad[2] = NAN; }));
  EXPECT_TRUE(refused([](auto& m) { m.ring_elevation_rad[2] = 1.6f; }));
  EXPECT_TRUE(refused([](auto& m) { m.azimuth_step_rad = INFINITY; }));
  EXPECT_TRUE(refused([](auto& m) { m.azimuth_step_rad = 2.0; }));  // 6 columns: 12 rad
  EXPECT_TRUE(refused([](auto& m) { m.azimuth_start_rad = NAN; }));
  EXPECT_TRUE(refused([](auto& m) { m.slice_index = 20; }));
  EXPECT_TRUE(refused([](auto& m) { m.sensor_orientation_wxyz[0] = NAN; }));
}

TEST(ConversionsTest, LaserScanRoundTrip) {
  common::LaserScan s;
  s.utime = 99;
  s.robot = "kobuki1";
  s.sensor_pose = SomePose();
  s.angle_min_rad = -2.0943951f;
  s.angle_increment_rad = 0.00613f;
  s.range_min_m = 0.02f;
  s.range_max_m = 5.6f;
  s.ranges_m = {1.f, INFINITY, 2.5f};
  auto back = FromLcm(ToLcm(s));
  ASSERT_TRUE(back.ok());
  EXPECT_EQ(back->ranges_m.size(), 3u);
  EXPECT_TRUE(std::isinf(back->ranges_m[1]));
  EXPECT_EQ(back->angle_min_rad, s.angle_min_rad);
  EXPECT_EQ(back->range_max_m, s.range_max_m);
}

TEST(ConversionsTest, RobotProfileRoundTrip) {
  common::RobotProfile p;
  p.name = "rover";
  p.drive = common::DriveKind::kSkidSteer;
  p.footprint_m = common::RectangleFootprint(0.7, 0.55);
  p.max_slope_down_rad = INFINITY;
  p.sensors = {"hdl32e"};
  const auto m = ToLcm(p);
  EXPECT_EQ(m.content_hash, p.ContentHash());
  auto back = FromLcm(m);
  ASSERT_TRUE(back.ok()) << back.status().ToString();
  EXPECT_EQ(*back, p);
  auto bad = m;
  bad.max_step_up_m = -1;
  EXPECT_FALSE(FromLcm(bad).ok());
  bad = m;
  bad.drive = 42;
  EXPECT_FALSE(FromLcm(bad).ok());
}

TEST(ConversionsTest, PoseRoundTripAndRejectsNonUnitQuaternion) {
  const common::Pose3 p = SomePose();
  auto back = FromLcm(ToLcmPose(p, 5, "r", "world"));
  ASSERT_TRUE(back.ok());
  EXPECT_TRUE(back->position_m.isApprox(p.position_m));
  auto m = ToLcmPose(p, 5, "r", "world");
  m.orientation_wxyz[0] = 2.0;
  EXPECT_FALSE(FromLcm(m).ok());
}

}  // namespace
}  // namespace cairn::runtime

namespace cairn::runtime {
namespace {

TEST(ConversionsTest, ObstacleRegistryRoundTrip) {
  common::ObstacleRegistry r;
  r.map_version = 12;
  common::Obstacle o;
  o.id = 4;
  o.kind = common::ObstacleKind::kRamp;
  o.centroid_m = {3.0, -1.0};
  o.outline_m = {{2, -2}, {4, -2}, {4, 0}, {2, 0}};
  o.slope_rad = 0.1745;
  o.height_m = 0.35;
  o.width_m = 2.0;
  o.length_m = 2.0;
  o.depth_m = NAN;
  o.area_m2 = 4.0;
  o.num_cells = 100;
  o.downhill_heading_rad = 1.25;
  o.verdicts = {{"pioneer3at", "abc", false, "slope 10.0 deg > 8.0 deg"},
                {"rover", "def", true, ""}};
  r.obstacles.push_back(o);
  auto back = FromLcm(ToLcm(r, 1, "r1", "live"));
  ASSERT_TRUE(back.ok());
  ASSERT_EQ(back->obstacles.size(), 1u);
  const auto& b = back->obstacles[0];
  EXPECT_EQ(back->map_version, 12);
  EXPECT_EQ(b.kind, common::ObstacleKind::kRamp);
  EXPECT_EQ(b.outline_m.size(), 4u);
  EXPECT_TRUE(std::isnan(b.depth_m));
  EXPECT_EQ(b.downhill_heading_rad, 1.25);
  EXPECT_EQ(b.verdicts, o.verdicts);
  EXPECT_EQ(b.VerdictFor("rover")->crossable, true);
  auto bad = ToLcm(o);
  bad.kind = 9;
  EXPECT_FALSE(FromLcm(bad).ok());
}

// A terrace crosses the bus with its parts; a message whose part count is over the limit, that
// gives parts to another kind, or whose part is not a ramp or a face is refused (rule 8).
TEST(ConversionsTest, ATerraceCrossesTheBusWithItsParts) {
  const common::Obstacle t = cairn::testing::SampleTerrace();
  auto back = FromLcm(ToLcm(t));
  ASSERT_TRUE(back.ok()) << back.status().ToString();
  ASSERT_EQ(back->parts.size(), 2u);
  EXPECT_EQ(back->parts[1].heading_in_rad, t.parts[1].heading_in_rad);
  EXPECT_EQ(back->parts[1].verdicts, t.parts[1].verdicts);
  EXPECT_EQ(back->parts[0].outline_m, t.parts[0].outline_m);
  auto many = ToLcm(t);
  many.parts.resize(cairn::lcmt_obstacle::MAX_PARTS + 1, many.parts[0]);
  many.num_parts = static_cast<int32_t>(many.parts.size());
  EXPECT_FALSE(FromLcm(many).ok());
  auto lying = ToLcm(t);
  lying.num_parts = 3;
  EXPECT_FALSE(FromLcm(lying).ok());
  auto ramp_with_parts = ToLcm(t);
  ramp_with_parts.kind = cairn::lcmt_obstacle::KIND_RAMP;
  EXPECT_FALSE(FromLcm(ramp_with_parts).ok());
  auto ditch_part = ToLcm(t);
  ditch_part.parts[0].kind = cairn::lcmt_obstacle::KIND_DITCH;
  EXPECT_FALSE(FromLcm(ditch_part).ok());
  auto terrace_alone = ToLcm(t);
  terrace_alone.parts.clear();
  terrace_alone.num_parts = 0;
  EXPECT_FALSE(FromLcm(terrace_alone).ok());
}

TEST(ConversionsTest, ARegistryOverTheBusLimitLosesItsOutlinesOnly) {
  common::ObstacleRegistry r;
  common::Obstacle o;
  o.kind = common::ObstacleKind::kWallOrObject;
  o.height_m = 1.5;
  for (int i = 0; i < 100; ++i) o.outline_m.push_back({0.1 * i, 0.0});
  r.obstacles.push_back(o);
  auto small = ToLcm(r, 1, "r1", "live");
  EXPECT_FALSE(FitRegistryToMessageLimit(&small));
  EXPECT_EQ(small.obstacles[0].num_outline, 100);
  r.obstacles.assign(300, o);  // 300 x 100 points x 16 bytes: about 480 KB
  auto large = ToLcm(r, 1, "r1", "live");
  ASSERT_GT(large.getEncodedSize(), static_cast<int>(kMaxMessageBytes));
  EXPECT_TRUE(FitRegistryToMessageLimit(&large));
  EXPECT_LE(large.getEncodedSize(), static_cast<int>(kMaxMessageBytes));
  ASSERT_EQ(large.obstacles.size(), 300u);
  EXPECT_EQ(large.obstacles[0].num_outline, 0);
  EXPECT_DOUBLE_EQ(large.obstacles[299].height_m, 1.5);
  EXPECT_TRUE(FromLcm(large).ok());
}

}  // namespace
}  // namespace cairn::runtime
