#include "simulator/places.h"

namespace cairn::sim {

bool Place::Contains(const common::Vector2& p) const {
  bool inside = false;
  const size_t n = polygon_m.size();
  for (size_t i = 0, j = n - 1; i < n; j = i++) {
    const common::Vector2& a = polygon_m[i];
    const common::Vector2& b = polygon_m[j];
    if ((a.y() > p.y()) != (b.y() > p.y()) &&
        p.x() < (b.x() - a.x()) * (p.y() - a.y()) / (b.y() - a.y()) + a.x()) {
      inside = !inside;
    }
  }
  return inside;
}

std::vector<Place> LoadPlaces(common::YamlMap& map) {
  std::vector<Place> places;
  YAML::Node list = map.Raw("places");
  if (!list || !list.IsSequence()) map.Fail(list ? list : YAML::Node(), "'places' must be a list");
  int index = 0;
  for (const auto& node : list) {
    common::YamlMap entry = map.Wrap(node, "places[" + std::to_string(index++) + "]");
    Place place;
    place.name = entry.Require<std::string>("name");
    entry.Get("label_value", &place.label_value);
    YAML::Node polygon = entry.Raw("polygon");
    if (!polygon || !polygon.IsSequence() || polygon.size() < 3) {
      entry.Fail(node, "place '" + place.name + "' needs a polygon of at least 3 [x, y] points");
    }
    for (const auto& vertex : polygon) {
      if (!vertex.IsSequence() || vertex.size() != 2) entry.Fail(vertex, "a vertex is [x, y]");
      place.polygon_m.emplace_back(entry.As<double>(vertex[0], "a number"),
                                   entry.As<double>(vertex[1], "a number"));
    }
    entry.Finish();
    places.push_back(std::move(place));
  }
  map.Finish();
  return places;
}

std::vector<Place> LoadPlacesFile(const std::string& path) {
  common::YamlMap map = common::YamlMap::LoadFile(path);
  return LoadPlaces(map);
}

std::string PlaceAt(const std::vector<Place>& places, const common::Vector2& point_m) {
  for (const Place& p : places) {
    if (p.Contains(point_m)) return p.name;
  }
  return "";
}

}  // namespace cairn::sim
