#pragma once

#include <string>
#include <vector>

#include "common/status.h"
#include "mapstore/map_io.h"
#include "mapstore/map_store.h"

/// @file
/// Export of stored maps to files and import of files into new map versions, shared by the
/// `cairn-map` command line and the OP_EXPORT / OP_IMPORT requests of `cairn-mapstore`.

namespace cairn::mapstore {

struct ExportOptions {
  MapRef ref;
  /// "ros" (YAML + PGM, mode from `ros.mode`), "png", "bt", "ot" or "csv".
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

/// Writes the files and returns their paths. kNotFound for an unknown map, layer or profile,
/// or a map without OctoMap; kInvalidArgument for a bad format or a layer that cannot be
/// written in that format.
common::Result<std::vector<std::string>> ExportMap(const MapStore& store,
                                                   const ProfileDeriver* deriver,
                                                   const ExportOptions& options);

struct ImportOptions {
  /// A map_server .yaml (with its PGM), an OctoMap .bt/.ot, or an obstacle .csv.
  std::string path;
  std::string site{kDefaultSite};
  std::string name;
  std::string layer{"static"};  ///< the layer that receives a YAML + PGM map's occupancy
  Provenance provenance;
};

/// Imports a file as a new version of site/name. The new version starts from the latest
/// version's layers, obstacles and OctoMap when its geometry matches (a YAML map of another
/// geometry starts empty) and replaces what the file holds. OctoMap and CSV files need an
/// existing map (kNotFound otherwise).
common::Result<MapInfo> ImportMap(MapStore& store, const ImportOptions& options,
                                  const WriteContext& ctx);

/// Choice of the default export layer, see ExportOptions::layer.
common::Result<std::string> DefaultExportLayer(const MapInfo& info, const std::string& format,
                                               const std::string& profile);

}  // namespace cairn::mapstore
