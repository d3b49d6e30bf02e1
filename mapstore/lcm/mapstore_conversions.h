#pragma once

#include <string>
#include <vector>

#include "cairn/lcmt_grid_manifest.hpp"
#include "cairn/lcmt_grid_tile.hpp"
#include "cairn/lcmt_map_control_reply.hpp"
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
#include "services/runtime/tile_conversions.h"

/// @file
/// ToLcm / FromLcm for the map store's own types: map infos, places and the OctoMap chunks of the
/// save assembly (mapstore/octomap_chunks.h). Tiles, manifests and resend requests convert in
/// services/runtime/tile_conversions.h (the save assembly's core types are common's).

namespace cairn::mapstore {

using runtime::CheckFloatTile;
using runtime::CheckOccupancyTile;
using runtime::DecodedTile;
using runtime::HeaderOf;
using runtime::FromLcm;
using runtime::ToLcm;

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

/// An OctoMap chunk borrowing the message's bytes; kInvalidArgument when num_bytes disagrees.
common::Result<OctomapChunk> FromLcm(const cairn::lcmt_octomap& msg);
cairn::lcmt_octomap ToLcm(const OctomapChunk& chunk, const std::string& robot,
                          const std::string& map_name, int64_t utime);

/// A mapper's answer to OP_PUBLISH_ALL in core terms. kInvalidArgument when `layers` disagrees
/// with num_layers, holds more than MAX_LAYERS names, or a name is not a valid layer name.
common::Result<MapperLayers> FromLcm(const cairn::lcmt_map_control_reply& msg);

}  // namespace cairn::mapstore
