#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "common/point_cloud.h"
#include "services/explore/scan_mesh.h"

/// @file
/// Stop-and-scan (seed 002 §2.1): the rotating planar laser's lines, one vertical fan per pan
/// step, assembled into the ordered grid the mesh is built on. The assembler starts on request,
/// takes the first line at pan 0 and every following step until the pan range is covered, and
/// hands over an OrderedScan whose row k is the line at pan k · pan_step. A few lines lost on the
/// bus (max_missing_lines in a row) are left without returns; it starts over when more are
/// missing or a line comes out of order, when the scanner moved during the sweep (the robot must
/// stand still), or when a line does not fit the first one's beam layout; it gives up after
/// timeout_s. Every size read from a line is checked against a bound before it allocates
/// (beams, lines), so a faulty peer cannot make it grow.

namespace cairn::explore {

struct TurretScanParams {
  double pan_step_rad{0.5 * 3.14159265358979323846 / 180.0};
  double pan_range_rad{3.14159265358979323846};  ///< one scan (a 270 deg fan covers the sphere)
  double tilt_step_rad{0.5 * 3.14159265358979323846 / 180.0};
  int max_beams{8192};        ///< per line
  int max_lines{4096};        ///< per scan
  double max_motion_m{0.03};  ///< the scanner may drift this much during a sweep
  double max_rotation_rad{0.02};
  double timeout_s{60.0};  ///< from the request to the last line
  /// Up to this many consecutive lines lost (on the bus) leave lines with no return; a longer
  /// gap starts the scan over.
  int max_missing_lines{3};
  /// Height of the scanner above the ground under the robot (OrderedScan::robot_base_z_m is
  /// the first line's scanner height minus this).
  double scanner_height_m{1.0};

  /// @throws std::invalid_argument naming the bad field.
  void Validate() const;
};

class TurretScanAssembler {
 public:
  enum class State { kIdle, kWaitingForStart, kCollecting, kDone, kTimedOut };

  /// @throws std::invalid_argument for invalid params.
  explicit TurretScanAssembler(const TurretScanParams& params);

  /// Starts (or restarts) a scan at simulation time now_s.
  void Request(double now_s);

  /// One line (its sensor_pose is the scanning plane's pose; beam angles are in that plane,
  /// measured from its x axis). Returns the scan when this line completes it. `event` receives
  /// one line when the assembler starts over or gives up (left alone otherwise).
  std::optional<OrderedScan> Add(const common::LaserScan& line, double pan_rad, double now_s,
                                 std::string* event = nullptr);

  /// Gives up when the request is older than timeout_s (call it periodically; returns true once
  /// when it times out).
  bool CheckTimeout(double now_s, std::string* event = nullptr);

  State state() const { return state_; }
  int lines_collected() const { return next_step_; }
  int lines_needed() const { return steps_; }
  int restarts() const { return restarts_; }
  /// Lines missing from the scan being collected (or the last one completed).
  int missing_lines() const { return missing_lines_; }

 private:
  void StartOver(const std::string& why, std::string* event);

  TurretScanParams params_;
  int steps_{0};
  State state_{State::kIdle};
  double requested_s_{0.0};
  int next_step_{0};
  int beams_{0};
  double angle_min_rad_{0.0};
  double angle_increment_rad_{0.0};
  common::Pose3 first_pose_;
  OrderedScan scan_;
  int restarts_{0};
  int missing_lines_{0};
};

}  // namespace cairn::explore
