#include "simulator/sensors/lidar_sensor.h"

#include <cmath>
#include <map>
#include <set>
#include <string>

#include <gtest/gtest.h>

#include "simulator/mujoco_sim.h"
#include "simulator/sensors/planar_laser_sensor.h"
#include "tests/unit/simulator/sim_test_util.h"

namespace cairn::sim {
namespace {

using testing::FlatWorld;
using testing::InlineScenario;
using testing::SimTest;

constexpr double kDeg = M_PI / 180.0;

// The lidar's slices as points, the way a consumer that needs points reads the range images
// the HDL-32E makes.
std::vector<common::LidarSlice> AsPoints(const std::vector<common::LidarSlice>& slices) {
  std::vector<common::LidarSlice> out = slices;
  for (common::LidarSlice& slice : out) {
    EXPECT_TRUE(common::HasRangeImage(slice));
    EXPECT_TRUE(slice.points.empty());  // the sensor writes no points beside its ranges
    common::ExpandRangeImage(&slice);
  }
  return out;
}

TEST(LidarLayoutTest, RingAnglesAreExact) {
  const LidarParams p;  // HDL-32E defaults
  ASSERT_EQ(p.rings, 32);
  EXPECT_DOUBLE_EQ(LidarRingElevationRad(p, 0), -30.67 * kDeg);
  EXPECT_DOUBLE_EQ(LidarRingElevationRad(p, 31), 10.67 * kDeg);
  const double step_deg = (10.67 + 30.67) / 31.0;  // 1.3335 deg between rings
  for (int r = 0; r < 32; ++r) {
    EXPECT_NEAR(LidarRingElevationRad(p, r), (-30.67 + r * step_deg) * kDeg, 1e-12) << r;
  }
  // Every ray of the pattern carries exactly its ring's elevation, and each (ring, step) pair
  // appears once.
  const LidarPattern pattern = BuildLidarPattern(p);
  ASSERT_EQ(pattern.rays.directions.size(), 32u * 1800u);
  std::vector<int> seen(32 * 1800, 0);
  for (size_t i = 0; i < pattern.rays.directions.size(); ++i) {
    const Eigen::Vector3d& d = pattern.rays.directions[i];
    const int r = pattern.ring[i];
    ASSERT_NEAR(d.norm(), 1.0, 1e-12);
    ASSERT_NEAR(std::asin(d.z()), LidarRingElevationRad(p, r), 1e-12) << "ray " << i;
    ++seen[pattern.azimuth_step[i] * 32 + r];
  }
  for (int count : seen) ASSERT_EQ(count, 1);
}

TEST(LidarLayoutTest, AzimuthStepsAreExact) {
  const LidarParams p;
  ASSERT_EQ(p.azimuth_steps, 1800);
  EXPECT_DOUBLE_EQ(LidarAzimuthRad(p, 1), 0.2 * kDeg);
  EXPECT_DOUBLE_EQ(LidarAzimuthRad(p, 900), M_PI);
  EXPECT_DOUBLE_EQ(LidarAzimuthRad(p, 1800), 2.0 * M_PI);
  const LidarPattern pattern = BuildLidarPattern(p);
  for (size_t i = 0; i < pattern.rays.directions.size(); ++i) {
    const Eigen::Vector3d& d = pattern.rays.directions[i];
    double az = std::atan2(d.y(), d.x());
    if (az < -1e-12) az += 2.0 * M_PI;
    ASSERT_NEAR(az, pattern.azimuth_step[i] * 0.2 * kDeg, 1e-11) << "ray " << i;
  }
}

TEST(LidarLayoutTest, SlicesCoverTheTurnOnce) {
  for (int slices : {18, 20, 7}) {
    LidarParams p;
    p.slices_per_revolution = slices;
    std::vector<int> owner(p.azimuth_steps, -1);
    for (int s = 0; s < slices; ++s) {
      for (int k = LidarSliceBegin(p, s); k < LidarSliceBegin(p, s + 1); ++k) {
        ASSERT_EQ(owner[k], -1) << "step " << k << " in two slices";
        owner[k] = s;
      }
    }
    for (int k = 0; k < p.azimuth_steps; ++k) ASSERT_GE(owner[k], 0) << "step " << k;
    EXPECT_EQ(LidarSliceBegin(p, 0), 0);
    EXPECT_EQ(LidarSliceBegin(p, slices), p.azimuth_steps);
    // Slices own contiguous rays; every ray of a slice (and of each of its groups) has an
    // azimuth step of that slice.
    const LidarPattern pattern = BuildLidarPattern(p);
    ASSERT_EQ(pattern.slice_ray_begin.size(), static_cast<size_t>(slices + 1));
    ASSERT_EQ(pattern.slice_group_begin.size(), static_cast<size_t>(slices + 1));
    for (int s = 0; s < slices; ++s) {
      for (int i = pattern.slice_ray_begin[s]; i < pattern.slice_ray_begin[s + 1]; ++i) {
        ASSERT_EQ(owner[pattern.azimuth_step[i]], s);
      }
      const auto& groups = pattern.rays.groups;
      EXPECT_EQ(groups[pattern.slice_group_begin[s]].begin, pattern.slice_ray_begin[s]);
      EXPECT_EQ(groups[pattern.slice_group_begin[s + 1] - 1].end, pattern.slice_ray_begin[s + 1]);
    }
  }
}

TEST(LidarLayoutTest, DefaultSliceFitsOneDatagramFriendlyMessage) {
  const LidarParams p;
  EXPECT_NO_THROW(p.Validate());
  const int rays = (p.azimuth_steps / p.slices_per_revolution) * p.rings;
  EXPECT_GT(p.range_resolution_m, 0.0);  // published as ranges: 3 bytes a ray
  EXPECT_LE(rays * 3, 64 * 1024);        // 10 a turn: 5,760 rays, 17 KB
  // As points (17 bytes each) such a slice would not fit: refused with the way out. Twenty
  // slices a turn fit.
  LidarParams points = p;
  points.range_resolution_m = 0.0;
  try {
    points.Validate();
    ADD_FAILURE() << "a 98 KB slice of points was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("slices_per_revolution"), std::string::npos) << e.what();
  }
  points.slices_per_revolution = 20;
  EXPECT_NO_THROW(points.Validate());
  // Four slices a turn: 14,400 rays, 43 KB as ranges.
  LidarParams four = p;
  four.slices_per_revolution = 4;
  EXPECT_NO_THROW(four.Validate());
  LidarParams one = p;
  one.slices_per_revolution = 1;
  EXPECT_THROW(one.Validate(), std::invalid_argument);
  // 16 bits of 1 mm steps reach 65.5 m, short of the 70 m range.
  LidarParams fine = p;
  fine.range_resolution_m = 0.001;
  EXPECT_THROW(fine.Validate(), std::invalid_argument);
  fine.max_range_m = 65.0;
  EXPECT_NO_THROW(fine.Validate());
}

class LidarSimTest : public SimTest {};

// A closed box room so every lidar ray returns.
std::string RoomWorld() {
  return FlatWorld(R"(
    <geom name="wall_east" type="box" size="0.1 6 2" pos="5.1 0 2"/>
    <geom name="wall_west" type="box" size="0.1 6 2" pos="-6.1 0 2"/>
    <geom name="wall_north" type="box" size="6 0.1 2" pos="0 6.1 2"/>
    <geom name="wall_south" type="box" size="6 0.1 2" pos="0 -6.1 2"/>)");
}

TEST_F(LidarSimTest, OneRevolutionIsSlicesCoveringTheTurnOnce) {
  Scenario s = InlineScenario(RoomWorld(), "p3at", "pioneer3at");
  MujocoSim sim(s);
  SimOutputs out;
  // Slices of revolution 0 fall due over the first 0.1 s.
  while (sim.time_s() < 0.1 + 1e-9) sim.Step(&out);
  std::map<int, const common::LidarSlice*> by_index;
  const std::vector<common::LidarSlice> slices = AsPoints(out.Readings<LidarSensor>());
  for (const auto& slice : slices) {
    if (slice.revolution == 0) {
      EXPECT_TRUE(by_index.emplace(slice.slice_index, &slice).second) << slice.slice_index;
    }
  }
  ASSERT_EQ(by_index.size(), 10u);
  double expected_start = 0.0;
  size_t points = 0;
  for (const auto& [index, slice] : by_index) {
    EXPECT_EQ(slice->slice_count, 10);
    EXPECT_NEAR(slice->azimuth_start_rad, expected_start, 1e-12);
    EXPECT_NEAR(slice->azimuth_end_rad - slice->azimuth_start_rad, 2.0 * M_PI / 10, 1e-12);
    // Its grid: 180 columns of 0.2 deg by the 32 rings, 2 mm range steps.
    EXPECT_EQ(slice->grid.columns, 180);
    EXPECT_NEAR(slice->grid.azimuth_step_rad, 2.0 * M_PI / 1800, 1e-15);
    EXPECT_EQ(slice->grid.ring_elevation_rad.size(), 32u);
    EXPECT_DOUBLE_EQ(slice->grid.range_resolution_m, 0.002);
    expected_start = slice->azimuth_end_rad;
    for (const auto& pt : slice->points) {
      double az = std::atan2(pt.y_m, pt.x_m);
      if (az < 0) az += 2.0 * M_PI;
      // Points lie within their slice (float rounding aside).
      EXPECT_GE(az, slice->azimuth_start_rad - 1e-5);
      EXPECT_LT(az, slice->azimuth_end_rad + 1e-5);
      EXPECT_GE(pt.ring, 0);
      EXPECT_LT(pt.ring, 32);
      // Its ray is the one its column and ring name.
      EXPECT_NEAR(az, slice->azimuth_start_rad + pt.column * slice->grid.azimuth_step_rad, 1e-5);
      const double elevation = std::atan2(pt.z_m, std::hypot(pt.x_m, pt.y_m));
      EXPECT_NEAR(elevation, slice->grid.ring_elevation_rad[pt.ring], 1e-5);
    }
    points += slice->points.size();
  }
  EXPECT_NEAR(expected_start, 2.0 * M_PI, 1e-12);
  // In a closed room every ray returns (no point is closer than the minimum range).
  EXPECT_EQ(points, 32u * 1800u);
  // Slices are stamped with their own time, 10 ms apart.
  EXPECT_EQ(by_index.at(9)->utime - by_index.at(0)->utime, 9 * 10000);
}

TEST_F(LidarSimTest, WallAtKnownDistanceReadsWithinNoise) {
  // Wall face at x = 5.0; the robot at the origin facing it.
  Scenario s = InlineScenario(RoomWorld(), "p3at", "pioneer3at");
  MujocoSim sim(s);
  SimOutputs out;
  while (sim.time_s() < 0.3) sim.Step(&out);
  const double sigma = s.robots[0].sensors.Find<LidarSensor>()->range_noise_sigma_m;
  ASSERT_GT(sigma, 0.0);

  // Ring 23 is level (+0.0016 deg): its beams towards azimuth ~0 hit the wall face.
  int n = 0;
  double sum_error = 0.0;
  for (const auto& slice : AsPoints(out.Readings<LidarSensor>())) {
    if (slice.slice_index != 0 && slice.slice_index != 19) continue;
    const common::Pose3& sensor = slice.sensor_pose;
    const double distance_to_wall = 5.0 - sensor.position_m.x();
    for (const auto& pt : slice.points) {
      if (pt.ring != 23) continue;
      const double az = std::atan2(pt.y_m, pt.x_m);
      if (std::abs(az) > 10.0 * kDeg) continue;
      const double range = std::sqrt(pt.x_m * pt.x_m + pt.y_m * pt.y_m + pt.z_m * pt.z_m);
      const double expected =
          distance_to_wall / (std::cos(az) * std::cos(std::asin(pt.z_m / range)));
      const double error = range - expected;
      // The noise, and half a 2 mm step of rounding.
      EXPECT_LT(std::abs(error), 5.0 * sigma + 0.001) << "azimuth " << az;
      sum_error += error;
      ++n;
    }
  }
  ASSERT_GT(n, 100);
  // The mean error shrinks with sqrt(n): unbiased within 4 standard errors (rounding to the
  // nearest step adds no bias, and its own spread, 2 mm / sqrt(12), is small beside sigma).
  EXPECT_LT(std::abs(sum_error / n),
            4.0 * std::hypot(sigma, 0.002 / std::sqrt(12.0)) / std::sqrt(n));

  // The planar laser's centre beam also reads the wall within its noise.
  ASSERT_FALSE(out.Readings<PlanarLaserSensor>().empty());
  const common::LaserScan& scan = out.Readings<PlanarLaserSensor>().back();
  const int centre = static_cast<int>(scan.ranges_m.size() / 2);
  EXPECT_NEAR(scan.angle_min_rad + centre * scan.angle_increment_rad, 0.0, 1e-6);
  const double laser_sigma = s.robots[0].sensors.Find<PlanarLaserSensor>()->range_noise_sigma_m;
  EXPECT_NEAR(scan.ranges_m[centre], 5.0 - scan.sensor_pose.position_m.x(), 5.0 * laser_sigma);
}

TEST_F(LidarSimTest, NoiseFreeLidarIsExact) {
  // As points (no range resolution), a noise-free reading is the exact distance.
  Scenario s = InlineScenario(RoomWorld(), "p3at", "pioneer3at");
  s.robots[0].sensors.Find<LidarSensor>()->range_noise_sigma_m = 0.0;
  s.robots[0].sensors.Find<LidarSensor>()->range_resolution_m = 0.0;
  s.robots[0].sensors.Find<LidarSensor>()->slices_per_revolution = 20;  // 17 bytes a point
  MujocoSim sim(s);
  SimOutputs out;
  while (sim.time_s() < 0.01) sim.Step(&out);
  ASSERT_FALSE(out.Readings<LidarSensor>().empty());
  const auto& slice = out.Readings<LidarSensor>().front();
  ASSERT_EQ(slice.slice_index, 0);
  EXPECT_TRUE(slice.range_steps.empty());
  const double distance_to_wall = 5.0 - slice.sensor_pose.position_m.x();
  bool found = false;
  for (const auto& pt : slice.points) {
    if (pt.ring == 23 && std::abs(pt.y_m) < 1e-6) {
      // Azimuth 0, elevation 0.0016 deg: range = d / cos(el).
      EXPECT_NEAR(pt.x_m, distance_to_wall, 1e-5);
      found = true;
    }
  }
  EXPECT_TRUE(found);
}

TEST_F(LidarSimTest, TheRangeImageIsTheReadingsRoundedToTheResolution) {
  // The same run (same seed, so the same noise) as points and as a range image: every point's
  // range, rounded to 2 mm, is at its ray; every ray without a point reads 0.
  auto run = [](double resolution_m) {
    Scenario s = InlineScenario(FlatWorld(R"(<geom type="box" size="0.5 0.5 0.5" pos="3 1 0.5"/>)"),
                                "r", "pioneer3at");
    s.robots[0].sensors.Find<LidarSensor>()->range_resolution_m = resolution_m;
    s.robots[0].sensors.Find<LidarSensor>()->slices_per_revolution = 20;  // points fit too
    MujocoSim sim(s);
    SimOutputs out;
    while (sim.time_s() < 0.1 + 1e-9) sim.Step(&out);
    return out.Readings<LidarSensor>();
  };
  const std::vector<common::LidarSlice> points = run(0.0), image = run(0.002);
  ASSERT_EQ(points.size(), image.size());
  ASSERT_GE(points.size(), 20u);
  size_t returns = 0, empty = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    const common::LidarSlice& a = points[i];
    const common::LidarSlice& b = image[i];
    ASSERT_TRUE(common::HasRangeImage(b)) << i;
    ASSERT_FALSE(common::HasRangeImage(a)) << i;
    EXPECT_EQ(a.grid.columns, b.grid.columns);
    const size_t rings = b.grid.ring_elevation_rad.size();
    std::vector<uint16_t> expected(b.range_steps.size(), 0);
    std::vector<uint8_t> expected_intensity(b.range_steps.size(), 0);
    for (const auto& pt : a.points) {
      const size_t ray = static_cast<size_t>(pt.column) * rings + pt.ring;
      const float range = std::sqrt(pt.x_m * pt.x_m + pt.y_m * pt.y_m + pt.z_m * pt.z_m);
      expected[ray] = static_cast<uint16_t>(std::lround(range / 0.002));
      expected_intensity[ray] = static_cast<uint8_t>(std::lround(pt.intensity));
    }
    for (size_t ray = 0; ray < expected.size(); ++ray) {
      // The points' float coordinates may move a range across a half step: one step apart.
      ASSERT_NEAR(b.range_steps[ray], expected[ray], 1) << "slice " << i << " ray " << ray;
      ASSERT_EQ(b.range_steps[ray] == 0, expected[ray] == 0) << "slice " << i << " ray " << ray;
      ASSERT_EQ(b.range_intensity[ray], expected_intensity[ray]);
      ++(expected[ray] == 0 ? empty : returns);
    }
    // Expanded, the image gives the points back within a step.
    common::LidarSlice expanded = b;
    common::ExpandRangeImage(&expanded);
    ASSERT_EQ(expanded.points.size(), a.points.size()) << i;
    EXPECT_TRUE(expanded.range_steps.empty());
    for (size_t k = 0; k < a.points.size(); ++k) {
      ASSERT_EQ(expanded.points[k].ring, a.points[k].ring);
      ASSERT_EQ(expanded.points[k].column, a.points[k].column);
      ASSERT_NEAR(expanded.points[k].x_m, a.points[k].x_m, 0.0015);
      ASSERT_NEAR(expanded.points[k].y_m, a.points[k].y_m, 0.0015);
      ASSERT_NEAR(expanded.points[k].z_m, a.points[k].z_m, 0.0015);
    }
  }
  EXPECT_GT(returns, 10000u);  // the ground and the box
  EXPECT_GT(empty, 10000u);    // the sky
}

TEST_F(LidarSimTest, RobotDoesNotSeeItselfButSeesOthers) {
  Scenario s = InlineScenario(FlatWorld(), "a", "pioneer3at");
  SpawnPose other;
  other.x_m = 3.0;
  s.robots.push_back(MakeRobotSpec("b", "pioneer3at", "", other, testing::TestPaths()));
  s.robots[0].sensors.Find<LidarSensor>()->range_noise_sigma_m = 0.0;
  MujocoSim sim(s);
  SimOutputs out;
  while (sim.time_s() < 0.1 + 1e-9) sim.Step(&out);
  size_t near_points = 0, toward_b = 0;
  for (const auto& slice : AsPoints(out.Readings<LidarSensor>())) {
    if (slice.robot != "a") continue;
    for (const auto& pt : slice.points) {
      const double r = std::hypot(pt.x_m, pt.y_m);
      if (r < 0.35 && pt.z_m > -0.2) ++near_points;  // would be robot a's own body
      if (std::abs(std::atan2(pt.y_m, pt.x_m)) < 2 * kDeg && r > 2.5 && r < 3.0 && pt.z_m > -0.3)
        ++toward_b;
    }
  }
  EXPECT_EQ(near_points, 0u);
  EXPECT_GT(toward_b, 5u);
}

}  // namespace
}  // namespace cairn::sim
