#pragma once

/// @file
/// Differential-drive inverse kinematics and planar-scan angle metadata (seed 003 §4, tests
/// 29–33): the simulator side of the reactive explorer, which turns (v, ω) into wheel joint
/// speeds and publishes the laser's angles.

namespace cairn::explore {

/// Wheel joint speeds (rad/s), positive driving the robot forward.
struct WheelSpeeds {
  double left_radps{0.0};
  double right_radps{0.0};
};

/// Inverse differential-drive kinematics: ω_L = (v − L·ω/2)/r, ω_R = (v + L·ω/2)/r, with
/// v the forward speed, ω the yaw rate (counter-clockwise positive), r the wheel radius and
/// L the distance between the wheels. Seed 003's Pioneer P3DX uses r = 0.0975 m and
/// L = 0.381 m (the source's `axis_length`; 381 mm is the P3DX body width, the real wheel
/// track is smaller: verify before reuse).
/// @throws std::invalid_argument for a non-finite speed, or a non-positive or non-finite
/// radius or track.
WheelSpeeds InverseKinematics(double v_mps, double omega_radps, double wheel_radius_m,
                              double track_m);

/// The angles of a planar scan of `beams` beams (LaserScan convention: beam i points at
/// angle_min_rad + i·angle_increment_rad).
struct ScanAngles {
  double angle_min_rad{0.0};
  double angle_max_rad{0.0};
  double angle_increment_rad{0.0};
  int beams{0};
};

/// Angles consistent with the beam count (seed 003's SLAM script): increment FOV/(N − 1),
/// angle_min = −FOV/2, angle_max = angle_min + (N − 1)·increment, so beam 0 and beam N − 1
/// lie on the two edges of the field of view.
/// @throws std::invalid_argument unless 0 < fov_rad <= 2π and beams >= 2.
ScanAngles ConsistentScanAngles(double fov_rad, int beams);

/// Seed 003's first (No-SLAM) script, kept to document its bug: increment FOV/N with
/// angle_min = −FOV/2 and angle_max = +FOV/2, so N beams span only FOV·(N − 1)/N and
/// IsConsistent() fails.
/// @throws std::invalid_argument unless 0 < fov_rad <= 2π and beams >= 1.
ScanAngles LegacyScanAngles(double fov_rad, int beams);

/// True when (angle_max − angle_min)/angle_increment + 1 equals `beams` within
/// `tolerance` (what a LaserScan consumer that derives N from the angles relies on). False for
/// a zero or non-finite increment.
bool IsConsistent(const ScanAngles& angles, double tolerance = 1e-6);

}  // namespace cairn::explore
