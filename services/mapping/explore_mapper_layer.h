#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "common/point_cloud.h"
#include "services/explore/info_map.h"
#include "services/explore/nbv_mission.h"
#include "services/explore/scan_mesh.h"
#include "services/explore/turret_scan.h"
#include "services/mapping/mapper_layer.h"

/// @file
/// Seed 002's information map as a mapper layer ("explore"): the turret's sweeps (the stream
/// TURRET_SCAN, one vertical line per pan step) assembled into ordered scans, each meshed,
/// scored and added to a 0.3 m information map (C_nc, Q_a, explored, per level) limited to a
/// work area. The parameters are those of an explorer configuration (`explorer_config`, its
/// `nbv` section), so the map is the one cairn-explorer builds from the same sweeps: the layer
/// makes it live on the bus (explore/* on <robot>.MAP.TILES) and stored with the mapper's map by
/// cairn-mapstore like every other layer.
///
/// The assembler is passive: it waits for a line at pan 0 and takes the sweep that follows
/// (whoever asked for it); a sweep broken by lost lines or a moving scanner is dropped, and the
/// next one starts at its own pan 0. A line is placed at the pose the turret reports with it
/// (the scanner's frame turns with the pan, so no single measured mount stands for it), the
/// pose the explorer places it at.

namespace cairn::mapping {

/// One turret line (lcmt_laser_scan on <robot>.TURRET_SCAN): the vertical fan at one pan step.
struct TurretLineReading : SensorReading {
  common::LaserScan line;  ///< sensor_pose: the scanning plane's pose as the turret reports it
  double pan_rad{0.0};
};

struct ExploreMapperLayerParams {
  /// The explorer configuration the map's parameters come from (a path, as given).
  std::string explorer_config;
  /// The work area ("x0,y0 x1,y1 ..."): replaces the configuration's when not empty.
  std::string work_area;
  double publish_period_s{1.0};
  /// Read from explorer_config (and work_area) by LoadExploreMapperLayerParams.
  explore::NbvMissionParams mission;
  bool loaded{false};

  /// @throws std::invalid_argument naming a bad field (no explorer configuration read).
  void Validate() const;
};

/// Reads an `explore` section (explorer_config, work_area, publish_period_s) and the explorer
/// configuration it names: the caller reads `enabled` first. @throws common::ConfigError naming
/// the file and line of a bad or unknown key, or std::invalid_argument for a bad explorer
/// configuration.
ExploreMapperLayerParams LoadExploreMapperLayerParams(common::YamlMap& map);

/// Reads p->explorer_config (its nbv section; p->work_area over its work area) into p->mission.
/// @throws common::ConfigError or std::invalid_argument naming what is wrong.
void ReadExplorerConfig(ExploreMapperLayerParams* p);

class ExploreMapperLayer : public MapperLayer {
 public:
  /// @throws std::invalid_argument if the params are invalid.
  explicit ExploreMapperLayer(const ExploreMapperLayerParams& params);

  const std::string& name() const override;
  uint32_t inputs() const override { return kSensorReadings; }
  LayerSchedule schedule() const override;
  std::vector<std::string> OwnedLayers() const override { return layer_names_; }
  std::vector<std::string> ReadingStreams() const override { return {"TURRET_SCAN"}; }
  void OnReading(const SensorReading& reading) override;
  void Reset() override;
  std::vector<GridOutput> GridOutputs() const override;
  std::optional<common::GridMap> ExportGrids() const override;
  int64_t version() const override { return version_; }
  std::vector<std::string> TakeEvents() override;

  const explore::InfoMap& info_map() const { return info_; }
  /// Whole sweeps integrated, and sweeps dropped (broken or timed out) since the start.
  int scans() const { return scans_; }
  int broken_sweeps() const { return assembler_.restarts() + timeouts_; }

 private:
  ExploreMapperLayerParams params_;
  explore::InfoMap info_;
  explore::TurretScanAssembler assembler_;
  explore::ScanMesh mesh_;
  int scans_{0};
  int timeouts_{0};
  std::vector<std::string> layer_names_;  ///< the map's layers (the levels' included)
  int64_t version_{0};
  std::vector<std::string> events_;
};

}  // namespace cairn::mapping
