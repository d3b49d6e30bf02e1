#pragma once

#include <string>
#include <vector>

#include "common/grid_map.h"
#include "common/obstacle.h"
#include "common/status.h"
#include "mapstore/map_store.h"

/// @file
/// Files the map store exports and imports:
/// - ROS map_server maps: a YAML file and a binary PGM, in trinary, scale or raw mode, with the
///   map_server conventions (image row 0 is the top of the map, p = (255 - pixel) / 255,
///   occupied above occupied_thresh, free below free_thresh). Raw mode keeps 0..100 exactly
///   (255 = unknown); trinary keeps {free, occupied, unknown}; scale cannot say "unknown"
///   (a map_server limitation).
/// - PNG renders of any layer with a legend (libpng).
/// - OctoMap trees as .bt (binary) or .ot (full) files, converted with OctoMap when needed.
/// - CSV of obstacles with their measurements, outlines and verdicts (round-trips exactly).
/// Every writer takes a target folder and a plain file stem and never writes elsewhere: names
/// with '/' or "..", or an existing symlink in the folder, are refused. Files are written to a
/// temporary name and renamed, so a reader never sees half a file.

namespace cairn::mapstore::io {

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

/// Occupancy in percent (0..100, NaN unknown) of a layer: log-odds layers are converted to
/// probabilities, cost and occupancy layers are taken as they are (clamped). kInvalidArgument
/// for layers that are not occupancy-like (elevation, slope, ...).
common::Result<common::Layer> OccupancyPercent(const common::GridMap& map,
                                               const std::string& layer);

/// The path `folder`/`file_name` after checking that it stays inside `folder` (created if
/// missing) and is not a symlink or a directory.
common::Result<std::string> SafeOutputPath(const std::string& folder, const std::string& file_name);
/// Writes bytes atomically (temporary file + rename) to a path from SafeOutputPath.
common::Status WriteFileAtomically(const std::string& path, const std::string& bytes);
common::Result<std::string> ReadFile(const std::string& path, size_t max_bytes = 1u << 30);

/// Writes <stem>.yaml and <stem>.pgm; returns both paths.
common::Result<std::vector<std::string>> WriteRosMap(const std::string& folder,
                                                     const std::string& stem,
                                                     const common::GridGeometry& geometry,
                                                     const common::Layer& occupancy_percent,
                                                     const RosMapOptions& options = {});
/// Reads a map_server YAML (keys image, resolution, origin, mode, negate, occupied_thresh,
/// free_thresh; unknown keys are errors naming the line) and its PGM (P5 or P2).
common::Result<RosMap> ReadRosMap(const std::string& yaml_path);

/// Renders a layer to <stem>.png with a legend (occupancy colours for cost/occupancy layers, a
/// colour bar with the value range for others). Returns the path.
common::Result<std::string> WritePng(const std::string& folder, const std::string& stem,
                                     const common::GridMap& map, const std::string& layer);

/// What can be drawn over a rendered layer (world frame).
struct PngOverlay {
  std::vector<common::Vector2> path_m;        ///< a driven or planned path (blue)
  std::vector<common::Obstacle> obstacles;    ///< outlined and labelled "<id> <KIND>"
  /// Colours each obstacle by this profile's verdict: green crossable, red not (grey: no
  /// verdict or empty).
  std::string verdict_profile;
  std::string caption;                        ///< a line under the legend
  int min_pixels{900};                        ///< the larger side is scaled up to about this
};

/// WritePng with an overlay.
common::Result<std::string> WritePng(const std::string& folder, const std::string& stem,
                                     const common::GridMap& map, const std::string& layer,
                                     const PngOverlay& overlay);

/// <stem>.csv: one obstacle per row.
common::Result<std::string> WriteObstaclesCsv(const std::string& folder, const std::string& stem,
                                              const common::ObstacleRegistry& registry);
common::Result<common::ObstacleRegistry> ReadObstaclesCsv(const std::string& path);

/// <stem>.bt (binary = true) or <stem>.ot, converting the stored form when it differs.
common::Result<std::string> WriteOctomap(const std::string& folder, const std::string& stem,
                                         const OctomapData& octomap, bool binary);
/// Reads a .bt or .ot file and checks that OctoMap can parse it.
common::Result<OctomapData> ReadOctomap(const std::string& path);

}  // namespace cairn::mapstore::io
