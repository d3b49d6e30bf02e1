#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "cairn/lcmt_grid_tile.hpp"

/// @file
/// Fast publishing of grid tiles. lcmt_grid_tile::encode byte-swaps its cells one call at a time;
/// a map of four 1000 x 1000 layers spends more time there than in the database. The encoding
/// here writes the same bytes (the cells are the last field of the message) with one swap loop,
/// after checking once, at first use, that it matches the generated encoder (if it ever does
/// not, the generated one is used).

namespace cairn::mapstore {

/// Encodes a tile exactly as lcmt_grid_tile::encode does.
void EncodeTile(const cairn::lcmt_grid_tile& tile, std::vector<uint8_t>* out);

/// Encodes and publishes a tile; false when LCM refuses it.
bool PublishTile(lcm::LCM& lcm, const std::string& channel, const cairn::lcmt_grid_tile& tile);

}  // namespace cairn::mapstore
