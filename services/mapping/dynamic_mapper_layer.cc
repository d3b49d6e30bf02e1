#include "services/mapping/dynamic_mapper_layer.h"

#include <cmath>

#include "common/check.h"
#include "common/layers.h"
#include "common/yaml_reader.h"

namespace cairn::mapping {
namespace {

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

// The static map: the map_server file, or the extent with an all-unknown static layer.
common::GridMap StaticMap(const DynamicMapperLayerParams& params) {
  if (!params.static_map_path.empty()) {
    auto loaded = LoadStaticMap(params.static_map_path);
    if (!loaded.ok()) throw std::invalid_argument(loaded.status().ToString());
    return std::move(loaded.value());
  }
  CAIRN_THROW_UNLESS(params.extent.size_x > 0 && params.extent.size_y > 0,
                     "dynamic layers need a static map or an extent");
  common::GridMap map(params.extent);
  map.AddLayer(layers::kStaticMap);
  return map;
}

}  // namespace

void DynamicMapperLayerParams::Validate() const {
  layers.Validate();
  if (static_map_path.empty()) extent.Validate();
  CAIRN_THROW_UNLESS(publish_period_s > 0,
                     "occupancy_period_s must be positive, got " << publish_period_s);
}

DynamicMapperLayerParams LoadDynamicMapperLayerParams(common::YamlMap& m) {
  DynamicMapperLayerParams p;
  m.Get("static_map", &p.static_map_path);
  double origin_x = -20.0, origin_y = -20.0, size_x = 40.0, size_y = 40.0, res = 0.05;
  m.Get("origin_x_m", &origin_x);
  m.Get("origin_y_m", &origin_y);
  m.Get("size_x_m", &size_x);
  m.Get("size_y_m", &size_y);
  m.Get("resolution_m", &res);
  if (!(res > 0) || !(size_x > 0) || !(size_y > 0)) {
    m.Fail(m.Raw("resolution_m"), "dynamic: resolution and size must be positive");
  }
  p.extent.resolution_m = res;
  p.extent.size_x = static_cast<int>(std::lround(size_x / res));
  p.extent.size_y = static_cast<int>(std::lround(size_y / res));
  p.extent.origin = {origin_x, origin_y, 0.0};
  p.layers = ReadDynamicLayersParams(m);
  m.Finish();
  return p;
}

DynamicMapperLayer::DynamicMapperLayer(const DynamicMapperLayerParams& params)
    : params_((params.Validate(), params)), layers_(StaticMap(params_), params_.layers) {
  initial_ = std::make_unique<DynamicLayers>(layers_);
  // The remembered long-term layer (OP_RESET goes back to the static map alone).
  if (params_.long_term_restore) {
    const common::GridMap& restore = *params_.long_term_restore;
    if (!restore.HasLayer(layers::kLongTerm)) {
      long_term_restore_status_ =
          common::InvalidArgumentError("the stored map has no long_term layer");
    } else if (!SameGrid(restore.geometry(), layers_.geometry())) {
      long_term_restore_status_ = common::InvalidArgumentError(
          "the stored long-term layer lies on another grid than the static map (was the "
          "static map changed?)");
    } else {
      // The same grid up to the rounding of a store round trip: take the static map's.
      common::GridMap same(layers_.geometry());
      same.AddLayer(layers::kLongTerm) = restore.at(layers::kLongTerm);
      layers_.SetLongTerm(same, layers::kLongTerm);
    }
    params_.long_term_restore.reset();  // used once; do not keep a copy
  }
}

const std::string& DynamicMapperLayer::name() const {
  static const std::string kName = "dynamic";
  return kName;
}

LayerSchedule DynamicMapperLayer::schedule() const {
  LayerSchedule s;
  s.publish_period_s = params_.publish_period_s;
  return s;
}

std::vector<std::string> DynamicMapperLayer::OwnedLayers() const {
  return {layers::kStaticMap, layers::kShortTerm, layers::kLongTerm, layers::kFinal};
}

void DynamicMapperLayer::OnObstacleBand(const std::vector<PlanarRay>& rays, RevolutionReport*) {
  pending_rays_.insert(pending_rays_.end(), rays.begin(), rays.end());
}

void DynamicMapperLayer::AdvanceTo(int64_t utime) {
  if (utime <= 0) return;
  const int64_t period = static_cast<int64_t>(std::llround(layers_.update_period_s() * 1e6));
  if (next_step_utime_ == 0) next_step_utime_ = utime + period;
  if (utime < next_step_utime_) return;
  Step();
  next_step_utime_ += period;
  if (next_step_utime_ <= utime) next_step_utime_ = utime + period;
}

DynamicUpdateStats DynamicMapperLayer::Step() {
  const DynamicUpdateStats stats = layers_.Update(pending_scans_, pending_rays_);
  pending_scans_.clear();
  pending_rays_.clear();
  ++version_;
  return stats;
}

void DynamicMapperLayer::ClearShortTerm() {
  const common::GridGeometry& g = layers_.geometry();
  for (int iy = 0; iy < g.size_y; ++iy) {
    for (int ix = 0; ix < g.size_x; ++ix) layers_.SetShortTermCost({ix, iy}, kCostUnknown);
  }
  ++version_;
}

void DynamicMapperLayer::Reset() {
  layers_ = *initial_;
  pending_scans_.clear();
  pending_rays_.clear();
  ++version_;
}

std::vector<GridOutput> DynamicMapperLayer::GridOutputs() const {
  return {{layers::kStaticMap, GridEncoding::kOccupancy, false, true},
          {layers::kShortTerm, GridEncoding::kOccupancy, true, true},
          {layers::kLongTerm, GridEncoding::kOccupancy, true, true},
          {layers::kFinal, GridEncoding::kOccupancy, true, true}};
}

}  // namespace cairn::mapping
