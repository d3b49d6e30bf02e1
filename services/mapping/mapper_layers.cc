#include "services/mapping/mapper_layers.h"

#include <algorithm>
#include <set>

#include "common/check.h"
#include "common/yaml_reader.h"

namespace cairn::mapping {
namespace {

const LayerRegistration& Find(const std::string& name) {
  for (const LayerRegistration& r : LayerRegistry()) {
    if (name == r.name) return r;
  }
  throw std::invalid_argument("no mapper layer named '" + name + "'");
}

}  // namespace

bool MapperCoreParams::Has(const std::string& layer) const {
  return std::find(layers.begin(), layers.end(), layer) != layers.end();
}

void MapperCoreParams::SetListed(const std::string& layer, bool listed) {
  if (!listed) {
    layers.erase(std::remove(layers.begin(), layers.end(), layer), layers.end());
    return;
  }
  if (Has(layer)) return;
  // Registered layers keep the registry's order among themselves.
  const std::vector<std::string>& order = RegisteredLayers();
  const auto rank = [&](const std::string& name) {
    return std::find(order.begin(), order.end(), name) - order.begin();
  };
  auto at = std::find_if(layers.begin(), layers.end(),
                         [&](const std::string& other) { return rank(other) > rank(layer); });
  layers.insert(at, layer);
}

void MapperCoreParams::Validate() const {
  std::set<std::string> seen;
  for (const std::string& name : layers) {
    CAIRN_THROW_UNLESS(seen.insert(name).second,
                       "the mapper layer '" << name << "' is listed twice");
    ValidateMapperLayerParams(name, *this);
  }
  band.Validate();
}

const std::vector<std::string>& RegisteredLayers() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> out;
    for (const LayerRegistration& r : LayerRegistry()) out.push_back(r.name);
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
  const LayerRegistration& r = Find(name);
  bool enabled = params->Has(name);
  if (section.Get("enabled", &enabled)) params->SetListed(name, enabled);
  r.load(section, params);
}

}  // namespace cairn::mapping
