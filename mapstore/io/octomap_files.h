#pragma once

#include <string>

#include "common/status.h"
#include "mapstore/map_store.h"

/// @file
/// OctoMap trees as .bt (binary) or .ot (full) files, converted through OctoMap when the stored
/// form differs. Formats: export and import "bt" and "ot".

namespace cairn::mapstore::io {

class FormatRegistry;

/// <stem>.bt (binary = true) or <stem>.ot, converting the stored form when it differs.
common::Result<std::string> WriteOctomap(const std::string& folder, const std::string& stem,
                                         const OctomapData& octomap, bool binary);
/// Reads a .bt or .ot file and checks that OctoMap can parse it.
common::Result<OctomapData> ReadOctomap(const std::string& path);

/// Registers the bt and ot export and import formats.
void RegisterOctomapFormats(FormatRegistry* registry);

}  // namespace cairn::mapstore::io
