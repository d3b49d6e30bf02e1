#include "mapstore/lcm/mapstore_conversions.h"

#include <algorithm>
#include <cmath>

#include "common/crc32.h"

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

}  // namespace cairn::mapstore

namespace cairn::mapstore {

namespace {

template <typename Msg>
common::GridGeometry GeometryOf(const Msg& m) {
  common::GridGeometry g;
  g.resolution_m = m.resolution_m;
  g.size_x = m.layer_size_x;
  g.size_y = m.layer_size_y;
  g.origin = {m.origin_x_m, m.origin_y_m, m.origin_yaw_rad};
  return g;
}

template <typename Msg>
TileHeader TileHeaderOf(const Msg& m) {
  TileHeader h;
  h.robot = m.robot;
  h.map_name = m.map_name;
  h.layer = m.layer;
  h.geometry = GeometryOf(m);
  h.tile_size = m.tile_size;
  h.tile_ix = m.tile_ix;
  h.tile_iy = m.tile_iy;
  h.cells_x = m.cells_x;
  h.cells_y = m.cells_y;
  h.tile_version = m.tile_version;
  h.checksum = static_cast<uint32_t>(m.checksum);
  return h;
}

}  // namespace

TileHeader HeaderOf(const cairn::lcmt_grid_tile& tile) { return TileHeaderOf(tile); }

TileHeader HeaderOf(const cairn::lcmt_occupancy_tile& tile) { return TileHeaderOf(tile); }

common::Result<CheckedTile> CheckFloatTile(const cairn::lcmt_grid_tile& tile) {
  if (tile.encoding != cairn::lcmt_grid_tile::ENCODING_FLOAT32 ||
      tile.data.size() != static_cast<size_t>(std::max(0, tile.num_cells))) {
    return common::InvalidArgumentError("not a float tile of num_cells cells");
  }
  const size_t bytes = tile.data.size() * sizeof(float);
  if (common::Crc32(tile.data.data(), bytes) != static_cast<uint32_t>(tile.checksum)) {
    return common::CorruptError("tile checksum mismatch");
  }
  return CheckedTile{TileHeaderOf(tile), tile.data.data(), tile.data.size()};
}

CheckedTile DecodedTile(const cairn::lcmt_grid_tile& tile, const std::vector<float>& cells) {
  return CheckedTile{TileHeaderOf(tile), cells.data(), cells.size()};
}

common::Result<CheckedTile> CheckOccupancyTile(const cairn::lcmt_occupancy_tile& tile,
                                               std::vector<float>* cells) {
  if (tile.data.size() != static_cast<size_t>(std::max(0, tile.num_cells))) {
    return common::InvalidArgumentError("occupancy cells disagree with num_cells");
  }
  if (common::Crc32(tile.data.data(), tile.data.size()) != static_cast<uint32_t>(tile.checksum)) {
    return common::CorruptError("tile checksum mismatch");
  }
  cells->resize(tile.data.size());
  for (size_t i = 0; i < cells->size(); ++i) {
    (*cells)[i] = tile.data[i] < 0 ? common::kUnknown : static_cast<float>(tile.data[i]);
  }
  return CheckedTile{TileHeaderOf(tile), cells->data(), cells->size()};
}

common::Result<TileManifest> FromLcm(const cairn::lcmt_grid_manifest& m) {
  const size_t n = static_cast<size_t>(std::max(0, m.num_tiles));
  if (m.num_tiles < 0 || m.tile_ix.size() != n || m.tile_iy.size() != n || m.checksum.size() != n ||
      m.tile_version.size() != n) {
    return common::InvalidArgumentError("manifest arrays disagree with num_tiles");
  }
  TileManifest out;
  out.robot = m.robot;
  out.map_name = m.map_name;
  out.layer = m.layer;
  out.layer_version = m.layer_version;
  out.geometry = GeometryOf(m);
  out.tile_size = m.tile_size;
  out.tiles.resize(n);
  for (size_t i = 0; i < n; ++i) {
    out.tiles[i] = {m.tile_ix[i], m.tile_iy[i], m.tile_version[i],
                    static_cast<uint32_t>(m.checksum[i])};
  }
  return out;
}

cairn::lcmt_grid_manifest ToLcm(const TileManifest& manifest, int64_t utime) {
  cairn::lcmt_grid_manifest m{};
  m.utime = utime;
  m.robot = manifest.robot;
  m.map_name = manifest.map_name;
  m.layer = manifest.layer;
  m.layer_version = manifest.layer_version;
  m.resolution_m = manifest.geometry.resolution_m;
  m.origin_x_m = manifest.geometry.origin.x_m;
  m.origin_y_m = manifest.geometry.origin.y_m;
  m.origin_yaw_rad = manifest.geometry.origin.yaw_rad;
  m.layer_size_x = manifest.geometry.size_x;
  m.layer_size_y = manifest.geometry.size_y;
  m.tile_size = manifest.tile_size;
  for (const TileManifest::Entry& e : manifest.tiles) {
    m.tile_ix.push_back(e.tile_ix);
    m.tile_iy.push_back(e.tile_iy);
    m.tile_version.push_back(e.tile_version);
    m.checksum.push_back(e.checksum);
  }
  m.num_tiles = static_cast<int32_t>(m.tile_ix.size());
  return m;
}

cairn::lcmt_tile_resend_request ToLcm(const TileRequest& request, const std::string& requester,
                                      int64_t utime) {
  cairn::lcmt_tile_resend_request r{};
  r.utime = utime;
  r.requester = requester;
  r.robot = request.robot;
  r.map_name = request.map_name;
  r.layer = request.layer;
  r.layer_version = request.layer_version;
  for (const auto& [ix, iy] : request.tiles) {
    r.tile_ix.push_back(ix);
    r.tile_iy.push_back(iy);
  }
  r.num_tiles = static_cast<int32_t>(r.tile_ix.size());
  return r;
}

TileRequest FromLcm(const cairn::lcmt_tile_resend_request& msg) {
  TileRequest r;
  r.robot = msg.robot;
  r.map_name = msg.map_name;
  r.layer = msg.layer;
  r.layer_version = msg.layer_version;
  const size_t n = std::min(
      {static_cast<size_t>(std::max(0, msg.num_tiles)), msg.tile_ix.size(), msg.tile_iy.size()});
  for (size_t i = 0; i < n; ++i) r.tiles.emplace_back(msg.tile_ix[i], msg.tile_iy[i]);
  return r;
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
