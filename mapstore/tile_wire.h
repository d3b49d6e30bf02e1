#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "cairn/lcmt_grid_tile.hpp"

#include "common/status.h"

/// @file
/// Fast publishing of grid tiles. lcmt_grid_tile::encode byte-swaps its cells one call at a time;
/// a map of four 1000 x 1000 layers spends more time there than in the database. The encoding
/// here writes the same bytes (the cells are the last field of the message) with one swap loop,
/// after checking once, at first use, that it matches the generated encoder (if it ever does
/// not, the generated one is used).

namespace cairn::mapstore {

/// Encodes a tile exactly as lcmt_grid_tile::encode does.
void EncodeTile(const cairn::lcmt_grid_tile& tile, std::vector<uint8_t>* out);

/// Compresses a float tile in place (ENCODING_ZSTD_SHUFFLE4, the store's own blob codec); false,
/// and the tile unchanged, when it is not a float tile or would not get smaller.
bool CompressTile(cairn::lcmt_grid_tile* tile, int zstd_level = 1);

/// Turns a compressed tile back into a float tile in place, checking zstd's frame checksum
/// and, with `verify_checksum`, the float bytes against the tile's checksum; a float tile is
/// left as it is. kInvalidArgument for an unknown encoding or a bad size, kCorrupt for damaged
/// bytes.
common::Status DecompressTile(cairn::lcmt_grid_tile* tile, bool verify_checksum = true);

/// The float form of a received tile: the tile itself when it is one, else its decoded copy in
/// `*scratch`; nullptr when it does not decode. The tile's checksum is left to the
/// LayerAssembler it goes to (one CRC pass over the cells, not two).
const cairn::lcmt_grid_tile* FloatTile(const cairn::lcmt_grid_tile& tile,
                                       cairn::lcmt_grid_tile* scratch);

/// Encodes and publishes a tile; false when LCM refuses it.
bool PublishTile(lcm::LCM& lcm, const std::string& channel, const cairn::lcmt_grid_tile& tile);

/// Bytes of a tile's cells on the bus (its floats, or its encoded bytes): what pacing counts.
int64_t TilePayloadBytes(const cairn::lcmt_grid_tile& tile);

}  // namespace cairn::mapstore
