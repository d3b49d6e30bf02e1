#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "services/mapping/dynamic_mapper_layer.h"
#include "services/mapping/explore_mapper_layer.h"
#include "services/mapping/mapper_layer.h"
#include "services/mapping/occupancy_band.h"
#include "services/mapping/occupancy_mapper_layer.h"
#include "services/mapping/octomap_mapper_layer.h"
#include "services/mapping/sonar_mapper_layer.h"
#include "services/mapping/terrain_mapper_layer.h"

/// @file
/// The mapper's layers: their params (MapperCoreParams) and their registry (LayerRegistry: how
/// each is built, checked and read from its YAML section). A new layer registers here, with a
/// params field and an entry; services/mapping/README.md ("Adding a layer") lists the rest.

namespace cairn::common {
class YamlMap;
}  // namespace cairn::common

namespace cairn::mapping {

/// The built-in layers by name (their YAML sections).
inline constexpr char kTerrainLayerName[] = "terrain";
inline constexpr char kOccupancyLayerName[] = "occupancy";
inline constexpr char kOctomapLayerName[] = "octomap";
inline constexpr char kDynamicLayerName[] = "dynamic";
inline constexpr char kExploreLayerName[] = "explore";
inline constexpr char kSonarLayerName[] = "sonar";

struct MapperCoreParams {
  /// The configured layers, in the order they take each input (names of RegisteredLayers()).
  std::vector<std::string> layers{kTerrainLayerName, kOccupancyLayerName, kOctomapLayerName};
  /// The obstacle band computed for the layers that take kObstacleBand.
  ObstacleBandParams band;
  // Each registered layer's params (used when the layer is listed).
  TerrainMapperLayerParams terrain;
  OccupancyMapperLayerParams occupancy;
  OctomapMapperLayerParams octomap;
  /// Seed 001's dynamic layers (static, short-term, long-term, final) from the planar laser
  /// and the lidar's obstacle band, over the static map's grid or an extent.
  DynamicMapperLayerParams dynamic;
  /// Seed 002's information map from the turret's sweeps, with an explorer configuration's
  /// parameters.
  ExploreMapperLayerParams explore;
  /// Seed 004's sonar obstacles from the imaging sonar's pings, on a 2-D occupancy of their own.
  SonarMapperLayerParams sonar;

  /// Whether `layer` is listed.
  bool Has(const std::string& layer) const;
  /// Lists `layer` (registered layers in the registry's order) unless it is; or removes it.
  void SetListed(const std::string& layer, bool listed);
  /// @throws std::invalid_argument naming a bad field, an unknown or a repeated layer.
  void Validate() const;
};

/// One registered layer: its name (and YAML section), how it is built from the params, how its
/// params are checked, and how its section's keys are read (`enabled` excepted).
struct LayerRegistration {
  const char* name;
  std::function<std::unique_ptr<MapperLayer>(const MapperCoreParams&)> make;
  std::function<void(const MapperCoreParams&)> validate;
  std::function<void(common::YamlMap&, MapperCoreParams*)> load;
};

/// Every layer the mapper knows, in its canonical order.
inline const std::vector<LayerRegistration>& LayerRegistry() {
  static const std::vector<LayerRegistration> registry{
      {kTerrainLayerName,
       [](const MapperCoreParams& p) { return std::make_unique<TerrainMapperLayer>(p.terrain); },
       [](const MapperCoreParams& p) { p.terrain.Validate(); },
       [](common::YamlMap& m, MapperCoreParams* p) {
         p->terrain.map = LoadTerrainMapperLayerParams(m).map;  // periods: top-level keys
       }},
      {kOccupancyLayerName,
       [](const MapperCoreParams& p) {
         return std::make_unique<OccupancyMapperLayer>(p.occupancy);
       },
       [](const MapperCoreParams& p) { p.occupancy.Validate(); },
       [](common::YamlMap& m, MapperCoreParams* p) {
         // The core's obstacle band is configured in this section, as it always was.
         LoadOccupancySection(m, &p->occupancy.grid, &p->band);
       }},
      {kOctomapLayerName,
       [](const MapperCoreParams& p) { return std::make_unique<OctomapMapperLayer>(p.octomap); },
       [](const MapperCoreParams& p) { p.octomap.Validate(); },
       [](common::YamlMap& m, MapperCoreParams* p) {
         p->octomap = LoadOctomapMapperLayerParams(m);
       }},
      {kDynamicLayerName,
       [](const MapperCoreParams& p) { return std::make_unique<DynamicMapperLayer>(p.dynamic); },
       [](const MapperCoreParams& p) { p.dynamic.Validate(); },
       [](common::YamlMap& m, MapperCoreParams* p) {
         const double period = p->dynamic.publish_period_s;  // the top-level occupancy period
         p->dynamic = LoadDynamicMapperLayerParams(m);
         p->dynamic.publish_period_s = period;
       }},
      {kExploreLayerName,
       [](const MapperCoreParams& p) { return std::make_unique<ExploreMapperLayer>(p.explore); },
       [](const MapperCoreParams& p) { p.explore.Validate(); },
       [](common::YamlMap& m, MapperCoreParams* p) {
         p->explore = LoadExploreMapperLayerParams(m);
       }},
      {kSonarLayerName,
       [](const MapperCoreParams& p) { return std::make_unique<SonarMapperLayer>(p.sonar); },
       [](const MapperCoreParams& p) { p.sonar.Validate(); },
       [](common::YamlMap& m, MapperCoreParams* p) { p->sonar = LoadSonarMapperLayerParams(m); }},
  };
  return registry;
}

/// The names of LayerRegistry(), in its order.
const std::vector<std::string>& RegisteredLayers();

/// Builds the layer `name` from its params in `params`.
/// @throws std::invalid_argument for an unknown name or invalid params.
std::unique_ptr<MapperLayer> MakeMapperLayer(const std::string& name,
                                             const MapperCoreParams& params);

/// Validates the params of the layer `name`. @throws std::invalid_argument.
void ValidateMapperLayerParams(const std::string& name, const MapperCoreParams& params);

/// Reads the YAML section of the layer `name` into `params`: `enabled` (true or false) lists the
/// layer or removes it; the other keys are the layer's. The caller has read the keys of the
/// section that are not the layer's (the dynamic section's long-term store).
/// @throws common::ConfigError naming the file and line of a bad or unknown key.
void LoadMapperLayerSection(const std::string& name, common::YamlMap& section,
                            MapperCoreParams* params);

}  // namespace cairn::mapping
