#pragma once

#include <cstdint>
#include <deque>
#include <optional>
#include <string>
#include <vector>

#include "common/layers.h"
#include "services/mapping/mapper_layer.h"
#include "services/mapping/occupancy_grid.h"
#include "services/mapping/sonar_detection.h"

/// @file
/// Seed 004's sonar obstacles as a mapper layer ("sonar"): each ping of the imaging sonar
/// (the stream SONAR, one beam of range bins at the head's angle) is searched for obstacle
/// peaks (sonar_detection.h: mph 110, mpd 2, the shadow check when asked for), and goes into a
/// 2-D log-odds occupancy of its own: free along the beam up to the nearest peak, occupied at
/// every peak (the near edge of its bin); free to range_max when nothing echoes above the
/// threshold. Publishes `sonar/occupancy` (0..100, -1 unknown) and `sonar/occupancy_logodds`.

namespace cairn::mapping {

/// Layer names.
inline constexpr const char* kSonarOccupancy = layers::kSonarOccupancy;
inline constexpr char kSonarLogOdds[] = "sonar/occupancy_logodds";

/// One sonar ping (lcmt_sonar_ping on <robot>.SONAR, checked by its converter).
struct SonarReading : SensorReading {
  double pan_rad{0.0};  ///< the head's angle (the pose already points along the beam)
  double range_min_m{0.0};
  double range_max_m{50.0};
  std::vector<uint8_t> bins;
};

/// What one ping showed (published per ping as lcmt_sonar_detection).
struct SonarDetection {
  int64_t utime{0};
  double pan_rad{0.0};
  common::Vector3 head_m{common::Vector3::Zero()};
  double beam_yaw_rad{0.0};
  double range_max_m{0.0};
  std::vector<int> bins;                ///< verified peaks, nearest first
  std::vector<common::Vector2> points;  ///< world frame, at each bin's near edge
};

struct SonarMapperLayerParams {
  OccupancyParams grid = DefaultGrid();
  SonarPeakParams peaks;
  double publish_period_s{1.0};
  /// > 0: after every ping the cells nothing has observed in a disc of this radius round the
  /// vehicle's centre read free (one miss). The centre lies vehicle_centre_behind_head_m behind
  /// the head along the hull (the head's heading less its pan). This is the water the vehicle
  /// is in, which a nose-mounted head never sees: planners that treat unknown cells as obstacles
  /// then find the vehicle's own cells free. Observed cells keep what the beams made of them.
  double vehicle_clear_radius_m{0.0};
  /// > 0: each peak marks the arc of the beam's horizontal width at its range, not one point
  /// (the thesis's ray fan has no width; a Miniking's beam is 3 deg wide): an echo comes from
  /// anywhere across the beam, and faces seen at a slant fill in between beams.
  double beam_width_deg{0.0};
  double vehicle_centre_behind_head_m{0.0};

  /// The default grid: 0.25 m cells over 2 km round the site origin, OctoMap's log-odds.
  static OccupancyParams DefaultGrid();
  /// @throws std::invalid_argument naming a bad field.
  void Validate() const;
};

/// Reads a `sonar` section (the grid keys of occupancy, min_peak_height, min_peak_distance,
/// verify_shadow, publish_period_s, vehicle_clear_radius_m,
/// vehicle_centre_behind_head_m, beam_width_deg): the caller reads `enabled` first.
/// @throws common::ConfigError naming the file and line of a bad or unknown key.
SonarMapperLayerParams LoadSonarMapperLayerParams(common::YamlMap& map);

/// The rays one ping puts on the map (the beam's heading from the head's pose), and the bins
/// found as obstacles in it.
std::vector<PlanarRay> SonarPingRays(const SonarReading& ping, const SonarPeakParams& peaks,
                                     std::vector<int>* obstacle_bins = nullptr,
                                     double beam_width_rad = 0.0, double cell_m = 0.25);

class SonarMapperLayer : public MapperLayer {
 public:
  /// @throws std::invalid_argument if the params are invalid.
  explicit SonarMapperLayer(const SonarMapperLayerParams& params);

  const std::string& name() const override;
  uint32_t inputs() const override { return kSensorReadings; }
  LayerSchedule schedule() const override;
  std::vector<std::string> OwnedLayers() const override { return {kSonarOccupancy, kSonarLogOdds}; }
  std::vector<std::string> ReadingStreams() const override { return {"SONAR"}; }
  void OnReading(const SensorReading& reading) override;
  void Reset() override;
  std::vector<GridOutput> GridOutputs() const override;
  std::optional<common::GridMap> ExportGrids() const override;
  int64_t version() const override { return grid_.version(); }
  std::vector<std::string> TakeEvents() override;
  /// The detections of the pings taken since the last call, oldest first (at most
  /// kMaxPendingDetections: older ones are dropped and counted).
  std::vector<SonarDetection> TakeDetections();
  static constexpr size_t kMaxPendingDetections = 256;
  int64_t dropped_detections() const { return dropped_detections_; }

  const OccupancyGrid& grid() const { return grid_; }
  int64_t pings() const { return pings_; }
  int64_t obstacles() const { return obstacles_; }  ///< obstacle bins over all pings
  /// Obstacle bins in the last ping.
  int last_obstacles() const { return last_obstacles_; }

 private:
  SonarMapperLayerParams params_;
  OccupancyGrid grid_;
  int64_t pings_{0};
  int64_t obstacles_{0};
  int last_obstacles_{0};
  std::vector<std::string> events_;
  std::deque<SonarDetection> detections_;
  int64_t dropped_detections_{0};
};

}  // namespace cairn::mapping
