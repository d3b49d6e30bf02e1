#pragma once

#include <string>
#include <vector>

#include "cairn/lcmt_grid_manifest.hpp"
#include "cairn/lcmt_grid_tile.hpp"
#include "cairn/lcmt_occupancy_tile.hpp"
#include "cairn/lcmt_tile_resend_request.hpp"

#include "common/status.h"
#include "common/tile_assembler.h"

/// @file
/// ToLcm / FromLcm for tiled layers: tiles, manifests and resend requests on the bus, and the
/// core's tile types (common/tile_assembler.h). A tile from the bus becomes a CheckedTile only
/// after its cells were checked against its CRC.

namespace cairn::runtime {

/// Where a tile lies and what its sender declared (not its cells).
common::TileHeader HeaderOf(const cairn::lcmt_grid_tile& tile);
common::TileHeader HeaderOf(const cairn::lcmt_occupancy_tile& tile);
/// A float tile whose CRC-32 holds, borrowing the message's cells. kInvalidArgument for a
/// compressed tile or one whose cells disagree with num_cells, kCorrupt for a CRC that fails.
common::Result<common::CheckedTile> CheckFloatTile(const cairn::lcmt_grid_tile& tile);
/// A compressed tile its receiver decoded into `cells` with a codec that verified the bytes
/// against the sender's checksum (DecodeTileCells): the declared checksum stands for the cells.
common::CheckedTile DecodedTile(const cairn::lcmt_grid_tile& tile, const std::vector<float>& cells);
/// An occupancy tile whose CRC-32 (of its int8 cells) holds, its cells as floats in `*cells`
/// (-1 becomes unknown). Errors as CheckFloatTile.
common::Result<common::CheckedTile> CheckOccupancyTile(const cairn::lcmt_occupancy_tile& tile,
                                                       std::vector<float>* cells);

/// kInvalidArgument when an array disagrees with num_tiles.
common::Result<common::TileManifest> FromLcm(const cairn::lcmt_grid_manifest& msg);
/// A manifest as LayerTiler would publish it (for tests and senders).
cairn::lcmt_grid_manifest ToLcm(const common::TileManifest& manifest, int64_t utime);

cairn::lcmt_tile_resend_request ToLcm(const common::TileRequest& request,
                                      const std::string& requester, int64_t utime);
common::TileRequest FromLcm(const cairn::lcmt_tile_resend_request& msg);

}  // namespace cairn::runtime
