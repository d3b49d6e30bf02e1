#include "services/mapping/mapper_core.h"

#include <chrono>
#include <cmath>
#include <limits>

#include "common/check.h"
#include "common/layers.h"

namespace cairn::mapping {
namespace {

double Seconds(std::chrono::steady_clock::time_point a, std::chrono::steady_clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

// Equal sizes, and resolution and origin equal within a micrometre (a grid that went through a
// store and back).
bool SameGrid(const common::GridGeometry& a, const common::GridGeometry& b) {
  constexpr double kTolerance = 1e-6;
  return a.size_x == b.size_x && a.size_y == b.size_y &&
         std::abs(a.resolution_m - b.resolution_m) < kTolerance &&
         std::abs(a.origin.x_m - b.origin.x_m) < kTolerance &&
         std::abs(a.origin.y_m - b.origin.y_m) < kTolerance &&
         std::abs(a.origin.yaw_rad - b.origin.yaw_rad) < kTolerance;
}

}  // namespace

void MapperCoreParams::Validate() const {
  terrain.Validate();
  if (occupancy_enabled) {
    occupancy.Validate();
    band.Validate();
  }
  if (octomap_enabled) octomap.Validate();
  if (dynamic_enabled) {
    dynamic.Validate();
    if (static_map_path.empty()) dynamic_extent.Validate();
  }
}

MapperCore::MapperCore(const MapperCoreParams& params)
    : params_(params), terrain_(params.terrain), band_(params.band) {
  params_.Validate();
  if (params_.occupancy_enabled) occupancy_ = std::make_unique<OccupancyGrid>(params_.occupancy);
  if (params_.octomap_enabled) octomap_ = std::make_unique<OctomapLayer>(params_.octomap);
  if (params_.dynamic_enabled) {
    common::GridMap static_map;
    if (!params_.static_map_path.empty()) {
      auto loaded = LoadStaticMap(params_.static_map_path);
      if (!loaded.ok()) throw std::invalid_argument(loaded.status().ToString());
      static_map = std::move(loaded.value());
    } else {
      CAIRN_THROW_UNLESS(params_.dynamic_extent.size_x > 0 && params_.dynamic_extent.size_y > 0,
                         "dynamic layers need a static map or an extent");
      static_map = common::GridMap(params_.dynamic_extent);
      static_map.AddLayer(layers::kStaticMap);
    }
    dynamic_ = std::make_unique<DynamicLayers>(static_map, params_.dynamic);
    dynamic_initial_ = std::make_unique<DynamicLayers>(*dynamic_);
    // The remembered long-term layer (OP_RESET goes back to the static map alone).
    if (params_.long_term_restore) {
      const common::GridMap& restore = *params_.long_term_restore;
      if (!restore.HasLayer(layers::kLongTerm)) {
        long_term_restore_status_ =
            common::InvalidArgumentError("the stored map has no long_term layer");
      } else if (!SameGrid(restore.geometry(), dynamic_->geometry())) {
        long_term_restore_status_ = common::InvalidArgumentError(
            "the stored long-term layer lies on another grid than the static map (was the "
            "static map changed?)");
      } else {
        // The same grid up to the rounding of a store round trip: take the static map's.
        common::GridMap same(dynamic_->geometry());
        same.AddLayer(layers::kLongTerm) = restore.at(layers::kLongTerm);
        dynamic_->SetLongTerm(same, layers::kLongTerm);
      }
      params_.long_term_restore.reset();  // used once; do not keep a copy
    }
  }
}

RevolutionReport MapperCore::ProcessRevolution(const common::LidarRevolution& revolution,
                                               const RobotContext& robot, double time_s) {
  using Clock = std::chrono::steady_clock;
  RevolutionReport report;
  const auto t0 = Clock::now();
  report.terrain = terrain_.Integrate(revolution, time_s);
  const auto t1 = Clock::now();
  report.derived = terrain_.UpdateDerived(robot);
  const auto t2 = Clock::now();
  if (occupancy_) {
    // The obstacle band is measured from the ground under the robot when the terrain knows it.
    double ground_z = std::numeric_limits<double>::quiet_NaN();
    if (robot.xy_m) {
      common::GridGeometry g;
      g.resolution_m = params_.terrain.resolution_m;
      g.size_x = g.size_y = 3;
      g.origin = {std::floor(robot.xy_m->x() / g.resolution_m - 1) * g.resolution_m,
                  std::floor(robot.xy_m->y() / g.resolution_m - 1) * g.resolution_m, 0.0};
      const common::GridMap under = terrain_.Export({layers::kElevation}, g);
      double sum = 0;
      int n = 0;
      for (int64_t i = 0; i < under.at(layers::kElevation).size(); ++i) {
        const float h = under.at(layers::kElevation).data()[i];
        if (!std::isnan(h)) {
          sum += h;
          ++n;
        }
      }
      if (n > 0) ground_z = sum / n;
    }
    const std::vector<PlanarRay>& rays = band_.Project(revolution, ground_z, &report.band);
    report.occupancy = occupancy_->InsertRays(rays);
    if (dynamic_) pending_rays_.insert(pending_rays_.end(), rays.begin(), rays.end());
  }
  const auto t3 = Clock::now();
  report.elevation_s = Seconds(t0, t1);
  report.derived_s = Seconds(t1, t2);
  report.occupancy_s = Seconds(t2, t3);
  ++revolutions_;
  return report;
}

OccupancyInsertStats MapperCore::ProcessScan(const common::LaserScan& scan) {
  if (dynamic_) pending_scans_.push_back(scan);
  if (!occupancy_) return {};
  return occupancy_->InsertScan(scan);
}

DynamicUpdateStats MapperCore::StepDynamic() {
  if (!dynamic_) return {};
  const DynamicUpdateStats stats = dynamic_->Update(pending_scans_, pending_rays_);
  pending_scans_.clear();
  pending_rays_.clear();
  return stats;
}

void MapperCore::ClearShortTerm() {
  if (!dynamic_) return;
  const common::GridGeometry& g = dynamic_->geometry();
  for (int iy = 0; iy < g.size_y; ++iy) {
    for (int ix = 0; ix < g.size_x; ++ix) dynamic_->SetShortTermCost({ix, iy}, kCostUnknown);
  }
}

OctomapInsertStats MapperCore::InsertOctomap(const common::LidarRevolution& revolution) {
  if (!octomap_) return {};
  return octomap_->InsertRevolution(revolution);
}

void MapperCore::Reset() {
  terrain_.Clear();
  if (occupancy_) occupancy_->Clear();
  if (octomap_) octomap_ = std::make_unique<OctomapLayer>(params_.octomap);
  if (dynamic_) *dynamic_ = *dynamic_initial_;
  pending_scans_.clear();
  pending_rays_.clear();
  revolutions_ = 0;
}

}  // namespace cairn::mapping
