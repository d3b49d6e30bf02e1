#pragma once

#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "common/grid_map.h"
#include "common/obstacle.h"
#include "common/status.h"
#include "mapstore/io/ros_map.h"
#include "mapstore/map_store.h"

/// @file
/// The seam where the map store's file formats grow: exporters and importers registered by
/// format name. `cairn-map export --format F`, OP_EXPORT's `format`, `cairn-map import` and
/// OP_IMPORT find their format here (ExportMap and ImportMap in mapstore/map_transfer.h), and
/// `cairn-map export --help` lists what is registered.
///
/// Each format lives in one file under mapstore/io/ with a `Register<Format>Formats` function;
/// mapstore/io/builtin_formats.cc calls them all (see mapstore/README.md, "Adding an export
/// format").

namespace cairn::mapstore {

/// What an export is asked for.
struct ExportOptions {
  MapRef ref;
  /// A registered export format: "ros" (YAML + PGM, mode from `ros.mode`), "ros-trinary",
  /// "ros-scale", "ros-raw", "png", "bt", "ot", "csv", ...
  std::string format{"ros"};
  std::string folder;  ///< files are written here and nowhere else
  /// ros/png: the layer to write. Default: cost/<profile> when a profile is given, else for ros
  /// the first of final, static, occupancy, occupancy_logodds, long_term, short_term, and for
  /// png elevation (or the first layer).
  std::string layer;
  std::string profile;  ///< derive this profile's layers (and, for csv, its verdicts)
  io::RosMapOptions ros;
  std::string stem;  ///< file stem; default "<map>_v<version>" (+ "_<layer>" for ros/png)
};

/// What an import is asked for.
struct ImportOptions {
  /// A map_server .yaml (with its PGM), an OctoMap .bt/.ot, or an obstacle .csv: any file a
  /// registered importer reads.
  std::string path;
  std::string format;  ///< a registered import format; "" = by the file's extension
  std::string site{kDefaultSite};
  std::string name;
  std::string layer{"static"};  ///< the layer that receives a YAML + PGM map's occupancy
  Provenance provenance;
};

namespace io {

/// An export under way: the stored version and what was asked, with what most formats need.
class ExportContext {
 public:
  ExportContext(const MapStore& store, const ProfileDeriver* deriver, MapInfo info,
                const ExportOptions& options);

  const MapInfo& info() const { return info_; }
  const ExportOptions& options() const { return options_; }
  const MapStore& store() const { return store_; }
  const ProfileDeriver* deriver() const { return deriver_; }
  /// The file stem: the caller's, else "<map>_v<version>" followed by "_<suffix>" when a
  /// suffix is given ('/' in it becomes '_').
  std::string Stem(const std::string& suffix = "") const;
  /// The layer asked for; else cost/<profile> with a profile; else the first of `preferred`
  /// the version has; else, with `or_first_layer`, its first layer (kNotFound when it has
  /// none), otherwise kInvalidArgument saying `why_none`.
  common::Result<std::string> ChooseLayer(const std::vector<std::string>& preferred,
                                          bool or_first_layer,
                                          const std::string& why_none = "") const;
  /// One layer (base or derived for the profile) of the version; the name is validated.
  common::Result<common::GridMap> LoadLayer(const std::string& layer) const;
  /// The stored obstacles, with the profile's verdicts when one is given.
  common::Result<common::ObstacleRegistry> Obstacles() const;
  common::Result<OctomapData> Octomap() const;

 private:
  const MapStore& store_;
  const ProfileDeriver* deriver_;
  MapInfo info_;
  const ExportOptions& options_;
};

/// An import under way: the new version being built from the latest one and the file.
class ImportTarget {
 public:
  ImportTarget(MapStore& store, const ImportOptions& options, std::optional<MapInfo> latest);

  const ImportOptions& options() const { return options_; }
  /// The latest version of the map, if there is one.
  const std::optional<MapInfo>& latest() const { return latest_; }
  /// The new version starts as a copy of the latest: its layers, obstacles and OctoMap (and,
  /// when the import names no robot, its source robot and profile). kNotFound when there is no
  /// map yet (for data that need a grid map first).
  common::Status StartFromLatest();
  /// What will be saved.
  MapSnapshot& snapshot() { return snapshot_; }

 private:
  MapStore& store_;
  const ImportOptions& options_;
  std::optional<MapInfo> latest_;
  MapSnapshot snapshot_;
};

/// A format files can be written in.
struct ExportFormat {
  std::string name;     ///< what --format says: "png"
  std::string summary;  ///< one line for --help: "PNG render of a layer with a legend"
  /// Writes the files and returns their paths. kNotFound for a missing layer, profile or
  /// OctoMap, kInvalidArgument for a layer the format cannot hold.
  std::function<common::Result<std::vector<std::string>>(const ExportContext&)> write;
};

/// A format files can be read from.
struct ImportFormat {
  std::string name;                     ///< "ros"
  std::vector<std::string> extensions;  ///< lower case, with the dot: {".yaml", ".yml"}
  std::string summary;                  ///< "map_server YAML + PGM into --layer"
  /// Reads `path` into the new version (target.snapshot()).
  std::function<common::Status(const std::string& path, ImportTarget& target)> read;
};

/// Formats by name. Registering a name twice is a bug (std::invalid_argument).
class FormatRegistry {
 public:
  void AddExporter(ExportFormat format);
  void AddImporter(ImportFormat format);
  const ExportFormat* FindExporter(const std::string& name) const;
  const ImportFormat* FindImporter(const std::string& name) const;
  /// The importer of a file by its extension (case-insensitive); null when none reads it.
  const ImportFormat* ImporterForPath(const std::string& path) const;
  /// Registered names, sorted.
  std::vector<std::string> ExportNames() const;
  std::vector<std::string> ImportNames() const;
  const std::map<std::string, ExportFormat>& exporters() const { return exporters_; }
  const std::map<std::string, ImportFormat>& importers() const { return importers_; }

 private:
  std::map<std::string, ExportFormat> exporters_;
  std::map<std::string, ImportFormat> importers_;
};

/// Every built-in format (mapstore/io/builtin_formats.cc), registered once.
const FormatRegistry& BuiltinFormats();
/// Adds the built-in formats to a registry (a test adds its own beside them).
void RegisterBuiltinFormats(FormatRegistry* registry);

}  // namespace io
}  // namespace cairn::mapstore
