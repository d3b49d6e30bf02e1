#pragma once

#include <string>
#include <vector>

#include "common/status.h"
#include "mapstore/io/format_registry.h"
#include "mapstore/map_store.h"

/// @file
/// Export of stored maps to files and import of files into new map versions, shared by the
/// `cairn-map` command line and the OP_EXPORT / OP_IMPORT requests of `cairn-mapstore`. The
/// formats are those of a format registry (mapstore/io/format_registry.h): the built-in ones
/// unless the caller passes its own.

namespace cairn::mapstore {

/// Writes the files and returns their paths. kNotFound for an unknown map, layer or profile,
/// or a map without OctoMap; kInvalidArgument for a format the registry does not hold or a
/// layer that cannot be written in that format.
common::Result<std::vector<std::string>> ExportMap(
    const MapStore& store, const ProfileDeriver* deriver, const ExportOptions& options,
    const io::FormatRegistry& formats = io::BuiltinFormats());

/// Imports a file as a new version of site/name, read by the importer `options.format` names
/// (or, without one, the importer of the file's extension). The new version starts from the
/// latest version's layers, obstacles and OctoMap when the format says so (a YAML map of the
/// latest's geometry; OctoMap and CSV files, which need an existing map: kNotFound otherwise)
/// and replaces what the file holds.
common::Result<MapInfo> ImportMap(MapStore& store, const ImportOptions& options,
                                  const WriteContext& ctx,
                                  const io::FormatRegistry& formats = io::BuiltinFormats());

}  // namespace cairn::mapstore
