#pragma once

#include <optional>
#include <string>
#include <vector>

#include "services/mapping/mapper_layer.h"
#include "services/mapping/terrain_map.h"

/// @file
/// The terrain as a mapper layer ("terrain"): the elevation fused from lidar revolutions, its
/// derived layers, a cost layer per profile and the obstacle registry (TerrainMap). Published
/// its own way (sparse tiles of the layers that changed, and the registry) at the periods below.

namespace cairn::mapping {

struct TerrainMapperLayerParams {
  TerrainMapParams map;
  double publish_period_s{0.2};       ///< elevation, slope, step, roughness, cost/<profile>
  double slow_publish_period_s{5.0};  ///< the base statistics, ditches; every manifest again
  double registry_period_s{1.0};      ///< the obstacle registry (when it changed)
  /// The fast layers' manifests say "this layer is current" every period (a navigator's
  /// stale-map stop reads them so). They say it only while revolutions come in: with none
  /// integrated for this long (wall seconds; a lidar gone quiet, or lost on a lossy link), they
  /// stop until the next one, and the navigator's map goes stale. Forced publications (a pull
  /// save's OP_PUBLISH_ALL) still go out.
  double max_announce_without_data_s{1.0};

  /// @throws std::invalid_argument naming a bad field.
  void Validate() const;
};

/// Reads a `terrain` section: TerrainMapParams' keys. The periods are top-level keys of the
/// mapper's file (publish_period_s, slow_publish_period_s, registry_period_s), read by
/// LoadMapperConfig. @throws common::ConfigError naming the file and line of a bad key.
TerrainMapperLayerParams LoadTerrainMapperLayerParams(common::YamlMap& map);

class TerrainMapperLayer : public MapperLayer {
 public:
  /// @throws std::invalid_argument if the params are invalid.
  explicit TerrainMapperLayer(const TerrainMapperLayerParams& params);

  const std::string& name() const override;
  uint32_t inputs() const override { return kLidarRevolutions; }
  LayerSchedule schedule() const override;
  std::vector<std::string> OwnedLayers() const override;
  /// Integrates the revolution, then updates the derived layers around what changed.
  void OnRevolution(const RevolutionInput& input, RevolutionReport* report) override;
  /// The mean elevation of the 3 x 3 cells around the cell of `xy_m`, nullopt if all unknown.
  std::optional<double> GroundHeightUnder(const common::Vector2& xy_m) const override;
  void Reset() override { map_.Clear(); }
  /// Every base and derived layer as raw float32, the registry as obstacles.yaml.
  common::Status WriteOutputs(const std::string& dir, std::ostream& yaml) const override;

  TerrainMap& map() { return map_; }
  const TerrainMap& map() const { return map_; }
  const TerrainMapperLayerParams& params() const { return params_; }

 private:
  TerrainMapperLayerParams params_;
  TerrainMap map_;
};

}  // namespace cairn::mapping
