#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "common/point_cloud.h"
#include "common/status.h"
#include "services/mapping/mapper_layer.h"
#include "services/mapping/mapper_layers.h"
#include "services/mapping/occupancy_band.h"

/// @file
/// MapperCore: the layers one robot's mapper keeps (configured by MapperCoreParams,
/// mapper_layers.h), fed with lidar revolutions and planar scans
/// whose sensor poses are already resolved (MapperInputs). The core holds the configured layers
/// in a list (MapperLayer, mapper_layer.h) and hands each input to the layers that take it, in
/// list order; it computes the obstacle band once per revolution for the layers that take it.
/// No transport: the LCM service, the offline replay and the benchmark all drive this class, so
/// they build the same maps.

namespace cairn::mapping {

class MapperCore {
 public:
  /// Builds the listed layers. @throws std::invalid_argument if the params are invalid or a
  /// layer cannot be built (the dynamic layers' static map cannot be loaded).
  explicit MapperCore(const MapperCoreParams& params);
  MapperCore(const MapperCore&) = delete;
  MapperCore& operator=(const MapperCore&) = delete;

  /// Adds a layer at the end of the list (a layer built elsewhere: tests, tools).
  /// @throws std::invalid_argument for a null layer or a name already listed.
  void AddLayer(std::unique_ptr<MapperLayer> layer);

  /// The revolution to the layers that take revolutions (those due, per their schedule), its
  /// obstacle band to those that take the band, then the sensor clock to its last slice's time.
  /// `time_s` stamps last_seen.
  RevolutionReport ProcessRevolution(const common::LidarRevolution& revolution,
                                     const RobotContext& robot, double time_s);
  /// A planar laser scan to the layers that take scans, then the sensor clock to its time.
  void ProcessScan(const common::LaserScan& scan);
  /// A reading of another sensor stream to the layers that take its stream, then the sensor
  /// clock to its time.
  void ProcessReading(const SensorReading& reading);
  /// The sensor clock to the layers that take it.
  void AdvanceTo(int64_t utime);
  /// Every stream whose readings a listed layer takes (the service subscribes to them).
  std::vector<std::string> ReadingStreams() const;

  /// With true, layers that run on a thread of their own (LayerSchedule::own_thread) are not
  /// fed by ProcessRevolution but listed in RevolutionReport::deferred for the caller to feed
  /// (FeedDeferred) on that thread. Default false: every layer runs inline.
  void set_defer_own_thread_layers(bool defer) { defer_own_thread_ = defer; }
  /// Feeds a deferred layer a revolution (on the caller's thread, under the caller's lock).
  static void FeedDeferred(MapperLayer* layer, const common::LidarRevolution& revolution,
                           const RobotContext& robot, double time_s);

  const std::vector<std::unique_ptr<MapperLayer>>& layers() const { return layers_; }
  /// The listed layer of that name, or nullptr.
  MapperLayer* FindLayer(const std::string& name) const;

  // The built-in layers' state (nullptr when not listed).
  TerrainMap* terrain();
  const TerrainMap* terrain() const;
  OccupancyGrid* occupancy();
  const OccupancyGrid* occupancy() const;
  OctomapLayer* octomap();
  const OctomapLayer* octomap() const;
  DynamicLayers* dynamic();
  const DynamicLayers* dynamic() const;
  /// The dynamic layer's long-term restore status (Ok without one).
  const common::Status& long_term_restore_status() const;

  const MapperCoreParams& params() const { return params_; }
  /// Revolutions processed since start or the last Reset.
  int64_t revolutions() const { return revolutions_; }

  /// Writes every layer under `dir` (created) with map.yaml: a header naming `robot` and the
  /// `revolutions` mapped, then each layer's section in list order (MapperLayer::WriteOutputs).
  /// The caller holds the locks of layers that run on their own thread.
  common::Status WriteOutputs(const std::string& dir, const std::string& robot,
                              int64_t revolutions) const;

  /// Forgets every measurement (profiles are kept).
  void Reset();

 private:
  MapperCoreParams params_;
  std::vector<std::unique_ptr<MapperLayer>> layers_;
  ObstacleBand band_;  // keeps its buffers from one revolution to the next
  bool takes_band_{false};
  bool defer_own_thread_{false};
  int64_t revolutions_{0};
  int64_t revolutions_seen_{0};  // never reset: the schedule's every_revolutions counts these
};

}  // namespace cairn::mapping
