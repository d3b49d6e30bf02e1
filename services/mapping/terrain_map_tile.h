#pragma once

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "common/grid_map.h"
#include "common/layers.h"
#include "services/mapping/terrain_map.h"

/// @file
/// TerrainMap's tile and the helpers its two implementation files share (internal to the mapping
/// core): terrain_map.cc fuses measurements, terrain_map_derived.cc recomputes the derived layers
/// and exports windows.

namespace cairn::mapping {

namespace internal {

inline constexpr float kTerrainNaN = std::numeric_limits<float>::quiet_NaN();

inline int64_t FloorDiv(int64_t a, int64_t b) { return a >= 0 ? a / b : -((-a + b - 1) / b); }

inline CellRect Grow(const CellRect& r, int m) { return {r.x0 - m, r.y0 - m, r.x1 + m, r.y1 + m}; }

/// Derived layers that are not cost layers.
inline const std::vector<std::string>& GeometricLayers() {
  static const std::vector<std::string> names{
      layers::kSlope, layers::kStepMax,    layers::kRoughness, kNormalXLayer,
      kNormalYLayer,  layers::kDitchDepth, layers::kDitchWidth};
  return names;
}

/// The feature layers the registry is assembled from.
inline const std::vector<std::string>& FeatureLayers() {
  static const std::vector<std::string> names{kFeatureClassLayer, kFeatureEdgeLayer,
                                              kFeatureLowLayer, kFeatureHighLayer};
  return names;
}

}  // namespace internal

// One tile: every layer as a GridMap over the tile, plus the filter state that is not
// published (the unrounded filter height, the last scan per cell, the raw ground bound).
struct TerrainMap::Tile {
  common::GridMap layers;
  std::vector<float> filter_height;
  // Where the fused points lie in the cell, relative to its centre (weighted like the height):
  // a lidar at rest samples each cell along a few ring lines, off its centre.
  std::vector<float> hit_dx;
  std::vector<float> hit_dy;
  std::vector<float> raw_bound;
  std::vector<float> conflict_bound;  // as raw_bound, from rays ending two or more cells on
  std::vector<uint32_t> scan;         // low 32 bits of the scan id, 0 = none yet
  // 1 where the last commit carried the height to the cell's centre (CommitHeight): a cell
  // committed before its normal could be trusted is committed again once it can.
  std::vector<uint8_t> carried;
  float* elevation{nullptr};
  float* variance{nullptr};
  float* count{nullptr};
  float* last_seen{nullptr};
  float* bound{nullptr};
  const float* slope{nullptr};  // the derived slope and normal, once UpdateDerived wrote them
  const float* normal_x{nullptr};
  const float* normal_y{nullptr};
  int64_t base_version{0};
  int64_t derived_version{0};
};

}  // namespace cairn::mapping
