#pragma once

#include <string>
#include <vector>

#include "common/grid_map.h"
#include "common/obstacle.h"
#include "common/status.h"

/// @file
/// PNG renders of any layer with a legend (libpng): occupancy colours for cost and occupancy
/// layers, a colour bar with the value range for others; optionally a path and the obstacles
/// drawn over it. Format: export "png".

namespace cairn::mapstore::io {

class FormatRegistry;

/// Renders a layer to <stem>.png with a legend. Returns the path.
common::Result<std::string> WritePng(const std::string& folder, const std::string& stem,
                                     const common::GridMap& map, const std::string& layer);

/// A labelled point drawn over a rendered layer (a view point, a waypoint).
struct PngMarker {
  common::Vector2 position_m{0.0, 0.0};
  std::string label;  ///< "1", "2", ...: drawn beside the point
};

/// What can be drawn over a rendered layer (world frame).
struct PngOverlay {
  std::vector<common::Vector2> path_m;      ///< a driven or planned path (blue)
  std::vector<PngMarker> markers;           ///< labelled points (black squares)
  std::vector<common::Obstacle> obstacles;  ///< outlined and labelled "<id> <KIND>"
  /// Colours each obstacle by this profile's verdict: green crossable, red not (grey: no
  /// verdict or empty).
  std::string verdict_profile;
  std::string caption;  ///< a line under the legend
  int min_pixels{900};  ///< the larger side is scaled up to about this
};

/// WritePng with an overlay.
common::Result<std::string> WritePng(const std::string& folder, const std::string& stem,
                                     const common::GridMap& map, const std::string& layer,
                                     const PngOverlay& overlay);

/// Registers the png export format.
void RegisterPngFormats(FormatRegistry* registry);

}  // namespace cairn::mapstore::io
