#include "services/mapping/sonar_detection.h"

#include <cmath>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

// Seed 004 §7 unit tests 8, 9 and 12: detect_peaks parity (mph 110, mpd 2), the zero runs and
// the shadow verification, and where a peak lies in the world.

namespace cairn::mapping {
namespace {

std::vector<uint8_t> P(std::initializer_list<int> v) {
  std::vector<uint8_t> out;
  for (int x : v) out.push_back(static_cast<uint8_t>(x));
  return out;
}

TEST(SonarDetectionTest, Seed004Test8DetectPeaksParity) {
  auto peaks = [](std::initializer_list<int> v) { return DetectPeaks(P(v), 110, 2); };
  EXPECT_EQ(peaks({0, 0, 120, 0, 0, 115, 0, 0, 0, 200, 180, 0}), (std::vector<int>{2, 5, 9}));
  EXPECT_EQ(peaks({0, 120, 0, 130, 0}), (std::vector<int>{3}));
  EXPECT_EQ(peaks({0, 120, 0, 0, 130, 0}), (std::vector<int>{1, 4}));
  EXPECT_EQ(peaks({0, 110, 0, 0, 0}), (std::vector<int>{1}));
  EXPECT_EQ(peaks({0, 109, 0}), (std::vector<int>{}));
  EXPECT_EQ(peaks({200, 0, 0}), (std::vector<int>{}));
  EXPECT_EQ(peaks({0, 150, 150, 0, 0}), (std::vector<int>{1}));
  // Equal peaks within mpd: the later one stays (detect_peaks' order among equals).
  EXPECT_EQ(peaks({0, 130, 0, 130, 0}), (std::vector<int>{3}));
  EXPECT_EQ(peaks({}), (std::vector<int>{}));
}

TEST(SonarDetectionTest, Seed004Test9ZeroRunsAndTheShadowVerification) {
  const auto a = P({0, 0, 5, 7, 0, 0, 0, 9, 0});
  const auto runs = ZeroRuns(a);
  EXPECT_EQ(runs, (std::vector<std::pair<int, int>>{{0, 2}, {4, 7}, {8, 9}}));
  std::vector<int> between;
  for (int i = 0; i < static_cast<int>(a.size()); ++i) {
    if (PeakBetweenShadows(runs, i)) between.push_back(i);
  }
  EXPECT_EQ(between, (std::vector<int>{2, 3, 4, 7, 8}));  // {2, 3, 4} and {7, 8}
  // A peak in a trailing segment with no zero run after it is not verified.
  const auto trailing = P({0, 0, 60, 150, 90, 80, 70});
  EXPECT_FALSE(PeakBetweenShadows(ZeroRuns(trailing), 3));
  SonarPeakParams params;
  EXPECT_EQ(SonarObstacleBins(trailing, params), (std::vector<int>{3}));
  params.verify_shadow = true;
  EXPECT_TRUE(SonarObstacleBins(trailing, params).empty());
  // A rock's peak with its shadow behind it (test 5's profile) passes.
  const auto rock = P({0, 0, 0, 0, 81, 75, 215, 0, 0, 0, 55, 50});
  EXPECT_EQ(SonarObstacleBins(rock, params), (std::vector<int>{6}));
}

// Test 12: the sonar 0.7 m ahead of the robot's centre; a peak at bin k with the head at pan psi
// (positive to the left) and the robot at (X, Y, yaw) lies at (X, Y) + R(yaw)((0.7, 0) +
// R(psi)(k, 0)).
TEST(SonarDetectionTest, Seed004Test12APeakLiesAlongThePannedBeam) {
  const common::Vector2 robot(10.0, -4.0);
  const double yaw = 0.5, pan = 0.3;
  const common::Vector2 sensor = robot + common::Vector2(0.7 * std::cos(yaw), 0.7 * std::sin(yaw));
  const common::Vector2 at = SonarBinToWorld(sensor, yaw + pan, 12, 1.0);
  const common::Vector2 expected =
      robot + common::Vector2(0.7 * std::cos(yaw) + 12.0 * std::cos(yaw + pan),
                              0.7 * std::sin(yaw) + 12.0 * std::sin(yaw + pan));
  EXPECT_NEAR((at - expected).norm(), 0.0, 1e-9);
  // Pan to the left (positive) puts the point left of the robot's heading.
  const common::Vector2 left = SonarBinToWorld({0.0, 0.0}, 0.0 + 0.5, 10, 1.0);
  EXPECT_GT(left.y(), 0.0);
}

}  // namespace
}  // namespace cairn::mapping
