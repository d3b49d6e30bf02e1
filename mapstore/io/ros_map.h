#pragma once

#include <string>
#include <vector>

#include "common/grid_map.h"
#include "common/status.h"

/// @file
/// ROS map_server maps: a YAML file and a binary PGM, in trinary, scale or raw mode, with the
/// map_server conventions (image row 0 is the top of the map, p = (255 - pixel) / 255,
/// occupied above occupied_thresh, free below free_thresh). Raw mode keeps 0..100 exactly
/// (255 = unknown); trinary keeps {free, occupied, unknown}; scale cannot say "unknown" (a
/// map_server limitation).
///
/// Formats: export "ros" (the mode from ExportOptions::ros), "ros-trinary", "ros-scale",
/// "ros-raw"; import "ros" (.yaml, .yml; hand-drawn P2/P5 images too).

namespace cairn::mapstore::io {

class FormatRegistry;

enum class PgmMode { kTrinary, kScale, kRaw };
const char* PgmModeName(PgmMode mode);
common::Result<PgmMode> PgmModeFromName(const std::string& name);

struct RosMapOptions {
  PgmMode mode{PgmMode::kTrinary};
  double occupied_thresh{0.65};
  double free_thresh{0.196};  ///< map_saver's value: 205 (unknown) stays unknown on reload
};

/// A map read from a map_server YAML + PGM: occupancy in 0..100, NaN unknown.
struct RosMap {
  common::GridGeometry geometry;
  common::Layer occupancy;
  RosMapOptions options;
  std::string image_path;
};

/// Writes <stem>.yaml and <stem>.pgm; returns both paths.
common::Result<std::vector<std::string>> WriteRosMap(const std::string& folder,
                                                     const std::string& stem,
                                                     const common::GridGeometry& geometry,
                                                     const common::Layer& occupancy_percent,
                                                     const RosMapOptions& options = {});
/// Reads a map_server YAML (keys image, resolution, origin, mode, negate, occupied_thresh,
/// free_thresh; unknown keys are errors naming the line) and its PGM (P5 or P2).
common::Result<RosMap> ReadRosMap(const std::string& yaml_path);

/// Registers the ros export formats and the ros import format.
void RegisterRosFormats(FormatRegistry* registry);

}  // namespace cairn::mapstore::io
