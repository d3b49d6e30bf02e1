#pragma once

#include <cstdint>
#include <limits>
#include <optional>

#include "services/mapping/traversability.h"

/// @file
/// The ditch stage of ComputeGeometricLayers (internal to the mapping core): negative obstacles
/// found from the elevation and the ground bound the rays left over gaps they looked into.

namespace cairn::mapping::internal {

/// How far (cells) the ditch analysis looks for a gap's rims (max_ditch_search_m).
int DitchSearchCells(const TraversabilityParams& params, double resolution_m);

/// A read-only view of the layers the ditch analysis needs.
struct TerrainView {
  const float* h;      ///< elevation
  const float* bound;  ///< ground bound, or nullptr
  int sx;
  int sy;
  bool Inside(int x, int y) const { return x >= 0 && y >= 0 && x < sx && y < sy; }
  float H(int x, int y) const { return h[x + static_cast<int64_t>(y) * sx]; }
  float B(int x, int y) const {
    return bound ? bound[x + static_cast<int64_t>(y) * sx]
                 : std::numeric_limits<float>::quiet_NaN();
  }
};

/// A ditch whose bottom the sensor saw: the depth of the bottom cell below the lower rim and the
/// narrowest width between the rims (m).
struct SeenBottom {
  double depth_m;
  double width_m;
};

/// The ditch test of an unseen cell applied to a known one: (x, y) lies in a gap whose rims, along
/// x, y or a diagonal, both stand at least min_ditch_depth_m above its height, with ground at
/// rim level beyond them, and the gap is no valley (the flanks continued into it stay above it)
/// nor a gentle dip (min_ditch_wall_slope_rad). Here max_ditch_search_m bounds the gap's width
/// (the narrowest line's) as well as the search.
std::optional<SeenBottom> TestSeenBottom(const TerrainView& view, int x, int y,
                                         const TraversabilityParams& params, double resolution_m);

/// Writes layers::kDitchDepth and layers::kDitchWidth for the cells of `rect` (NaN where no
/// ditch), reading up to 2 * DitchSearchCells + 2 cells around it. Pass 1: unknown cells the
/// sensor looked into (a finite ground bound) whose rims stand above that bound, and the unknown
/// cells on their gap segments; pass 2: known cells sharing a gap with such a cell whose rims
/// stand high enough above them (the ditch's bottom).
void ComputeDitchLayers(const TerrainView& view, const TraversabilityParams& params,
                        double resolution_m, const CellRect& rect, float* ditch_depth,
                        float* ditch_width);

}  // namespace cairn::mapping::internal
