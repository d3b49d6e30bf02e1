#pragma once

#include <cstdint>
#include <memory>
#include <optional>

#include "common/point_cloud.h"
#include "common/status.h"
#include "services/mapping/dynamic_layers.h"
#include "services/mapping/occupancy_band.h"
#include "services/mapping/occupancy_grid.h"
#include "services/mapping/octomap_layer.h"
#include "services/mapping/terrain_map.h"

/// @file
/// MapperCore: every layer one robot's mapper keeps, fed with lidar revolutions and planar
/// scans whose sensor poses are already resolved. No transport: the LCM service, the offline
/// replay and the benchmark all drive this class, so they build the same maps.

namespace cairn::mapping {

struct MapperCoreParams {
  TerrainMapParams terrain;
  bool occupancy_enabled{true};
  OccupancyParams occupancy;
  ObstacleBandParams band;
  bool octomap_enabled{true};
  OctomapLayerParams octomap;
  /// Seed 001's dynamic layers (static, short-term, long-term, final) from the planar laser
  /// and the lidar's obstacle band. Their grid is the static map's when one is given, else
  /// dynamic_extent with an all-unknown static map.
  bool dynamic_enabled{false};
  DynamicLayersParams dynamic;
  std::string static_map_path;  ///< a map_server YAML file
  common::GridGeometry dynamic_extent;
  /// A stored long-term layer (layers::kLongTerm, 0..100, NaN unknown) that replaces the one
  /// copied from the static map at start: seed 001's memory across runs. It must lie on the
  /// static map's grid; otherwise it is ignored (long_term_restore_status() says why).
  std::optional<common::GridMap> long_term_restore;

  /// @throws std::invalid_argument naming a bad field.
  void Validate() const;
};

/// What one revolution did, with the time each stage took (wall clock, seconds).
struct RevolutionReport {
  IntegrateStats terrain;
  DerivedStats derived;
  ObstacleBandStats band;
  OccupancyInsertStats occupancy;
  double elevation_s{0.0};
  double derived_s{0.0};
  double occupancy_s{0.0};
};

class MapperCore {
 public:
  /// @throws std::invalid_argument if the params are invalid or the static map cannot be
  /// loaded.
  explicit MapperCore(const MapperCoreParams& params);
  MapperCore(const MapperCore&) = delete;
  MapperCore& operator=(const MapperCore&) = delete;

  /// Elevation, derived terrain layers and the occupancy from the revolution's obstacle band.
  /// `time_s` stamps last_seen. The OctoMap is separate (InsertOctomap): it costs far more per
  /// revolution, so callers feed it at their own rate.
  RevolutionReport ProcessRevolution(const common::LidarRevolution& revolution,
                                     const RobotContext& robot, double time_s);
  /// A planar laser scan into the occupancy grid.
  OccupancyInsertStats ProcessScan(const common::LaserScan& scan);
  /// A revolution into the OctoMap (no-op when disabled).
  OctomapInsertStats InsertOctomap(const common::LidarRevolution& revolution);
  /// One step of the dynamic layers from the scans and band rays received since the last step
  /// (no-op when disabled).
  DynamicUpdateStats StepDynamic();
  /// Forgets the short-term layer (every cell unknown again).
  void ClearShortTerm();

  TerrainMap& terrain() { return terrain_; }
  const TerrainMap& terrain() const { return terrain_; }
  OccupancyGrid* occupancy() { return occupancy_.get(); }
  const OccupancyGrid* occupancy() const { return occupancy_.get(); }
  OctomapLayer* octomap() { return octomap_.get(); }
  const OctomapLayer* octomap() const { return octomap_.get(); }
  /// Ok when no long-term layer was to be restored or it was; else why it was ignored.
  const common::Status& long_term_restore_status() const { return long_term_restore_status_; }
  DynamicLayers* dynamic() { return dynamic_.get(); }
  const DynamicLayers* dynamic() const { return dynamic_.get(); }
  const MapperCoreParams& params() const { return params_; }
  int64_t revolutions() const { return revolutions_; }

  /// Forgets every measurement (profiles are kept).
  void Reset();

 private:
  MapperCoreParams params_;
  TerrainMap terrain_;
  ObstacleBand band_;  // keeps its buffers from one revolution to the next
  std::unique_ptr<OccupancyGrid> occupancy_;
  std::unique_ptr<OctomapLayer> octomap_;
  std::unique_ptr<DynamicLayers> dynamic_;
  std::unique_ptr<DynamicLayers> dynamic_initial_;  // from the static map alone, for Reset
  common::Status long_term_restore_status_;
  std::vector<common::LaserScan> pending_scans_;
  std::vector<PlanarRay> pending_rays_;
  int64_t revolutions_{0};
};

}  // namespace cairn::mapping
