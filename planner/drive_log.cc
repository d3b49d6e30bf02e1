#include "planner/drive_log.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace cairn::planner {

void DriveLog::Record(const DwaResult& r, const common::Vector2& carrot) {
  ++dwa_;
  samples_ = r.samples;
  last_best_ = r.command;
  last_values_ = r.best_values;
  has_forward_ = r.has_best_forward;
  last_forward_ = r.best_forward;
  last_forward_values_ = r.best_forward_values;
  carrot_ = carrot;
  sum_v_mps_ += r.command.linear_mps;
  sum_abs_w_radps_ += std::abs(r.command.angular_radps);
  if (rejections_.size() < r.rejections.size()) rejections_.resize(r.rejections.size(), 0);
  for (size_t i = 0; i < r.rejections.size(); ++i) rejections_[i] += r.rejections[i];
  if (!r.found) ++dwa_invalid_;
}

std::string DriveLog::Describe(double moved_m, const std::vector<std::string>& names,
                               const std::optional<common::Pose2>& pose, double path_left_m) const {
  std::ostringstream m;
  m.setf(std::ios::fixed);
  m.precision(2);
  m << " (moved " << moved_m << " m; " << turning_ << " cycles turning toward the path, " << dwa_
    << " DWA cycles";
  if (dwa_ > 0) {
    m << " at a mean " << sum_v_mps_ / dwa_ << " m/s, " << sum_abs_w_radps_ / dwa_ << " rad/s, "
      << dwa_invalid_ << " without a valid sample";
    // The critics that rejected most samples, highest first.
    std::vector<size_t> order(rejections_.size());
    for (size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::sort(order.begin(), order.end(),
              [&](size_t a, size_t b) { return rejections_[a] > rejections_[b]; });
    bool first = true;
    for (size_t k = 0; k < order.size() && k < 2; ++k) {
      const size_t i = order[k];
      if (rejections_[i] == 0 || i >= names.size()) break;
      m << (first ? "; rejected per cycle: " : ", ") << names[i] << " "
        << static_cast<double>(rejections_[i]) / dwa_ << "/" << samples_;
      first = false;
    }
    m << "; last choice (" << last_best_.linear_mps << ", " << last_best_.angular_radps << ")";
    for (size_t i = 0; i < last_values_.size() && i < names.size(); ++i) {
      m << (i == 0 ? " scored " : ", ") << names[i] << " " << last_values_[i];
    }
    if (has_forward_ && !(last_forward_ == last_best_)) {
      m << "; best forward (" << last_forward_.linear_mps << ", " << last_forward_.angular_radps
        << ")";
      for (size_t i = 0; i < last_forward_values_.size() && i < names.size(); ++i) {
        m << (i == 0 ? " scored " : ", ") << names[i] << " " << last_forward_values_[i];
      }
    }
  }
  if (pose) {
    m << "; at (" << pose->x_m << ", " << pose->y_m << ", " << pose->yaw_rad << "), carrot ("
      << carrot_.x() << ", " << carrot_.y() << "), " << path_left_m << " m of path left";
  }
  m << ")";
  return m.str();
}

}  // namespace cairn::planner
