#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "common/status.h"
#include "services/mapping/dynamic_layers.h"
#include "services/mapping/mapper_layer.h"

/// @file
/// Seed 001's dynamic layers as a mapper layer ("dynamic"): the static, short-term, long-term
/// and final layers (DynamicLayers) from the planar laser's scans and the lidar's obstacle
/// band, stepped at update_hz on sensor time (so a replay steps alike). Publishes short_term,
/// long_term and final as occupancy tiles at every step (their manifests are the map's
/// heartbeat for a navigator planning on the final layer).

namespace cairn::mapping {

struct DynamicMapperLayerParams {
  DynamicLayersParams layers;
  /// A map_server YAML file whose map is the static layer and the grid of every layer; empty:
  /// `extent`, with an all-unknown static layer.
  std::string static_map_path;
  common::GridGeometry extent;
  /// A stored long-term layer (layers::kLongTerm, 0..100, NaN unknown) that replaces the one
  /// copied from the static map at start: seed 001's memory across runs. It must lie on the
  /// static map's grid; otherwise it is ignored (long_term_restore_status() says why).
  std::optional<common::GridMap> long_term_restore;
  double publish_period_s{1.0};  ///< the mapper's occupancy_period_s

  /// @throws std::invalid_argument naming a bad field.
  void Validate() const;
};

/// Reads a `dynamic` section's layer keys (static_map, origin_x_m, origin_y_m, size_x_m,
/// size_y_m, resolution_m and the seed 001 keys) and finishes it: the caller reads `enabled`
/// and the long-term store keys first. @throws common::ConfigError naming the file and line of
/// a bad or unknown key.
DynamicMapperLayerParams LoadDynamicMapperLayerParams(common::YamlMap& map);

class DynamicMapperLayer : public MapperLayer {
 public:
  /// @throws std::invalid_argument if the params are invalid or the static map cannot be
  /// loaded.
  explicit DynamicMapperLayer(const DynamicMapperLayerParams& params);

  const std::string& name() const override;
  uint32_t inputs() const override { return kObstacleBand | kPlanarScans | kSensorTime; }
  LayerSchedule schedule() const override;
  std::vector<std::string> OwnedLayers() const override;
  /// Band rays and scans wait for the next step.
  void OnObstacleBand(const std::vector<PlanarRay>& rays, RevolutionReport* report) override;
  void OnScan(const common::LaserScan& scan) override { pending_scans_.push_back(scan); }
  /// One step per update period of sensor time; after a gap, one step and a fresh start.
  void AdvanceTo(int64_t utime) override;
  /// Back to the static map alone (the restored long-term layer is forgotten too).
  void Reset() override;
  std::vector<GridOutput> GridOutputs() const override;
  std::optional<common::GridMap> ExportGrids() const override { return layers_.ToGridMap(); }
  int64_t version() const override { return version_; }

  /// One step now from what waited (AdvanceTo calls it at the rate).
  DynamicUpdateStats Step();
  /// Forgets the short-term layer (every cell unknown again).
  void ClearShortTerm();
  /// Ok when no long-term layer was to be restored or it was; else why it was ignored.
  const common::Status& long_term_restore_status() const { return long_term_restore_status_; }
  DynamicLayers& layers() { return layers_; }
  const DynamicLayers& layers() const { return layers_; }

 private:
  DynamicMapperLayerParams params_;
  DynamicLayers layers_;
  std::unique_ptr<DynamicLayers> initial_;  // from the static map alone, for Reset
  common::Status long_term_restore_status_;
  std::vector<common::LaserScan> pending_scans_;
  std::vector<PlanarRay> pending_rays_;
  int64_t next_step_utime_{0};
  int64_t version_{0};
};

}  // namespace cairn::mapping
