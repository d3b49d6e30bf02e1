#pragma once

#include <memory>
#include <string>
#include <vector>

#include "services/mapping/mapper_core.h"

/// @file
/// The registry of the mapper's layers: their names, how each is built from MapperCoreParams,
/// and how its YAML section is read. A new layer registers here (see services/mapping/README.md,
/// "Adding a layer").

namespace cairn::common {
class YamlMap;
}  // namespace cairn::common

namespace cairn::mapping {

/// Every layer name the registry knows, in its canonical order (the order of a layer list built
/// from `enabled` keys).
const std::vector<std::string>& RegisteredLayers();

/// Builds the layer `name` from its params in `params`.
/// @throws std::invalid_argument for an unknown name or invalid params.
std::unique_ptr<MapperLayer> MakeMapperLayer(const std::string& name,
                                             const MapperCoreParams& params);

/// Validates the params of the layer `name`. @throws std::invalid_argument.
void ValidateMapperLayerParams(const std::string& name, const MapperCoreParams& params);

/// Reads the YAML section of the layer `name` into `params`: `enabled` (true or false) lists the
/// layer or removes it; the other keys are the layer's (its Load...Params). The caller has read
/// the keys of the section that are not the layer's (the dynamic section's long-term store).
/// @throws common::ConfigError naming the file and line of a bad or unknown key.
void LoadMapperLayerSection(const std::string& name, common::YamlMap& section,
                            MapperCoreParams* params);

}  // namespace cairn::mapping
