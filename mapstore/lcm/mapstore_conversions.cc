#include "mapstore/lcm/mapstore_conversions.h"

#include <algorithm>
#include <cmath>

#include "common/crc32.h"
#include "mapstore/names.h"

namespace cairn::mapstore {

std::string SiteOf(const cairn::lcmt_mapstore_request& request) {
  return request.site.empty() ? kDefaultSite : request.site;
}

MapRef RefOf(const cairn::lcmt_mapstore_request& request) {
  return {SiteOf(request), request.map_name, request.version};
}

WriteContext ContextOf(const cairn::lcmt_mapstore_request& request) {
  return {request.requester.empty() ? "unknown" : request.requester, request.request_id, 0};
}

SaveRequest SaveRequestOf(const cairn::lcmt_mapstore_request& r) {
  SaveRequest s;
  s.requester = r.requester;
  s.request_id = r.request_id;
  s.site = r.site;
  s.map_name = r.map_name;
  s.robot = r.robot;
  s.layers = r.layers;
  s.profile = r.profile;
  s.code_version = r.code_version;
  s.parameters = r.parameters;
  s.expect_obstacles = r.expect_obstacles;
  s.expect_octomap = r.expect_octomap;
  return s;
}

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

common::Result<MapperLayers> FromLcm(const cairn::lcmt_map_control_reply& m) {
  if (m.num_layers < 0 || m.num_layers > cairn::lcmt_map_control_reply::MAX_LAYERS ||
      m.layers.size() != static_cast<size_t>(m.num_layers)) {
    return common::InvalidArgumentError(
        "map control reply: layers disagree with num_layers (" + std::to_string(m.num_layers) +
        ", at most " + std::to_string(cairn::lcmt_map_control_reply::MAX_LAYERS) + ")");
  }
  MapperLayers out;
  out.request_id = m.request_id;
  out.ok = m.status == cairn::lcmt_map_control_reply::STATUS_OK;
  for (const std::string& layer : m.layers) {
    common::Status s = ValidateLayerName(layer);
    if (!s.ok()) return common::InvalidArgumentError("map control reply: " + s.message());
    out.layers.push_back(layer);
  }
  return out;
}

common::Result<OctomapChunk> FromLcm(const cairn::lcmt_octomap& m) {
  if (m.num_bytes != static_cast<int32_t>(m.data.size())) {
    return common::InvalidArgumentError("OctoMap chunk bytes disagree with num_bytes");
  }
  OctomapChunk c;
  c.version = m.version;
  c.chunk_index = m.chunk_index;
  c.chunk_count = m.chunk_count;
  c.total_bytes = m.total_bytes;
  c.checksum = static_cast<uint32_t>(m.checksum);
  c.binary = m.binary;
  c.resolution_m = m.resolution_m;
  c.data = reinterpret_cast<const char*>(m.data.data());
  c.size = m.data.size();
  return c;
}

cairn::lcmt_octomap ToLcm(const OctomapChunk& chunk, const std::string& robot,
                          const std::string& map_name, int64_t utime) {
  cairn::lcmt_octomap c{};
  c.utime = utime;
  c.robot = robot;
  c.map_name = map_name;
  c.resolution_m = chunk.resolution_m;
  c.binary = chunk.binary;
  c.version = chunk.version;
  c.chunk_index = chunk.chunk_index;
  c.chunk_count = chunk.chunk_count;
  c.total_bytes = chunk.total_bytes;
  c.checksum = chunk.checksum;
  c.data.assign(chunk.data, chunk.data + chunk.size);
  c.num_bytes = static_cast<int32_t>(c.data.size());
  return c;
}

}  // namespace cairn::mapstore
