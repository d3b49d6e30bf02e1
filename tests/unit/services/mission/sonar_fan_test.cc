// The fan image of the last sweep: each bearing shows its latest ping, range outwards, and bad
// pings are refused with their reason.

#include "services/mission/sonar_fan.h"

#include <cmath>

#include <gtest/gtest.h>

namespace cairn::mission {
namespace {

FanPing Ping(double pan_rad, int echo_bin, uint8_t value) {
  FanPing p;
  p.pan_rad = pan_rad;
  p.range_min_m = 0.0;
  p.range_max_m = 50.0;
  p.bins.assign(50, 0);
  p.bins[echo_bin] = value;
  return p;
}

float At(const common::GridMap& image, double x_m, double y_m) {
  const auto cell = image.IndexOf({x_m, y_m});
  EXPECT_TRUE(cell.has_value()) << x_m << ", " << y_m;
  if (!cell) return -1.f;
  return image.at(SonarFan::kIntensityLayer)(cell->ix, cell->iy);
}

TEST(SonarFanTest, EachBearingShowsItsLatestPingAtItsRange) {
  SonarFan fan;
  // A sweep from -60 to +60 deg, a wall at 20 m straight ahead (bin 20 on bearings near 0).
  for (double a = -M_PI / 3; a <= M_PI / 3 + 1e-9; a += 0.005) {
    ASSERT_TRUE(fan.Add(Ping(a, std::abs(a) < 0.1 ? 20 : 40, 200)).ok());
  }
  EXPECT_EQ(fan.reversals(), 0);
  // The head swept back over 0: a later ping there shows a nearer echo.
  ASSERT_TRUE(fan.Add(Ping(0.0, 10, 120)).ok());
  EXPECT_EQ(fan.reversals(), 1);
  EXPECT_NEAR(fan.min_pan_rad(), -M_PI / 3, 0.005);
  EXPECT_NEAR(fan.max_pan_rad(), M_PI / 3, 0.005);
  const common::GridMap image = fan.Image(0.1);
  ASSERT_TRUE(image.HasLayer(SonarFan::kIntensityLayer));
  EXPECT_NEAR(At(image, 20.5, 1.0), 200.f, 0.f);   // bearing 0.05 rad: the wall bin
  EXPECT_NEAR(At(image, 10.5, 0.0), 120.f, 0.f);   // the latest ping at bearing 0
  EXPECT_NEAR(At(image, 20.5, 0.0), 0.f, 0.f);     // ... which replaced the older one
  // Bearing -0.78 rad: its echo at 40 m, and nothing at 28 m.
  EXPECT_NEAR(At(image, 40.5 * std::cos(0.78), -40.5 * std::sin(0.78)), 200.f, 0.f);
  EXPECT_NEAR(At(image, 28.5 * std::cos(0.78), -28.5 * std::sin(0.78)), 0.f, 0.f);
}

TEST(SonarFanTest, OutsideTheSectorIsNaN) {
  SonarFan fan;
  for (double a = -0.5; a <= 0.5; a += 0.005) ASSERT_TRUE(fan.Add(Ping(a, 5, 100)).ok());
  const common::GridMap image = fan.Image(0.25);
  // Bearing 0.6 rad at 10 m is outside the swept +-0.5 rad.
  const double x = 10 * std::cos(0.6), y = 10 * std::sin(0.6);
  const auto cell = image.IndexOf({x, y});
  ASSERT_TRUE(cell.has_value());
  EXPECT_TRUE(std::isnan(image.at(SonarFan::kIntensityLayer)(cell->ix, cell->iy)));
  EXPECT_NEAR(At(image, 5.1, 0.0), 100.f, 0.f);
}

TEST(SonarFanTest, BadPingsAreRefusedAndNothingIsKept) {
  SonarFan fan;
  FanPing p = Ping(0.0, 3, 90);
  p.bins.clear();
  EXPECT_FALSE(fan.Add(p).ok());
  p = Ping(std::nan(""), 3, 90);
  EXPECT_FALSE(fan.Add(p).ok());
  p = Ping(4.0, 3, 90);
  EXPECT_FALSE(fan.Add(p).ok());
  p = Ping(0.0, 3, 90);
  p.range_max_m = 0.0;
  EXPECT_FALSE(fan.Add(p).ok());
  p = Ping(0.0, 3, 90);
  p.bins.assign(SonarFan::kMaxBins + 1, 0);
  EXPECT_FALSE(fan.Add(p).ok());
  EXPECT_EQ(fan.bearings(), 0u);
  EXPECT_FALSE(fan.Image().HasLayer(SonarFan::kIntensityLayer));
}

}  // namespace
}  // namespace cairn::mission
