#pragma once

#include <string>
#include <vector>

#include "common/obstacle.h"
#include "common/status.h"
#include "common/types.h"

/// @file
/// The bytes the map store keeps obstacle registries and polygons in (the derived cache's
/// registries, obstacle outlines, places).

namespace cairn::mapstore {

/// Serialises a registry (obstacles, outlines, verdicts) in a compact little-endian form.
std::string SerializeRegistry(const common::ObstacleRegistry& registry);
/// kCorrupt when the bytes are not a registry.
common::Result<common::ObstacleRegistry> ParseRegistry(const std::string& bytes);

/// Polygons as little-endian doubles x0 y0 x1 y1 ...
std::string SerializePolygon(const std::vector<common::Vector2>& polygon);
common::Result<std::vector<common::Vector2>> ParsePolygon(const std::string& bytes);

}  // namespace cairn::mapstore
