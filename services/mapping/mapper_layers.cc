#include "services/mapping/mapper_layers.h"

#include <functional>

#include "common/check.h"
#include "common/yaml_reader.h"

namespace cairn::mapping {
namespace {

// One registered layer: its name, its builder, its params' check and its section's reader.
struct Registration {
  const char* name;
  std::function<std::unique_ptr<MapperLayer>(const MapperCoreParams&)> make;
  std::function<void(const MapperCoreParams&)> validate;
  std::function<void(common::YamlMap&, MapperCoreParams*)> load;
};

const std::vector<Registration>& Registry() {
  static const std::vector<Registration> registry{
      {kTerrainLayerName,
       [](const MapperCoreParams& p) { return std::make_unique<TerrainMapperLayer>(p.terrain); },
       [](const MapperCoreParams& p) { p.terrain.Validate(); },
       [](common::YamlMap& m, MapperCoreParams* p) {
         const TerrainMapperLayerParams loaded = LoadTerrainMapperLayerParams(m);
         p->terrain.map = loaded.map;  // the periods are top-level keys
       }},
      {kOccupancyLayerName,
       [](const MapperCoreParams& p) {
         return std::make_unique<OccupancyMapperLayer>(p.occupancy);
       },
       [](const MapperCoreParams& p) { p.occupancy.Validate(); },
       [](common::YamlMap& m, MapperCoreParams* p) {
         // The obstacle band is the core's, configured here as it always was.
         if (m.Has("band")) {
           common::YamlMap band = m.Child("band");
           p->band = LoadObstacleBandParams(band);
         }
         p->occupancy.grid = LoadOccupancyMapperLayerParams(m).grid;
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
  };
  return registry;
}

const Registration& Find(const std::string& name) {
  for (const Registration& r : Registry()) {
    if (name == r.name) return r;
  }
  throw std::invalid_argument("no mapper layer named '" + name + "'");
}

}  // namespace

const std::vector<std::string>& RegisteredLayers() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> out;
    for (const Registration& r : Registry()) out.push_back(r.name);
    return out;
  }();
  return names;
}

std::unique_ptr<MapperLayer> MakeMapperLayer(const std::string& name,
                                             const MapperCoreParams& params) {
  return Find(name).make(params);
}

void ValidateMapperLayerParams(const std::string& name, const MapperCoreParams& params) {
  Find(name).validate(params);
}

void LoadMapperLayerSection(const std::string& name, common::YamlMap& section,
                            MapperCoreParams* params) {
  const Registration& r = Find(name);
  bool enabled = params->Has(name);
  if (section.Get("enabled", &enabled)) params->SetListed(name, enabled);
  r.load(section, params);
}

}  // namespace cairn::mapping
