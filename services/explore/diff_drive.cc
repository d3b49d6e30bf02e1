#include "services/explore/diff_drive.h"

#include <cmath>

#include "common/check.h"

namespace cairn::explore {

namespace {

void CheckFov(double fov_rad) {
  CAIRN_THROW_UNLESS(std::isfinite(fov_rad) && fov_rad > 0.0 && fov_rad <= 2.0 * M_PI,
                     "scan fov_rad must lie in (0, 2*pi], got " << fov_rad);
}

}  // namespace

WheelSpeeds InverseKinematics(double v_mps, double omega_radps, double wheel_radius_m,
                              double track_m) {
  CAIRN_THROW_UNLESS(std::isfinite(v_mps),
                     "InverseKinematics: v_mps must be finite, got " << v_mps);
  CAIRN_THROW_UNLESS(std::isfinite(omega_radps),
                     "InverseKinematics: omega_radps must be finite, got " << omega_radps);
  CAIRN_THROW_UNLESS(std::isfinite(wheel_radius_m) && wheel_radius_m > 0.0,
                     "InverseKinematics: wheel_radius_m must be positive, got " << wheel_radius_m);
  CAIRN_THROW_UNLESS(std::isfinite(track_m) && track_m > 0.0,
                     "InverseKinematics: track_m must be positive, got " << track_m);
  const double half_turn_mps = 0.5 * track_m * omega_radps;
  return {(v_mps - half_turn_mps) / wheel_radius_m, (v_mps + half_turn_mps) / wheel_radius_m};
}

ScanAngles ConsistentScanAngles(double fov_rad, int beams) {
  CheckFov(fov_rad);
  CAIRN_THROW_UNLESS(beams >= 2, "ConsistentScanAngles: beams must be >= 2, got " << beams);
  ScanAngles angles;
  angles.beams = beams;
  angles.angle_increment_rad = fov_rad / (beams - 1);
  angles.angle_min_rad = -0.5 * fov_rad;
  angles.angle_max_rad = angles.angle_min_rad + (beams - 1) * angles.angle_increment_rad;
  return angles;
}

ScanAngles LegacyScanAngles(double fov_rad, int beams) {
  CheckFov(fov_rad);
  CAIRN_THROW_UNLESS(beams >= 1, "LegacyScanAngles: beams must be >= 1, got " << beams);
  ScanAngles angles;
  angles.beams = beams;
  angles.angle_increment_rad = fov_rad / beams;
  angles.angle_min_rad = -0.5 * fov_rad;
  angles.angle_max_rad = 0.5 * fov_rad;
  return angles;
}

bool IsConsistent(const ScanAngles& angles, double tolerance) {
  if (!std::isfinite(angles.angle_increment_rad) || angles.angle_increment_rad == 0.0) {
    return false;
  }
  const double implied_beams =
      (angles.angle_max_rad - angles.angle_min_rad) / angles.angle_increment_rad + 1.0;
  return std::abs(implied_beams - angles.beams) <= tolerance;
}

}  // namespace cairn::explore
