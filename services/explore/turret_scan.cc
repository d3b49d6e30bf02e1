#include "services/explore/turret_scan.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>

namespace cairn::explore {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

void RequirePositive(double v, const char* name) {
  if (!(v > 0.0) || !std::isfinite(v)) {
    throw std::invalid_argument(std::string("turret scan: ") + name + " must be positive");
  }
}

}  // namespace

void TurretScanParams::Validate() const {
  RequirePositive(pan_step_rad, "pan_step_rad");
  RequirePositive(pan_range_rad, "pan_range_rad");
  RequirePositive(tilt_step_rad, "tilt_step_rad");
  if (pan_range_rad < pan_step_rad || pan_range_rad > 2.0 * M_PI + 1e-9) {
    throw std::invalid_argument("turret scan: pan_range_rad must lie in [pan_step_rad, 2 pi]");
  }
  if (max_beams < 2) throw std::invalid_argument("turret scan: max_beams must be >= 2");
  if (max_lines < 1) throw std::invalid_argument("turret scan: max_lines must be >= 1");
  RequirePositive(max_motion_m, "max_motion_m");
  RequirePositive(max_rotation_rad, "max_rotation_rad");
  RequirePositive(timeout_s, "timeout_s");
  if (max_missing_lines < 0) {
    throw std::invalid_argument("turret scan: max_missing_lines must be >= 0");
  }
  if (!(scanner_height_m >= 0.0) || !std::isfinite(scanner_height_m)) {
    throw std::invalid_argument("turret scan: scanner_height_m must be >= 0");
  }
  if (std::lround(pan_range_rad / pan_step_rad) > max_lines) {
    throw std::invalid_argument("turret scan: pan_range_rad / pan_step_rad exceeds max_lines");
  }
}

TurretScanAssembler::TurretScanAssembler(const TurretScanParams& params) : params_(params) {
  params_.Validate();
  steps_ = static_cast<int>(std::lround(params_.pan_range_rad / params_.pan_step_rad));
}

void TurretScanAssembler::Request(double now_s) {
  state_ = State::kWaitingForStart;
  requested_s_ = now_s;
  next_step_ = 0;
  scan_ = OrderedScan{};
}

void TurretScanAssembler::StartOver(const std::string& why, std::string* event) {
  ++restarts_;
  if (event) *event = "scan started over: " + why;
  state_ = State::kWaitingForStart;
  next_step_ = 0;
  scan_ = OrderedScan{};
}

bool TurretScanAssembler::CheckTimeout(double now_s, std::string* event) {
  if (state_ != State::kWaitingForStart && state_ != State::kCollecting) return false;
  if (now_s - requested_s_ <= params_.timeout_s) return false;
  state_ = State::kTimedOut;
  if (event) {
    *event = "scan timed out after " + std::to_string(static_cast<int>(params_.timeout_s)) +
             " s with " + std::to_string(next_step_) + " of " + std::to_string(steps_) + " lines";
  }
  return true;
}

std::optional<OrderedScan> TurretScanAssembler::Add(const common::LaserScan& line, double pan_rad,
                                                    double now_s, std::string* event) {
  if (state_ != State::kWaitingForStart && state_ != State::kCollecting) return std::nullopt;
  if (CheckTimeout(now_s, event)) return std::nullopt;
  const int n = static_cast<int>(line.ranges_m.size());
  if (n < 2 || n > params_.max_beams || !std::isfinite(pan_rad) ||
      !std::isfinite(line.angle_min_rad) || !std::isfinite(line.angle_increment_rad) ||
      !line.sensor_pose.position_m.allFinite()) {
    if (state_ == State::kCollecting) StartOver("a malformed line", event);
    return std::nullopt;
  }
  // Which pan step is this line? Lines off the grid of steps are not the turret's.
  const double step_f = pan_rad / params_.pan_step_rad;
  const long step = std::lround(step_f);
  if (std::abs(step_f - static_cast<double>(step)) > 0.25) return std::nullopt;
  if (state_ == State::kWaitingForStart) {
    if (step != 0) return std::nullopt;
    state_ = State::kCollecting;
    beams_ = n;
    angle_min_rad_ = line.angle_min_rad;
    angle_increment_rad_ = line.angle_increment_rad;
    first_pose_ = line.sensor_pose;
    scan_ = OrderedScan{};
    scan_.num_lines = steps_;
    scan_.beams_per_line = beams_;
    scan_.points_m.assign(static_cast<size_t>(steps_) * static_cast<size_t>(beams_),
                          Eigen::Vector3f::Constant(kNaN));
    scan_.sensor_origin_m = first_pose_.position_m.cast<float>();
    scan_.robot_base_z_m =
        static_cast<float>(first_pose_.position_m.z() - params_.scanner_height_m);
    scan_.pan_step_rad = params_.pan_step_rad;
    scan_.tilt_step_rad = params_.tilt_step_rad;
    next_step_ = 0;
    missing_lines_ = 0;
  } else if (step != next_step_) {
    // A few lines lost on the bus leave no-return lines (a hole in the mesh); more, or lines
    // out of order, start the scan over.
    const long gap = step - next_step_;
    if (gap < 1 || gap > params_.max_missing_lines || step >= steps_) {
      StartOver(
          "line " + std::to_string(next_step_) + " missing (got " + std::to_string(step) + ")",
          event);
      return std::nullopt;
    }
    missing_lines_ += static_cast<int>(gap);
    next_step_ = static_cast<int>(step);
  }
  if (n != beams_ || line.angle_min_rad != angle_min_rad_ ||
      line.angle_increment_rad != angle_increment_rad_) {
    StartOver("a line with another beam layout", event);
    return std::nullopt;
  }
  // The scanner must stand still.
  const double moved = (line.sensor_pose.position_m - first_pose_.position_m).norm();
  // Lines turn about the turret's axis; compare the turret's heading through the pan.
  if (moved > params_.max_motion_m) {
    StartOver("the scanner moved " + std::to_string(moved) + " m", event);
    return std::nullopt;
  }
  const Eigen::Vector3d axis = line.sensor_pose.orientation * Eigen::Vector3d::UnitX();
  const Eigen::Vector3d first_axis = first_pose_.orientation * Eigen::Vector3d::UnitX();
  const double tilt = std::acos(std::clamp(axis.dot(first_axis), -1.0, 1.0));
  if (tilt > params_.max_rotation_rad) {
    StartOver("the scanner tilted", event);
    return std::nullopt;
  }
  Eigen::Vector3f* row = scan_.points_m.data() + static_cast<size_t>(next_step_) * beams_;
  for (int b = 0; b < n; ++b) {
    const float r = line.ranges_m[b];
    if (!std::isfinite(r) || r < line.range_min_m || r >= line.range_max_m) continue;
    const double a = angle_min_rad_ + b * angle_increment_rad_;
    const Eigen::Vector3d p =
        line.sensor_pose.Transform(Eigen::Vector3d(r * std::cos(a), r * std::sin(a), 0.0));
    row[b] = p.cast<float>();
  }
  if (++next_step_ < steps_) return std::nullopt;
  state_ = State::kDone;
  return std::move(scan_);
}

}  // namespace cairn::explore
