#pragma once

#include <cstdint>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "common/grid_map.h"
#include "common/obstacle.h"
#include "common/status.h"
#include "mapstore/blob_codec.h"
#include "mapstore/sqlite_map_store.h"

/// @file
/// Rows of the SQLite store and what its files share (internal to SqliteMapStore's .cc files):
/// the one SELECT of a map version and its one decoder (SqliteMapStore::ReadVersionRow), the
/// one SELECT of a tile's blob row and its decoder (ReadTileRow), the blobs a save encodes
/// before it takes the write lock, and the wording of write errors.

namespace cairn::mapstore {

/// Columns of a version row: every reader of map_versions selects them this way and decodes
/// them with ReadVersionRow.
inline constexpr char kVersionSelect[] =
    "SELECT v.id, v.map_id, m.site_id, s.name, m.name, v.version, v.source_robot, "
    "v.source_profile, v.source_profile_hash, v.code_version, v.parameters, v.created_utime, "
    "v.resolution_m, v.size_x, v.size_y, v.origin_x_m, v.origin_y_m, v.origin_yaw_rad, "
    "v.tile_size, v.deleted_utime IS NOT NULL "
    "FROM map_versions v JOIN maps m ON m.id = v.map_id JOIN sites s ON s.id = m.site_id ";

/// Columns of a tile's blob row (t: layer_tiles or derived_tiles, b: blobs), decoded by
/// ReadTileRow.
inline constexpr char kTileColumns[] =
    "t.tile_ix, t.tile_iy, b.codec, b.raw_size, b.raw_crc32, b.data, b.stored_crc32";

struct SqliteMapStore::VersionRow {
  int64_t id{0};
  int64_t map_id{0};
  int64_t site_id{0};
  std::string site;
  std::string name;
  int64_t version{0};
  Provenance provenance;
  common::GridGeometry geometry;
  int tile_size{0};
  bool deleted{false};
};

struct SqliteMapStore::TileRow {
  int tile_ix{0};
  int tile_iy{0};
  Codec codec{Codec::kRaw};
  int64_t raw_size{0};
  uint32_t raw_crc32{0};
  std::string data;
  std::optional<uint32_t> stored_crc32;
};

struct SqliteMapStore::DerivedHeader {
  int64_t id{0};
  std::string profile_name;
  int64_t created_utime{0};
  common::ObstacleRegistry registry;
  std::set<std::string> layers;
};

/// A save's blobs, compressed and checksummed before the write lock is taken.
struct SqliteMapStore::EncodedTiles {
  std::vector<std::string> layer_names;
  std::vector<TileSpec> specs;                   ///< every tile of the grid
  std::vector<EncodedBlob> blobs;                ///< the tiles stored (all-unknown ones are not)
  std::vector<std::pair<size_t, size_t>> place;  ///< (layer, spec) of each blob
  std::optional<EncodedBlob> octomap;
};

}  // namespace cairn::mapstore
