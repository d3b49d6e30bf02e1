#include "common/point_cloud.h"

#include <cmath>

#include <gtest/gtest.h>

namespace cairn::common {
namespace {

// Two columns 0.5 rad apart by three rings (-0.25, 0, 0.25 rad), 1 cm steps.
LidarSlice SmallImage() {
  LidarSlice s;
  s.azimuth_start_rad = 0.25;
  s.grid.ring_elevation_rad = {-0.25f, 0.f, 0.25f};
  s.grid.azimuth_step_rad = 0.5;
  s.grid.columns = 2;
  s.grid.range_resolution_m = 0.01;
  s.range_steps = {100, 0, 250, 0, 0, 65535};  // column 0: rings 0 and 2; column 1: ring 2
  s.range_intensity = {10, 99, 20, 0, 0, 255};
  return s;
}

TEST(LidarRangeImageTest, ExpandsEachReturnAtItsRingAndColumn) {
  LidarSlice s = SmallImage();
  ASSERT_TRUE(HasRangeImage(s));
  s.points.push_back({9.f, 9.f, 9.f, 1.f, 0});  // points already there stay first
  ExpandRangeImage(&s);
  EXPECT_FALSE(HasRangeImage(s));
  EXPECT_TRUE(s.range_steps.empty());
  EXPECT_TRUE(s.range_intensity.empty());
  ASSERT_EQ(s.points.size(), 4u);  // the three returns; a 0 is no return, whatever its byte
  EXPECT_EQ(s.points[0].x_m, 9.f);
  const struct {
    int ring, column;
    double range_m;
    float intensity;
  } expected[] = {{0, 0, 1.0, 10.f}, {2, 0, 2.5, 20.f}, {2, 1, 655.35, 255.f}};
  for (int k = 0; k < 3; ++k) {
    const LidarPoint& p = s.points[k + 1];
    const double elevation = s.grid.ring_elevation_rad[expected[k].ring];
    const double azimuth = 0.25 + 0.5 * expected[k].column;
    const double r = expected[k].range_m;
    EXPECT_EQ(p.ring, expected[k].ring);
    EXPECT_EQ(p.column, expected[k].column);
    EXPECT_EQ(p.intensity, expected[k].intensity);
    EXPECT_NEAR(p.x_m, r * std::cos(elevation) * std::cos(azimuth), 1e-4 * r);
    EXPECT_NEAR(p.y_m, r * std::cos(elevation) * std::sin(azimuth), 1e-4 * r);
    EXPECT_NEAR(p.z_m, r * std::sin(elevation), 1e-4 * r);
  }
}

TEST(LidarRangeImageTest, AnImageThatDoesNotFitItsGridIsLeftAlone) {
  // Arrays of the wrong size, a grid without rings or columns, a resolution out of (0, 1] m.
  std::vector<LidarSlice> bad(6, SmallImage());
  bad[0].range_steps.pop_back();
  bad[1].range_intensity.push_back(0);
  bad[2].grid.ring_elevation_rad.clear();
  bad[3].grid.columns = 0;
  bad[4].grid.range_resolution_m = 0.0;
  bad[5].grid.range_resolution_m = 1.5;
  for (size_t i = 0; i < bad.size(); ++i) {
    EXPECT_FALSE(HasRangeImage(bad[i])) << i;
    const LidarSlice before = bad[i];
    ExpandRangeImage(&bad[i]);
    EXPECT_TRUE(bad[i].points.empty()) << i;
    EXPECT_EQ(bad[i].range_steps, before.range_steps) << i;
  }
}

TEST(LidarRangeImageTest, RangesAndIntensitiesRoundToTheNearestAndClamp) {
  EXPECT_EQ(LidarRangeToSteps(1.0049f, 100.f), 100);
  EXPECT_EQ(LidarRangeToSteps(1.0051f, 100.f), 101);
  EXPECT_EQ(LidarRangeToSteps(0.004f, 100.f), 0);  // under half a step: no return
  EXPECT_EQ(LidarRangeToSteps(NAN, 100.f), 0);
  EXPECT_EQ(LidarRangeToSteps(1e6f, 100.f), 65535);
  EXPECT_EQ(LidarIntensityByte(99.6f), 100);
  EXPECT_EQ(LidarIntensityByte(-3.f), 0);
  EXPECT_EQ(LidarIntensityByte(300.f), 255);
}

}  // namespace
}  // namespace cairn::common
