#pragma once

#include <string>

#include "common/grid_map.h"
#include "common/status.h"

/// @file
/// Occupancy in percent of a layer, as the ROS map and PNG formats draw it.

namespace cairn::mapstore::io {

/// Cost and occupancy layers (0..100, NaN unknown): cost/<profile>, static, short_term,
/// long_term, final, occupancy.
bool IsOccupancyLayer(const std::string& name);

/// Occupancy in percent (0..100, NaN unknown) of a layer: log-odds layers are converted to
/// probabilities, cost and occupancy layers are taken as they are (clamped). kInvalidArgument
/// for layers that are not occupancy-like (elevation, slope, ...).
common::Result<common::Layer> OccupancyPercent(const common::GridMap& map,
                                               const std::string& layer);

}  // namespace cairn::mapstore::io
