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

/// Serialises a registry (obstacles, outlines, verdicts, parts) in a compact little-endian form
/// ("CRG2"; ParseRegistry also reads the "CRG1" form of registries stored before terraces).
std::string SerializeRegistry(const common::ObstacleRegistry& registry);
/// kCorrupt when the bytes are not a registry.
common::Result<common::ObstacleRegistry> ParseRegistry(const std::string& bytes);

/// A terrace's parts (measurements, outline, verdicts), as the registry keeps them; parsing
/// refuses more than common::kMaxObstacleParts.
std::string SerializeParts(const std::vector<common::ObstaclePart>& parts);
common::Result<std::vector<common::ObstaclePart>> ParseParts(const std::string& bytes);

/// Polygons as little-endian doubles x0 y0 x1 y1 ...
std::string SerializePolygon(const std::vector<common::Vector2>& polygon);
common::Result<std::vector<common::Vector2>> ParsePolygon(const std::string& bytes);

}  // namespace cairn::mapstore
