#pragma once

#include <cstdint>

/// @file
/// The per-cell feature classes of the obstacle registry (internal to the mapping core): the
/// values of kFeatureClassLayer, written by ComputeFeatureLayers (feature_classes.cc) and read by
/// AssembleObstacles (obstacles.cc).

namespace cairn::mapping::internal {

/// Per-cell feature class, in priority order (a cell takes the first that applies).
enum CellClass : uint8_t { kNone = 0, kDitch, kWall, kStep, kDrop, kRamp };

/// A class layer's value as its class: kNone for NaN (a cell never classified) or a value that is
/// no class. Casting NaN to an integer is undefined behaviour (found by fuzz_bus_mapper).
inline uint8_t ClassOf(float value) {
  return value >= 1.f && value <= static_cast<float>(kRamp) ? static_cast<uint8_t>(value)
                                                            : uint8_t{kNone};
}

}  // namespace cairn::mapping::internal
