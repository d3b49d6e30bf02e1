#include "services/mapping/sonar_mapper_layer.h"

#include <algorithm>
#include <cmath>

#include "common/check.h"
#include "common/layers.h"
#include "common/yaml_reader.h"

namespace cairn::mapping {

OccupancyParams SonarMapperLayerParams::DefaultGrid() {
  OccupancyParams g;
  g.resolution_m = 0.25;
  g.size_x_cells = 8000;
  g.size_y_cells = 8000;
  g.origin_x_m = -1000.0;
  g.origin_y_m = -1000.0;
  g.max_range_m = 1000.0;  // the ping says what its range is
  g.no_return_range_m = 1000.0;
  g.min_range_m = 0.0;
  return g;
}

void SonarMapperLayerParams::Validate() const {
  grid.Validate();
  CAIRN_THROW_UNLESS(peaks.min_peak_height >= 1 && peaks.min_peak_height <= 255,
                     "sonar.min_peak_height must be in [1, 255]");
  CAIRN_THROW_UNLESS(peaks.min_peak_distance >= 1 && peaks.min_peak_distance <= 1000,
                     "sonar.min_peak_distance must be in [1, 1000]");
  CAIRN_THROW_UNLESS(std::isfinite(publish_period_s) && publish_period_s > 0.0,
                     "sonar.publish_period_s must be > 0");
  CAIRN_THROW_UNLESS(std::isfinite(vehicle_clear_radius_m) && vehicle_clear_radius_m >= 0.0 &&
                         vehicle_clear_radius_m <= 20.0,
                     "sonar.vehicle_clear_radius_m must be in [0, 20]");
  CAIRN_THROW_UNLESS(
      std::isfinite(vehicle_centre_behind_head_m) && std::abs(vehicle_centre_behind_head_m) <= 20.0,
      "sonar.vehicle_centre_behind_head_m must be in [-20, 20]");
  CAIRN_THROW_UNLESS(
      std::isfinite(beam_width_deg) && beam_width_deg >= 0.0 && beam_width_deg <= 30.0,
      "sonar.beam_width_deg must be in [0, 30]");
}

SonarMapperLayerParams LoadSonarMapperLayerParams(common::YamlMap& map) {
  SonarMapperLayerParams p;
  map.Get("min_peak_height", &p.peaks.min_peak_height);
  map.Get("min_peak_distance", &p.peaks.min_peak_distance);
  map.Get("verify_shadow", &p.peaks.verify_shadow);
  map.Get("publish_period_s", &p.publish_period_s);
  map.Get("vehicle_clear_radius_m", &p.vehicle_clear_radius_m);
  map.Get("vehicle_centre_behind_head_m", &p.vehicle_centre_behind_head_m);
  map.Get("beam_width_deg", &p.beam_width_deg);
  p.grid = ReadOccupancyParams(map, SonarMapperLayerParams::DefaultGrid());
  map.Finish();
  return p;
}

std::vector<PlanarRay> SonarPingRays(const SonarReading& ping, const SonarPeakParams& peaks,
                                     std::vector<int>* obstacle_bins, double beam_width_rad,
                                     double cell_m) {
  std::vector<PlanarRay> rays;
  const int bins = static_cast<int>(ping.bins.size());
  if (bins == 0 || !(ping.range_max_m > ping.range_min_m)) return rays;
  const double bin_m = (ping.range_max_m - ping.range_min_m) / bins;
  const common::Vector2 origin = ping.sensor_pose.position_m.head<2>();
  const Eigen::Vector3d along = ping.sensor_pose.orientation * Eigen::Vector3d::UnitX();
  const double yaw = std::atan2(along.y(), along.x());
  const common::Vector2 dir(std::cos(yaw), std::sin(yaw));
  const std::vector<int> found = SonarObstacleBins(ping.bins, peaks);
  if (obstacle_bins != nullptr) *obstacle_bins = found;
  if (found.empty()) {
    rays.push_back({origin, origin + ping.range_max_m * dir, false});
    return rays;
  }
  // Free up to the nearest peak; every peak an obstacle at its bin's near edge.
  for (size_t i = 0; i < found.size(); ++i) {
    const double range_m = ping.range_min_m + found[i] * bin_m;
    const common::Vector2 at = origin + range_m * dir;
    rays.push_back({i == 0 ? origin : at, at, true});
    // Across the beam's width: a point a cell apart along the arc at that range.
    const int side = beam_width_rad > 0.0 && cell_m > 0.0
                         ? static_cast<int>(std::floor(0.5 * beam_width_rad * range_m / cell_m))
                         : 0;
    for (int k = 1; k <= side; ++k) {
      for (int sign : {-1, 1}) {
        const double a = yaw + sign * k * cell_m / std::max(range_m, cell_m);
        const common::Vector2 p = origin + range_m * common::Vector2(std::cos(a), std::sin(a));
        rays.push_back({p, p, true});
      }
    }
  }
  return rays;
}

SonarMapperLayer::SonarMapperLayer(const SonarMapperLayerParams& params)
    : params_((params.Validate(), params)), grid_(params.grid) {}

const std::string& SonarMapperLayer::name() const {
  static const std::string kName = "sonar";
  return kName;
}

LayerSchedule SonarMapperLayer::schedule() const {
  LayerSchedule s;
  s.publish_period_s = params_.publish_period_s;
  return s;
}

void SonarMapperLayer::OnReading(const SensorReading& reading) {
  const auto* ping = dynamic_cast<const SonarReading*>(&reading);
  if (ping == nullptr) return;
  std::vector<int> found;
  std::vector<PlanarRay> rays =
      SonarPingRays(*ping, params_.peaks, &found, params_.beam_width_deg * M_PI / 180.0,
                    grid_.params().resolution_m);
  grid_.InsertRays(rays);
  if (params_.vehicle_clear_radius_m > 0.0) {
    // The vehicle's own water: the cells round its centre that nothing has observed yet read
    // free (one miss). Observed cells keep what the beams made of them: a rock seen beside the
    // hull stays a rock.
    const Eigen::Vector3d beam = ping->sensor_pose.orientation * Eigen::Vector3d::UnitX();
    const double hull_yaw = std::atan2(beam.y(), beam.x()) - ping->pan_rad;
    const common::Vector2 centre = ping->sensor_pose.position_m.head<2>() -
                                   params_.vehicle_centre_behind_head_m *
                                       common::Vector2(std::cos(hull_yaw), std::sin(hull_yaw));
    // Every cell whose centre lies within the radius.
    const double r = params_.vehicle_clear_radius_m;
    const auto lo = grid_.CellAt(centre - common::Vector2(r, r));
    const auto hi = grid_.CellAt(centre + common::Vector2(r, r));
    if (lo && hi) {
      for (int iy = std::min(lo->iy, hi->iy); iy <= std::max(lo->iy, hi->iy); ++iy) {
        for (int ix = std::min(lo->ix, hi->ix); ix <= std::max(lo->ix, hi->ix); ++ix) {
          const common::CellIndex cell{ix, iy};
          if ((grid_.geometry().CenterOf(cell) - centre).norm() > r) continue;
          if (std::isnan(grid_.LogOdds(cell))) grid_.SetLogOdds(cell, grid_.params().miss_logodds);
        }
      }
    }
  }
  SonarDetection detection;
  detection.utime = ping->utime;
  detection.pan_rad = ping->pan_rad;
  detection.head_m = ping->sensor_pose.position_m;
  const Eigen::Vector3d along = ping->sensor_pose.orientation * Eigen::Vector3d::UnitX();
  detection.beam_yaw_rad = std::atan2(along.y(), along.x());
  detection.range_max_m = ping->range_max_m;
  detection.bins = found;
  if (!ping->bins.empty()) {
    const double bin_m = (ping->range_max_m - ping->range_min_m) / ping->bins.size();
    const common::Vector2 dir(std::cos(detection.beam_yaw_rad), std::sin(detection.beam_yaw_rad));
    for (int bin : found) {
      detection.points.push_back(detection.head_m.head<2>() +
                                 (ping->range_min_m + bin * bin_m) * dir);
    }
  }
  if (detections_.size() >= kMaxPendingDetections) {
    detections_.pop_front();
    ++dropped_detections_;
  }
  detections_.push_back(std::move(detection));
  ++pings_;
  last_obstacles_ = static_cast<int>(found.size());
  obstacles_ += last_obstacles_;
  if (pings_ == 1) {
    events_.push_back("first ping mapped: " + std::to_string(found.size()) + " obstacle bins of " +
                      std::to_string(ping->bins.size()));
  }
}

void SonarMapperLayer::Reset() {
  grid_.Clear();
  detections_.clear();
  pings_ = 0;
  obstacles_ = 0;
  last_obstacles_ = 0;
}

std::vector<GridOutput> SonarMapperLayer::GridOutputs() const {
  return {{kSonarOccupancy, GridEncoding::kOccupancy, true, false},
          {kSonarLogOdds, GridEncoding::kFloat, true, true}};
}

std::optional<common::GridMap> SonarMapperLayer::ExportGrids() const {
  const common::GridGeometry bounds = grid_.ObservedBounds();
  if (bounds.size_x <= 0 || bounds.size_y <= 0) return std::nullopt;
  common::GridMap exported = grid_.Export(bounds);
  common::GridMap out(exported.geometry());
  out.AddLayer(kSonarOccupancy, std::move(exported.at(layers::kOccupancy)));
  out.AddLayer(kSonarLogOdds, std::move(exported.at(layers::kOccupancyLogOdds)));
  return out;
}

std::vector<SonarDetection> SonarMapperLayer::TakeDetections() {
  std::vector<SonarDetection> out(std::make_move_iterator(detections_.begin()),
                                  std::make_move_iterator(detections_.end()));
  detections_.clear();
  return out;
}

std::vector<std::string> SonarMapperLayer::TakeEvents() {
  std::vector<std::string> out;
  out.swap(events_);
  return out;
}

}  // namespace cairn::mapping
