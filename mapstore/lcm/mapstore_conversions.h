#pragma once

#include <string>
#include <vector>

#include "cairn/lcmt_grid_manifest.hpp"
#include "cairn/lcmt_grid_tile.hpp"
#include "cairn/lcmt_map_info.hpp"
#include "cairn/lcmt_mapstore_request.hpp"
#include "cairn/lcmt_occupancy_tile.hpp"
#include "cairn/lcmt_octomap.hpp"
#include "cairn/lcmt_place.hpp"
#include "cairn/lcmt_tile_resend_request.hpp"

#include "common/status.h"
#include "mapstore/map_store.h"
#include "mapstore/octomap_chunks.h"
#include "mapstore/save_assembler.h"
#include "mapstore/tile_assembler.h"

/// @file
/// ToLcm / FromLcm for the map store's own types (the rest lives in services/runtime): map
/// infos, places, and the tiles, manifests, resend requests and OctoMap chunks of the save
/// assembly (mapstore/tile_assembler.h, mapstore/octomap_chunks.h). A tile from the bus becomes
/// a CheckedTile only after its cells were checked against its CRC.

namespace cairn::mapstore {

/// The site a request names, kDefaultSite when it names none.
std::string SiteOf(const cairn::lcmt_mapstore_request& request);
/// The map version a request names (its site defaulted).
MapRef RefOf(const cairn::lcmt_mapstore_request& request);
/// Who changes the store for a request: its requester ("unknown" when none) and request id.
WriteContext ContextOf(const cairn::lcmt_mapstore_request& request);
/// An OP_SAVE request in core terms (layers as they are: the caller checks num_layers).
SaveRequest SaveRequestOf(const cairn::lcmt_mapstore_request& request);

cairn::lcmt_map_info ToLcm(const MapInfo& info);
cairn::lcmt_place ToLcm(const Place& place);
/// @returns kInvalidArgument when the arrays disagree with their count or a vertex is not finite.
common::Result<Place> FromLcm(const cairn::lcmt_place& msg);

/// Where a tile lies and what its sender declared (not its cells).
TileHeader HeaderOf(const cairn::lcmt_grid_tile& tile);
TileHeader HeaderOf(const cairn::lcmt_occupancy_tile& tile);
/// A float tile whose CRC-32 holds, borrowing the message's cells. kInvalidArgument for a
/// compressed tile or one whose cells disagree with num_cells, kCorrupt for a CRC that fails.
common::Result<CheckedTile> CheckFloatTile(const cairn::lcmt_grid_tile& tile);
/// A compressed tile its receiver decoded into `cells` with a codec that verified the bytes
/// against the sender's checksum (DecodeTileCells): the declared checksum stands for the cells.
CheckedTile DecodedTile(const cairn::lcmt_grid_tile& tile, const std::vector<float>& cells);
/// An occupancy tile whose CRC-32 (of its int8 cells) holds, its cells as floats in `*cells`
/// (-1 becomes unknown). Errors as CheckFloatTile.
common::Result<CheckedTile> CheckOccupancyTile(const cairn::lcmt_occupancy_tile& tile,
                                               std::vector<float>* cells);

/// kInvalidArgument when an array disagrees with num_tiles.
common::Result<TileManifest> FromLcm(const cairn::lcmt_grid_manifest& msg);
/// A manifest as LayerTiler would publish it (for tests and senders).
cairn::lcmt_grid_manifest ToLcm(const TileManifest& manifest, int64_t utime);

cairn::lcmt_tile_resend_request ToLcm(const TileRequest& request, const std::string& requester,
                                      int64_t utime);
TileRequest FromLcm(const cairn::lcmt_tile_resend_request& msg);

/// An OctoMap chunk borrowing the message's bytes; kInvalidArgument when num_bytes disagrees.
common::Result<OctomapChunk> FromLcm(const cairn::lcmt_octomap& msg);
cairn::lcmt_octomap ToLcm(const OctomapChunk& chunk, const std::string& robot,
                          const std::string& map_name, int64_t utime);

}  // namespace cairn::mapstore
