#pragma once

#include <string>
#include <vector>

#include "common/types.h"
#include "common/yaml_reader.h"

/// @file
/// Semantic places of a world: named areas (rooms) as polygons in the world frame, read from
/// worlds/<world>_places.yaml (apartment_places.yaml lists the rooms of the apartment world).

namespace cairn::sim {

struct Place {
  std::string name;
  int label_value{0};  ///< the seed 001 grey level of the room (0 when it has none)
  std::vector<common::Vector2> polygon_m;  ///< counter-clockwise, world frame

  /// True when the point lies inside the polygon (even-odd rule; boundary points may go
  /// either way).
  bool Contains(const common::Vector2& point_m) const;
};

/// Reads `places: [{name, label_value, polygon: [[x, y], ...]}, ...]`.
/// @throws common::ConfigError with file and line for a missing or malformed entry.
std::vector<Place> LoadPlaces(common::YamlMap& map);
std::vector<Place> LoadPlacesFile(const std::string& path);

/// Name of the first place containing the point, or "".
std::string PlaceAt(const std::vector<Place>& places, const common::Vector2& point_m);

}  // namespace cairn::sim
