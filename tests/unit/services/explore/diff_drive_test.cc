#include "services/explore/diff_drive.h"

#include <cmath>
#include <stdexcept>

#include <gtest/gtest.h>

namespace cairn::explore {
namespace {

// Seed 003's Pioneer P3DX (§4).
constexpr double kWheelRadiusM = 0.0975;
constexpr double kTrackM = 0.381;
constexpr double kFov240Rad = 240.0 * M_PI / 180.0;

TEST(DiffDriveTest, CruiseDrivesBothWheelsEqually) {  // seed 003 test 29
  const WheelSpeeds w = InverseKinematics(0.35, 0.0, kWheelRadiusM, kTrackM);
  EXPECT_NEAR(w.left_radps, 3.5897, 1e-4);
  EXPECT_NEAR(w.right_radps, 3.5897, 1e-4);
}

TEST(DiffDriveTest, TurnInPlaceSpinsTheWheelsOppositely) {  // seed 003 test 30
  const WheelSpeeds w = InverseKinematics(0.0, 0.6, kWheelRadiusM, kTrackM);
  EXPECT_NEAR(w.left_radps, -1.1723, 1e-4);
  EXPECT_NEAR(w.right_radps, 1.1723, 1e-4);
}

TEST(DiffDriveTest, VeeringRightDrivesTheLeftWheelFaster) {  // seed 003 test 31
  const WheelSpeeds w = InverseKinematics(0.28, -0.4, kWheelRadiusM, kTrackM);
  EXPECT_NEAR(w.left_radps, 3.6533, 1e-4);
  EXPECT_NEAR(w.right_radps, 2.0903, 1e-4);
}

TEST(DiffDriveTest, ReverseDrivesBothWheelsBackwards) {  // seed 003 test 32
  const WheelSpeeds w = InverseKinematics(-0.15, 0.0, kWheelRadiusM, kTrackM);
  EXPECT_NEAR(w.left_radps, -1.5385, 1e-4);
  EXPECT_NEAR(w.right_radps, -1.5385, 1e-4);
}

TEST(DiffDriveTest, BadGeometryOrSpeedThrows) {
  EXPECT_THROW(InverseKinematics(0.1, 0.0, 0.0, kTrackM), std::invalid_argument);
  EXPECT_THROW(InverseKinematics(0.1, 0.0, -0.1, kTrackM), std::invalid_argument);
  EXPECT_THROW(InverseKinematics(0.1, 0.0, kWheelRadiusM, 0.0), std::invalid_argument);
  EXPECT_THROW(InverseKinematics(NAN, 0.0, kWheelRadiusM, kTrackM), std::invalid_argument);
  EXPECT_THROW(InverseKinematics(0.1, INFINITY, kWheelRadiusM, kTrackM), std::invalid_argument);
}

TEST(DiffDriveTest, ConsistentScanAnglesMatchTheBeamCount) {  // seed 003 test 33
  const ScanAngles a = ConsistentScanAngles(kFov240Rad, 684);
  EXPECT_EQ(a.beams, 684);
  EXPECT_NEAR(a.angle_increment_rad, 0.0061329, 1e-7);
  EXPECT_NEAR(a.angle_increment_rad * 180.0 / M_PI, 0.35139, 1e-5);
  EXPECT_NEAR(a.angle_min_rad, -kFov240Rad / 2.0, 1e-12);
  EXPECT_NEAR(a.angle_max_rad, kFov240Rad / 2.0, 1e-12);
  EXPECT_NEAR((a.angle_max_rad - a.angle_min_rad) / a.angle_increment_rad + 1.0, 684.0, 1e-6);
  EXPECT_TRUE(IsConsistent(a));
}

TEST(DiffDriveTest, LegacyScanAnglesFailTheConsistencyCheck) {  // seed 003 test 33
  const ScanAngles a = LegacyScanAngles(kFov240Rad, 684);
  EXPECT_NEAR(a.angle_increment_rad, 0.0061240, 1e-7);
  EXPECT_NEAR(a.angle_min_rad, -kFov240Rad / 2.0, 1e-12);
  EXPECT_NEAR(a.angle_max_rad, kFov240Rad / 2.0, 1e-12);
  EXPECT_FALSE(IsConsistent(a));
  // It implies one beam too many.
  EXPECT_NEAR((a.angle_max_rad - a.angle_min_rad) / a.angle_increment_rad + 1.0, 685.0, 1e-6);
}

TEST(DiffDriveTest, BadScanGeometryThrows) {
  EXPECT_THROW(ConsistentScanAngles(kFov240Rad, 1), std::invalid_argument);
  EXPECT_THROW(ConsistentScanAngles(0.0, 684), std::invalid_argument);
  EXPECT_THROW(ConsistentScanAngles(7.0, 684), std::invalid_argument);
  EXPECT_THROW(ConsistentScanAngles(NAN, 684), std::invalid_argument);
  EXPECT_THROW(LegacyScanAngles(kFov240Rad, 0), std::invalid_argument);
  EXPECT_NO_THROW(ConsistentScanAngles(2.0 * M_PI, 2));
}

TEST(DiffDriveTest, AZeroIncrementIsNotConsistent) {
  ScanAngles a;
  a.beams = 1;
  EXPECT_FALSE(IsConsistent(a));
}

}  // namespace
}  // namespace cairn::explore
