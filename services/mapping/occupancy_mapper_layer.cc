#include "services/mapping/occupancy_mapper_layer.h"

#include "common/check.h"
#include "common/layers.h"
#include "common/yaml_reader.h"

namespace cairn::mapping {

void OccupancyMapperLayerParams::Validate() const {
  grid.Validate();
  CAIRN_THROW_UNLESS(publish_period_s > 0,
                     "occupancy_period_s must be positive, got " << publish_period_s);
}

OccupancyMapperLayerParams LoadOccupancyMapperLayerParams(common::YamlMap& map) {
  OccupancyMapperLayerParams p;
  p.grid = ReadOccupancyParams(map);
  map.Finish();
  return p;
}

void LoadOccupancySection(common::YamlMap& map, OccupancyParams* grid, ObstacleBandParams* band) {
  if (map.Has("band")) {
    common::YamlMap child = map.Child("band");
    *band = LoadObstacleBandParams(child);
  }
  *grid = LoadOccupancyMapperLayerParams(map).grid;
}

OccupancyMapperLayer::OccupancyMapperLayer(const OccupancyMapperLayerParams& params)
    : params_((params.Validate(), params)), grid_(params.grid) {}

const std::string& OccupancyMapperLayer::name() const {
  static const std::string kName = "occupancy";
  return kName;
}

LayerSchedule OccupancyMapperLayer::schedule() const {
  LayerSchedule s;
  s.publish_period_s = params_.publish_period_s;
  return s;
}

std::vector<std::string> OccupancyMapperLayer::OwnedLayers() const {
  return {layers::kOccupancy, layers::kOccupancyLogOdds};
}

void OccupancyMapperLayer::OnObstacleBand(const std::vector<PlanarRay>& rays,
                                          RevolutionReport* report) {
  report->occupancy = grid_.InsertRays(rays);
}

std::vector<GridOutput> OccupancyMapperLayer::GridOutputs() const {
  // The 0..100 layer is derived from the log-odds: published, not written.
  return {{layers::kOccupancy, GridEncoding::kOccupancy, true, false},
          {layers::kOccupancyLogOdds, GridEncoding::kFloat, true, true}};
}

std::optional<common::GridMap> OccupancyMapperLayer::ExportGrids() const {
  const common::GridGeometry bounds = grid_.ObservedBounds();
  if (bounds.size_x <= 0 || bounds.size_y <= 0) return std::nullopt;
  return grid_.Export(bounds);
}

}  // namespace cairn::mapping
