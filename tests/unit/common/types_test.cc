#include "common/types.h"

#include <gtest/gtest.h>

namespace cairn::common {
namespace {

TEST(Pose2Test, ComposeInverseIsIdentity) {
  const Pose2 a{1.0, -2.0, 0.8};
  const Pose2 b{0.3, 0.4, -2.5};
  const Pose2 ab = a.Compose(b);
  const Pose2 back = a.Inverse().Compose(ab);
  EXPECT_NEAR(back.x_m, b.x_m, 1e-12);
  EXPECT_NEAR(back.y_m, b.y_m, 1e-12);
  EXPECT_NEAR(back.yaw_rad, b.yaw_rad, 1e-12);
  const Vector2 p = a.Transform({1.0, 0.0});
  EXPECT_NEAR(p.x(), 1.0 + std::cos(0.8), 1e-12);
  EXPECT_NEAR(p.y(), -2.0 + std::sin(0.8), 1e-12);
}

TEST(WrapAngleTest, Range) {
  EXPECT_NEAR(WrapAngle(3 * M_PI), M_PI, 1e-12);
  EXPECT_NEAR(WrapAngle(-M_PI), M_PI, 1e-12);
  EXPECT_NEAR(WrapAngle(0.5), 0.5, 1e-12);
  EXPECT_NEAR(WrapAngle(-7.0), -7.0 + 2 * M_PI, 1e-12);
}

TEST(Pose3Test, PitchSignIsNoseUpPositive) {
  Pose3 pose;
  // Rotating about +y by -0.1 rad lifts the nose (x axis gets a +z component).
  pose.orientation = Quaternion(Eigen::AngleAxisd(-0.1, Vector3::UnitY()));
  EXPECT_GT((pose.orientation * Vector3::UnitX()).z(), 0.0);
  EXPECT_NEAR(pose.pitch_rad(), 0.1, 1e-12);
  pose.orientation = Quaternion(Eigen::AngleAxisd(0.4, Vector3::UnitZ()));
  EXPECT_NEAR(pose.yaw_rad(), 0.4, 1e-12);
}

}  // namespace
}  // namespace cairn::common
