#pragma once

#include <string>
#include <vector>

#include "services/mapping/mapper_layer.h"
#include "services/mapping/occupancy_grid.h"

/// @file
/// The 2-D log-odds occupancy as a mapper layer ("occupancy"): the lidar's obstacle band and
/// the planar laser's scans into an OccupancyGrid. Publishes `occupancy` (0..100, -1 unknown)
/// and `occupancy_logodds` over the observed bounds when the grid changed.

namespace cairn::mapping {

struct OccupancyMapperLayerParams {
  OccupancyParams grid;
  double publish_period_s{1.0};  ///< the mapper's occupancy_period_s

  /// @throws std::invalid_argument naming a bad field.
  void Validate() const;
};

/// Reads the grid keys of an `occupancy` section (ReadOccupancyParams) and finishes it: the
/// caller reads `enabled` and `band` first. The period is the top-level occupancy_period_s.
/// @throws common::ConfigError naming the file and line of a bad or unknown key.
OccupancyMapperLayerParams LoadOccupancyMapperLayerParams(common::YamlMap& map);

/// Reads an `occupancy` section (`enabled` excepted): its `band` subsection into `band` (the
/// mapper's obstacle band is configured there), the rest into `grid`.
void LoadOccupancySection(common::YamlMap& map, OccupancyParams* grid, ObstacleBandParams* band);

class OccupancyMapperLayer : public MapperLayer {
 public:
  /// @throws std::invalid_argument if the params are invalid.
  explicit OccupancyMapperLayer(const OccupancyMapperLayerParams& params);

  const std::string& name() const override;
  uint32_t inputs() const override { return kObstacleBand | kPlanarScans; }
  LayerSchedule schedule() const override;
  std::vector<std::string> OwnedLayers() const override;
  void OnObstacleBand(const std::vector<PlanarRay>& rays, RevolutionReport* report) override;
  void OnScan(const common::LaserScan& scan) override { grid_.InsertScan(scan); }
  void Reset() override { grid_.Clear(); }
  std::vector<GridOutput> GridOutputs() const override;
  std::optional<common::GridMap> ExportGrids() const override;
  int64_t version() const override { return grid_.version(); }

  OccupancyGrid& grid() { return grid_; }
  const OccupancyGrid& grid() const { return grid_; }

 private:
  OccupancyMapperLayerParams params_;
  OccupancyGrid grid_;
};

}  // namespace cairn::mapping
