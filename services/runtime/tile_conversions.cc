#include "services/runtime/tile_conversions.h"

#include <algorithm>

#include "common/crc32.h"

namespace cairn::runtime {

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
common::TileHeader TileHeaderOf(const Msg& m) {
  common::TileHeader h;
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

common::TileHeader HeaderOf(const cairn::lcmt_grid_tile& tile) { return TileHeaderOf(tile); }

common::TileHeader HeaderOf(const cairn::lcmt_occupancy_tile& tile) { return TileHeaderOf(tile); }

common::Result<common::CheckedTile> CheckFloatTile(const cairn::lcmt_grid_tile& tile) {
  if (tile.encoding != cairn::lcmt_grid_tile::ENCODING_FLOAT32 ||
      tile.data.size() != static_cast<size_t>(std::max(0, tile.num_cells))) {
    return common::InvalidArgumentError("not a float tile of num_cells cells");
  }
  const size_t bytes = tile.data.size() * sizeof(float);
  if (common::Crc32(tile.data.data(), bytes) != static_cast<uint32_t>(tile.checksum)) {
    return common::CorruptError("tile checksum mismatch");
  }
  return common::CheckedTile{TileHeaderOf(tile), tile.data.data(), tile.data.size()};
}

common::CheckedTile DecodedTile(const cairn::lcmt_grid_tile& tile,
                                const std::vector<float>& cells) {
  return common::CheckedTile{TileHeaderOf(tile), cells.data(), cells.size()};
}

common::Result<common::CheckedTile> CheckOccupancyTile(const cairn::lcmt_occupancy_tile& tile,
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
  return common::CheckedTile{TileHeaderOf(tile), cells->data(), cells->size()};
}

common::Result<common::TileManifest> FromLcm(const cairn::lcmt_grid_manifest& m) {
  const size_t n = static_cast<size_t>(std::max(0, m.num_tiles));
  if (m.num_tiles < 0 || m.tile_ix.size() != n || m.tile_iy.size() != n || m.checksum.size() != n ||
      m.tile_version.size() != n) {
    return common::InvalidArgumentError("manifest arrays disagree with num_tiles");
  }
  common::TileManifest out;
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

cairn::lcmt_grid_manifest ToLcm(const common::TileManifest& manifest, int64_t utime) {
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
  for (const common::TileManifest::Entry& e : manifest.tiles) {
    m.tile_ix.push_back(e.tile_ix);
    m.tile_iy.push_back(e.tile_iy);
    m.tile_version.push_back(e.tile_version);
    m.checksum.push_back(e.checksum);
  }
  m.num_tiles = static_cast<int32_t>(m.tile_ix.size());
  return m;
}

cairn::lcmt_tile_resend_request ToLcm(const common::TileRequest& request,
                                      const std::string& requester, int64_t utime) {
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

common::TileRequest FromLcm(const cairn::lcmt_tile_resend_request& msg) {
  common::TileRequest r;
  r.robot = msg.robot;
  r.map_name = msg.map_name;
  r.layer = msg.layer;
  r.layer_version = msg.layer_version;
  const size_t n = std::min(
      {static_cast<size_t>(std::max(0, msg.num_tiles)), msg.tile_ix.size(), msg.tile_iy.size()});
  for (size_t i = 0; i < n; ++i) r.tiles.emplace_back(msg.tile_ix[i], msg.tile_iy[i]);
  return r;
}

}  // namespace cairn::runtime
