#include "services/mapping/occupancy_band.h"

#include <algorithm>
#include <cmath>

#include "common/check.h"
#include "common/yaml_reader.h"

namespace cairn::mapping {

void ObstacleBandParams::Validate() const {
  CAIRN_THROW_UNLESS(
      std::isfinite(min_height_m) && std::isfinite(max_height_m) && max_height_m > min_height_m,
      "obstacle band needs min_height_m < max_height_m, got " << min_height_m << " and "
                                                              << max_height_m);
  CAIRN_THROW_UNLESS(azimuth_bins >= 8 && azimuth_bins <= 1 << 20,
                     "obstacle band azimuth_bins must be in [8, 2^20], got " << azimuth_bins);
  CAIRN_THROW_UNLESS(std::isfinite(min_range_m) && min_range_m >= 0.0 &&
                         std::isfinite(max_range_m) && max_range_m > min_range_m,
                     "obstacle band needs 0 <= min_range_m < max_range_m");
  CAIRN_THROW_UNLESS(std::isfinite(ground_window_m) && ground_window_m >= 0.0,
                     "obstacle band ground_window_m must be >= 0, got " << ground_window_m);
  CAIRN_THROW_UNLESS(
      std::isfinite(max_ground_slope_rad) && max_ground_slope_rad >= 0.0 &&
          max_ground_slope_rad < M_PI / 2,
      "obstacle band max_ground_slope_rad must be in [0, pi/2), got " << max_ground_slope_rad);
  CAIRN_THROW_UNLESS(std::isfinite(sensor_height_m),
                     "obstacle band sensor_height_m must be finite");
}

namespace {

// atan2 to about 1e-5 rad (a minimax polynomial for atan on [0, 1] plus octant folding): the
// bins are 0.2 deg wide, and the libm call was a third of the projection's time.
double FastAtan2(double y, double x) {
  const double ax = std::abs(x), ay = std::abs(y);
  const double big = std::max(ax, ay);
  if (big == 0.0) return 0.0;
  const double z = std::min(ax, ay) / big;
  const double z2 = z * z;
  double a =
      z * (0.99997726 +
           z2 * (-0.33262347 +
                 z2 * (0.19354346 + z2 * (-0.11643287 + z2 * (0.05265332 + z2 * -0.01172120)))));
  if (ay > ax) a = M_PI / 2 - a;
  if (x < 0.0) a = M_PI - a;
  return y < 0.0 ? -a : a;
}

}  // namespace

ObstacleBand::ObstacleBand(const ObstacleBandParams& params) : params_(params) {
  params_.Validate();
}

const std::vector<PlanarRay>& ObstacleBand::Project(const common::LidarRevolution& revolution,
                                                    double ground_z_m,
                                                    ObstacleBandStats* stats_out) {
  ObstacleBandStats stats;
  TransformPoints(revolution, ground_z_m, &stats);
  SortByBinAndRange();
  ChooseRays(&stats);
  if (stats_out) *stats_out = stats;
  return rays_;
}

void ObstacleBand::TransformPoints(const common::LidarRevolution& revolution, double ground_z_m,
                                   ObstacleBandStats* stats_out) {
  ObstacleBandStats& stats = *stats_out;
  const int bins = params_.azimuth_bins;
  const double tan_slope = std::tan(params_.max_ground_slope_rad);
  const double bins_per_rad = bins / (2.0 * M_PI);
  const double min_range_sq = params_.min_range_m * params_.min_range_m;
  const double max_range_sq = params_.max_range_m * params_.max_range_m;

  // 1. Points in world, with bin and horizontal range around their slice's sensor.
  // Filled field by field: a braced temporary copied in stalled on store forwarding.
  points_.resize(revolution.num_points());
  size_t kept = 0;
  origins_.assign(revolution.slices.size(), common::Vector2::Zero());
  for (size_t si = 0; si < revolution.slices.size(); ++si) {
    const common::LidarSlice& slice = revolution.slices[si];
    const common::Pose3& pose = slice.sensor_pose;
    stats.points += static_cast<int64_t>(slice.points.size());
    if (!pose.position_m.allFinite() || !pose.orientation.coeffs().allFinite() ||
        pose.orientation.norm() < 1e-6) {
      stats.points_invalid += static_cast<int64_t>(slice.points.size());
      continue;
    }
    const Eigen::Matrix3d rotation = pose.orientation.normalized().toRotationMatrix();
    const Eigen::Vector3d& sensor = pose.position_m;
    origins_[si] = sensor.head<2>();
    const double ground =
        std::isnan(ground_z_m) ? sensor.z() - params_.sensor_height_m : ground_z_m;
    for (const common::LidarPoint& p : slice.points) {
      if (!std::isfinite(p.x_m) || !std::isfinite(p.y_m) || !std::isfinite(p.z_m)) {
        ++stats.points_invalid;
        continue;
      }
      const Eigen::Vector3d offset = rotation * Eigen::Vector3d(p.x_m, p.y_m, p.z_m);
      const double range_sq = offset.x() * offset.x() + offset.y() * offset.y();
      if (range_sq < min_range_sq || range_sq > max_range_sq) {
        ++stats.points_out_of_range;
        continue;
      }
      const double range = std::sqrt(range_sq);
      int bin = static_cast<int>((FastAtan2(offset.y(), offset.x()) + M_PI) * bins_per_rad);
      bin = std::clamp(bin, 0, bins - 1);
      Point& out = points_[kept++];
      out.bin = bin;
      out.slice = static_cast<int32_t>(si);
      out.range_m = static_cast<float>(range);
      out.z_m = static_cast<float>(sensor.z() + offset.z());
      out.ground_cap_m = static_cast<float>(ground + range * tan_slope);
      out.x_m = sensor.x() + offset.x();
      out.y_m = sensor.y() + offset.y();
    }
  }
  points_.resize(kept);
}

void ObstacleBand::SortByBinAndRange() {
  const int bins = params_.azimuth_bins;
  // 2. Counting sort by bin into compact records, then by range inside each bin (insertion
  //    sort: a bin holds a few dozen points; ties keep input order).
  start_.assign(static_cast<size_t>(bins) + 1, 0);
  for (const Point& p : points_) ++start_[static_cast<size_t>(p.bin) + 1];
  for (int b = 0; b < bins; ++b) start_[b + 1] += start_[b];
  sorted_.resize(points_.size());
  {
    std::vector<int32_t>& fill = window_;  // reused as scratch here
    fill.assign(start_.begin(), start_.end() - 1);
    for (size_t i = 0; i < points_.size(); ++i) {
      const Point& p = points_[i];
      sorted_[static_cast<size_t>(fill[p.bin]++)] = {p.range_m, p.z_m, p.ground_cap_m,
                                                     static_cast<int32_t>(i)};
    }
  }
  for (int b = 0; b < bins; ++b) {
    for (int32_t k = start_[b] + 1; k < start_[b + 1]; ++k) {
      const Record item = sorted_[k];
      int32_t j = k;
      while (j > start_[b] && sorted_[j - 1].range_m > item.range_m) {
        sorted_[j] = sorted_[j - 1];
        --j;
      }
      sorted_[j] = item;
    }
  }
}

void ObstacleBand::ChooseRays(ObstacleBandStats* stats_out) {
  ObstacleBandStats& stats = *stats_out;
  const int bins = params_.azimuth_bins;
  // 3. Per bin: local ground by a sliding-window minimum over range, then the nearest band
  //    point (hit) or the farthest ground point (free).
  rays_.clear();
  const float window_m = static_cast<float>(params_.ground_window_m);
  for (int b = 0; b < bins; ++b) {
    window_.clear();  // indices into sorted_ with increasing z (a monotonic queue)
    size_t head = 0;
    int32_t farthest_ground = -1;
    int32_t nearest_band = -1;
    for (int32_t k = start_[b]; k < start_[b + 1]; ++k) {
      const Record& p = sorted_[k];
      while (window_.size() > head && sorted_[window_.back()].z_m >= p.z_m) window_.pop_back();
      window_.push_back(k);
      while (sorted_[window_[head]].range_m < p.range_m - window_m) ++head;
      const float ground = std::min(sorted_[window_[head]].z_m, p.ground_cap_m);
      const double height = p.z_m - ground;
      if (height >= params_.min_height_m && height <= params_.max_height_m) {
        nearest_band = p.point;
        break;
      }
      if (height < params_.min_height_m) farthest_ground = p.point;
    }
    const int32_t chosen = nearest_band >= 0 ? nearest_band : farthest_ground;
    if (chosen < 0) continue;
    const Point& p = points_[static_cast<size_t>(chosen)];
    PlanarRay ray;
    ray.origin_m = origins_[p.slice];
    ray.end_m = common::Vector2(p.x_m, p.y_m);
    ray.hit = nearest_band >= 0;
    (ray.hit ? stats.hit_rays : stats.free_rays) += 1;
    rays_.push_back(ray);
  }
}

std::vector<PlanarRay> ProjectObstacleBand(const common::LidarRevolution& revolution,
                                           const ObstacleBandParams& params, double ground_z_m,
                                           ObstacleBandStats* stats) {
  ObstacleBand band(params);
  return band.Project(revolution, ground_z_m, stats);
}

ObstacleBandParams LoadObstacleBandParams(common::YamlMap& b) {
  ObstacleBandParams band;
  b.Get("min_height_m", &band.min_height_m);
  b.Get("max_height_m", &band.max_height_m);
  b.Get("azimuth_bins", &band.azimuth_bins);
  b.Get("min_range_m", &band.min_range_m);
  b.Get("max_range_m", &band.max_range_m);
  b.Get("ground_window_m", &band.ground_window_m);
  b.Get("max_ground_slope_rad", &band.max_ground_slope_rad);
  b.Get("sensor_height_m", &band.sensor_height_m);
  b.Finish();
  return band;
}

}  // namespace cairn::mapping
