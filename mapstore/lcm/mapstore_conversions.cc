#include "mapstore/lcm/mapstore_conversions.h"

#include <cmath>

namespace cairn::mapstore {

cairn::lcmt_map_info ToLcm(const MapInfo& info) {
  cairn::lcmt_map_info m{};
  m.site = info.site;
  m.name = info.name;
  m.version = info.version;
  m.source_robot = info.provenance.source_robot;
  m.source_profile = info.provenance.source_profile;
  m.code_version = info.provenance.code_version;
  m.created_utime = info.provenance.created_utime;
  m.resolution_m = info.geometry.resolution_m;
  m.size_x = info.geometry.size_x;
  m.size_y = info.geometry.size_y;
  m.num_layers = static_cast<int32_t>(info.layers.size());
  m.layers = info.layers;
  m.num_obstacles = info.num_obstacles;
  m.deleted = info.deleted;
  return m;
}

cairn::lcmt_place ToLcm(const Place& place) {
  cairn::lcmt_place m{};
  m.name = place.name;
  m.num_vertices = static_cast<int32_t>(place.polygon_m.size());
  for (const auto& v : place.polygon_m) {
    m.x_m.push_back(v.x());
    m.y_m.push_back(v.y());
  }
  return m;
}

common::Result<Place> FromLcm(const cairn::lcmt_place& m) {
  if (m.num_vertices < 0 || m.x_m.size() != static_cast<size_t>(m.num_vertices) ||
      m.y_m.size() != static_cast<size_t>(m.num_vertices)) {
    return common::InvalidArgumentError("place '" + m.name +
                                        "': vertex arrays disagree with num_vertices");
  }
  Place p;
  p.name = m.name;
  for (int i = 0; i < m.num_vertices; ++i) {
    if (!std::isfinite(m.x_m[i]) || !std::isfinite(m.y_m[i])) {
      return common::InvalidArgumentError("place '" + m.name + "' has a vertex that is not finite");
    }
    p.polygon_m.emplace_back(m.x_m[i], m.y_m[i]);
  }
  return p;
}

}  // namespace cairn::mapstore
