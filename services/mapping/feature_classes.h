#pragma once

#include <cstdint>

/// @file
/// The per-cell feature classes of the obstacle registry (internal to the mapping core): the
/// values of kFeatureClassLayer, written by ComputeFeatureLayers (feature_classes.cc) and read by
/// AssembleObstacles (obstacles.cc).

namespace cairn::mapping::internal {

/// Per-cell feature class, in priority order (a cell takes the first that applies).
enum CellClass : uint8_t { kNone = 0, kDitch, kWall, kStep, kDrop, kRamp };

}  // namespace cairn::mapping::internal
