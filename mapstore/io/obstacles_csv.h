#pragma once

#include <string>

#include "common/obstacle.h"
#include "common/status.h"

/// @file
/// CSV of obstacles: one obstacle per row with its measurements, outline and verdicts, and after
/// a terrace one row per part (`part_of` its id, `heading_in_rad` the way onto its platform); it
/// round-trips exactly. Formats: export and import "csv" (the export with a profile carries that
/// profile's verdicts).

namespace cairn::mapstore::io {

class FormatRegistry;

/// <stem>.csv: one obstacle per row, each terrace followed by its parts.
common::Result<std::string> WriteObstaclesCsv(const std::string& folder, const std::string& stem,
                                              const common::ObstacleRegistry& registry);
common::Result<common::ObstacleRegistry> ReadObstaclesCsv(const std::string& path);

/// Registers the csv export and import formats.
void RegisterObstaclesCsvFormats(FormatRegistry* registry);

}  // namespace cairn::mapstore::io
