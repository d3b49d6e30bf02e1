#pragma once

#include <string>

#include "common/grid_map.h"

/// @file
/// Planning on a 2-D occupancy layer (the ROS OccupancyGrid convention: 0 free .. 100
/// occupied, -1 unknown; here NaN unknown, as LayerAssembler delivers it), such as the dynamic
/// map server's `final` layer (seed 001), instead of a profile's cost layer. The conversion is
/// the one Nav2's static layer makes with trinary_costmap off, with map_server's two
/// thresholds:
///
///   occupancy >= occupied_threshold_og            -> lethal_cost
///   occupancy <= free_threshold_og                -> 0 (free)
///   free_threshold_og < occupancy < occupied_...  -> graded, linear from 0 to lethal_cost
///                                                    (both ends excluded)
///   unknown (NaN, or any negative value)          -> unknown (NaN)
///
/// Values above 100 count as occupied.

namespace cairn::planner {

/// How the navigator reads the mapper's map: a float cost layer (<robot>.MAP.TILES,
/// "cost/<profile>") or an int8 occupancy layer (<robot>.MAP.OCCUPANCY) converted to cost.
enum class MapEncoding { kCost = 0, kOccupancy = 1 };

const char* MapEncodingName(MapEncoding encoding);
/// "cost" or "occupancy". @throws std::invalid_argument otherwise.
MapEncoding MapEncodingFromName(const std::string& name);

/// Thresholds of the occupancy-to-cost conversion, in occupancy units (0..100).
struct OccupancyCostParams {
  /// Occupancy at or above this is lethal (map_server's occupied_thresh 0.65 by default).
  float occupied_threshold_og{65.0f};
  /// Occupancy at or below this is free (map_server's free_thresh 0.25 by default).
  float free_threshold_og{25.0f};

  /// 0 <= free_threshold_og < occupied_threshold_og <= 100.
  /// @throws std::invalid_argument naming the bad field.
  void Validate() const;
};

/// The cost of one occupancy value (see the file comment). `lethal_cost` > 0.
float OccupancyToCost(float occupancy_og, const OccupancyCostParams& params, float lethal_cost);

/// The whole layer, cell by cell. @throws std::invalid_argument for invalid params.
common::Layer OccupancyToCostLayer(const common::Layer& occupancy_og,
                                   const OccupancyCostParams& params, float lethal_cost);

}  // namespace cairn::planner
