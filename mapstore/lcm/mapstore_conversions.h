#pragma once

#include "cairn/lcmt_map_info.hpp"
#include "cairn/lcmt_place.hpp"

#include "common/status.h"
#include "mapstore/map_store.h"

/// @file
/// ToLcm / FromLcm for the map store's own types (the rest lives in services/runtime).

namespace cairn::mapstore {

cairn::lcmt_map_info ToLcm(const MapInfo& info);
cairn::lcmt_place ToLcm(const Place& place);
/// @returns kInvalidArgument when the arrays disagree with their count or a vertex is not finite.
common::Result<Place> FromLcm(const cairn::lcmt_place& msg);

}  // namespace cairn::mapstore
