#pragma once

#include <cstdint>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "common/grid_map.h"
#include "common/point_cloud.h"
#include "common/status.h"
#include "common/types.h"
#include "services/mapping/occupancy_band.h"
#include "services/mapping/occupancy_grid.h"
#include "services/mapping/terrain_map.h"
#include "services/mapping/traversability.h"

/// @file
/// MapperLayer: the seam through which the mapper grows. A layer says which inputs it takes,
/// which grid layers it owns and when it publishes; MapperCore holds the configured layers in
/// a list and hands each input to the layers that take it, in list order. The service publishes
/// a layer's dense grids (GridOutputs) and writes them with --output without knowing the layer.
/// services/mapping/README.md ("Adding a layer") lists the files a new layer touches.

namespace cairn::mapping {

/// The inputs a layer can take (bits of MapperLayer::inputs()).
enum MapperInput : uint32_t {
  /// OnRevolution: every lidar revolution, sensor poses resolved and bad points dropped, with
  /// the robot's pose at its end.
  kLidarRevolutions = 1u << 0,
  /// OnObstacleBand: each revolution's obstacle band as planar rays, measured from the ground
  /// under the robot (GroundHeightUnder of the first layer that knows it).
  kObstacleBand = 1u << 1,
  /// OnScan: planar laser scans, sensor pose resolved.
  kPlanarScans = 1u << 2,
  /// AdvanceTo: the sensor clock after every revolution, scan and reading (to step at a rate).
  kSensorTime = 1u << 3,
  /// OnReading: readings of the other sensor streams the layer names (ReadingStreams: a sonar's
  /// pings, ...), sensor pose resolved; lcm/mapper_streams.cc converts their messages.
  kSensorReadings = 1u << 4,
};

/// A reading of a sensor stream beyond the fixed inputs above, made from its message by the
/// stream's converter (lcm/mapper_streams.cc): a layer that takes the stream casts it to the type
/// that converter makes (declared in the layer's header).
struct SensorReading {
  SensorReading() = default;
  virtual ~SensorReading() = default;
  SensorReading(const SensorReading&) = default;
  SensorReading& operator=(const SensorReading&) = default;

  std::string stream;  ///< "SONAR": the reading came on <robot>.SONAR
  int64_t utime{0};
  common::Pose3 sensor_pose;  ///< as reported; MapperInputs resolves it per pose_source
};

/// What one revolution did, with the time each stage took (wall clock, seconds).
struct RevolutionReport {
  IntegrateStats terrain;
  DerivedStats derived;
  ObstacleBandStats band;
  OccupancyInsertStats occupancy;
  double elevation_s{0.0};
  double derived_s{0.0};
  double occupancy_s{0.0};  ///< the obstacle band and the layers that take it
  /// Layers due for this revolution that run on a thread of their own (LayerSchedule::
  /// own_thread) while MapperCore defers them: the caller feeds them (FeedDeferred).
  std::vector<class MapperLayer*> deferred;
};

/// A revolution as the layers take it.
struct RevolutionInput {
  const common::LidarRevolution& revolution;
  const RobotContext& robot;  ///< the robot at the revolution's end
  double time_s;              ///< sensor time of its last slice
};

/// When a layer takes revolutions and publishes.
struct LayerSchedule {
  double publish_period_s{1.0};  ///< the service publishes the layer this often (if changed)
  int every_revolutions{1};      ///< takes every n-th revolution (counted since start)
  /// Costly per revolution: a live mapper feeds it on a thread of its own, the newest due
  /// revolution winning; the layer is then read (published, written, reset) under a lock.
  bool own_thread{false};
};

/// How a dense grid of a layer goes out: float32 tiles on <robot>.MAP.TILES or occupancy tiles
/// (int8 0..100, -1 unknown) on <robot>.MAP.OCCUPANCY, manifests on <robot>.MAP.MANIFEST.
enum class GridEncoding { kFloat, kOccupancy };

struct GridOutput {
  std::string name;  ///< the layer's name in ExportGrids()
  GridEncoding encoding{GridEncoding::kFloat};
  bool published{true};  ///< sent on the bus
  bool written{true};    ///< written by WriteMapperOutputs (raw float32)
};

class MapperLayer {
 public:
  MapperLayer() = default;
  virtual ~MapperLayer() = default;
  MapperLayer(const MapperLayer&) = delete;
  MapperLayer& operator=(const MapperLayer&) = delete;

  /// The layer's name in the configuration (its YAML section) and in map.yaml.
  virtual const std::string& name() const = 0;
  /// The MapperInput bits it takes.
  virtual uint32_t inputs() const = 0;
  virtual LayerSchedule schedule() const = 0;
  /// The grid layers it owns (published or written under these names).
  virtual std::vector<std::string> OwnedLayers() const = 0;

  // Inputs (called only for the bits in inputs(), from one thread at a time).
  virtual void OnRevolution(const RevolutionInput& /*input*/, RevolutionReport* /*report*/) {}
  virtual void OnObstacleBand(const std::vector<PlanarRay>& /*rays*/,
                              RevolutionReport* /*report*/) {}
  virtual void OnScan(const common::LaserScan& /*scan*/) {}
  virtual void AdvanceTo(int64_t /*utime*/) {}
  /// With kSensorReadings: the streams whose readings it takes, and each reading.
  virtual std::vector<std::string> ReadingStreams() const { return {}; }
  virtual void OnReading(const SensorReading& /*reading*/) {}
  /// World height of the ground under `xy_m`, for layers that map the ground; nullopt else.
  virtual std::optional<double> GroundHeightUnder(const common::Vector2& /*xy_m*/) const {
    return std::nullopt;
  }
  /// Forgets every measurement (OP_RESET).
  virtual void Reset() = 0;
  /// Notable events since the last call, one log line each (a reading layer's sweep done or
  /// dropped); the service logs them after each reading.
  virtual std::vector<std::string> TakeEvents() { return {}; }

  // Outputs.
  /// Dense grids the service publishes and writes; none for layers published their own way
  /// (the terrain's sparse tiles, the OctoMap's stream).
  virtual std::vector<GridOutput> GridOutputs() const { return {}; }
  /// Those grids in one map; nullopt while there is nothing to show.
  virtual std::optional<common::GridMap> ExportGrids() const { return std::nullopt; }
  /// Changes whenever ExportGrids may have changed: the service publishes on a change (and
  /// sends every manifest of the layer then, so receivers hear it is current).
  virtual int64_t version() const { return 0; }
  /// Writes the layer under `dir` and its section of map.yaml to `yaml`. The default writes
  /// the written GridOutputs as raw float32 files (x fastest from the minimum corner).
  virtual common::Status WriteOutputs(const std::string& dir, std::ostream& yaml) const;
};

/// Writes `names` of `map` as `<name>.f32` files under `dir` (a '/' in a name becomes '_') and a
/// map.yaml section `section:` with the grid and the file list.
common::Status WriteGridSection(const std::string& dir, const std::string& section,
                                const common::GridMap& map, const std::vector<std::string>& names,
                                std::ostream& yaml);

}  // namespace cairn::mapping
