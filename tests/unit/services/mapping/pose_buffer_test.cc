// PoseBuffer: interpolation within the gap, nearest sample, out-of-order samples.

#include "services/mapping/pose_buffer.h"

#include <limits>

#include <gtest/gtest.h>

#include "tests/unit/services/mapping/synthetic_scan.h"

namespace cairn::mapping {
namespace {

using testing::SensorAt;

common::Pose3 At(double x, double y, double yaw = 0.0) { return SensorAt(x, y, 0.0, yaw); }

TEST(PoseBufferTest, InterpolatesWithinTheGapOnly) {
  PoseBuffer buffer;
  EXPECT_FALSE(buffer.At(0, 1.0).has_value());
  ASSERT_TRUE(buffer.Add(1'000'000, At(0.0, 0.0, 0.0)));
  ASSERT_TRUE(buffer.Add(1'200'000, At(2.0, 0.0, 0.4)));
  const auto mid = buffer.At(1'050'000, 0.2);
  ASSERT_TRUE(mid.has_value());
  EXPECT_NEAR(mid->position_m.x(), 0.5, 1e-9);
  EXPECT_NEAR(mid->yaw_rad(), 0.1, 1e-9);
  // Outside both samples but near one: that sample.
  EXPECT_NEAR(buffer.At(1'250'000, 0.1)->position_m.x(), 2.0, 1e-12);
  // Between samples farther apart than the gap: the nearer one if it is close enough.
  EXPECT_NEAR(buffer.At(1'090'000, 0.1)->position_m.x(), 0.0, 1e-12);
  EXPECT_FALSE(buffer.At(2'000'000, 0.1).has_value());
  // Out of order, and a non-finite pose refused.
  ASSERT_TRUE(buffer.Add(1'100'000, At(1.0, 1.0)));
  EXPECT_NEAR(buffer.At(1'100'000, 0.01)->position_m.y(), 1.0, 1e-12);
  common::Pose3 bad = At(0, 0);
  bad.position_m.x() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(buffer.Add(1'300'000, bad));
  EXPECT_EQ(buffer.size(), 3u);
}

}  // namespace
}  // namespace cairn::mapping
