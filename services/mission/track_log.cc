#include "services/mission/track_log.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>

#include "common/check.h"

namespace cairn::mission {

TrackLog::TrackLog(double period_s, size_t max_samples)
    : period_s_(period_s), max_samples_(max_samples) {
  CAIRN_THROW_UNLESS(period_s > 0.0 && std::isfinite(period_s), "the track period must be > 0");
}

common::Status TrackLog::OnPath(const std::vector<common::Vector2>& path_m) {
  for (const auto& p : path_m) {
    if (!p.allFinite()) return common::InvalidArgumentError("a path point is not finite");
  }
  path_m_ = path_m;
  return common::Status::Ok();
}

void TrackLog::OnOdometry(const common::Vector2& position_m) {
  if (position_m.allFinite()) odom_m_ = position_m;
}

void TrackLog::OnTruth(int64_t utime, const common::Vector2& position_m) {
  if (!position_m.allFinite()) return;
  if (!first_utime_) {
    first_utime_ = utime;
  } else if (utime - last_row_utime_ < static_cast<int64_t>(period_s_ * 1e6)) {
    return;
  }
  last_row_utime_ = utime;
  if (samples_.size() >= max_samples_) {
    ++dropped_;
    return;
  }
  TrackSample s;
  s.t_s = (utime - *first_utime_) * 1e-6;
  s.truth_m = position_m;
  s.odom_m = odom_m_;
  if (!path_m_.empty()) s.planned_m = NearestOnPath(path_m_, position_m);
  samples_.push_back(s);
}

common::Status TrackLog::WriteCsv(const std::string& path) const {
  std::ofstream out(path);
  if (!out) return common::UnavailableError("cannot write " + path);
  out << "t_s,odom_x_m,odom_y_m,truth_x_m,truth_y_m,planned_x_m,planned_y_m\n";
  char line[256];
  auto xy = [](const std::optional<common::Vector2>& v) {
    char b[64] = ",";
    if (v) std::snprintf(b, sizeof(b), "%.3f,%.3f", v->x(), v->y());
    return std::string(b);
  };
  for (const TrackSample& s : samples_) {
    std::snprintf(line, sizeof(line), "%.2f,%s,%.3f,%.3f,%s\n", s.t_s, xy(s.odom_m).c_str(),
                  s.truth_m.x(), s.truth_m.y(), xy(s.planned_m).c_str());
    out << line;
  }
  out.flush();
  if (!out) return common::UnavailableError("writing " + path + " failed (disk full?)");
  return common::Status::Ok();
}

common::Vector2 NearestOnPath(const std::vector<common::Vector2>& path_m,
                              const common::Vector2& p) {
  CAIRN_THROW_UNLESS(!path_m.empty(), "NearestOnPath needs a path");
  common::Vector2 best = path_m.front();
  double best_d2 = (best - p).squaredNorm();
  for (size_t i = 1; i < path_m.size(); ++i) {
    const common::Vector2 a = path_m[i - 1], ab = path_m[i] - a;
    const double len2 = ab.squaredNorm();
    const double t = len2 > 0.0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
    const common::Vector2 q = a + t * ab;
    const double d2 = (q - p).squaredNorm();
    if (d2 < best_d2) {
      best_d2 = d2;
      best = q;
    }
  }
  return best;
}

}  // namespace cairn::mission
