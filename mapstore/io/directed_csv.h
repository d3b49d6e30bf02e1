#pragma once

#include <string>

#include "common/grid_map.h"
#include "common/status.h"

/// @file
/// The per-direction export of a profile's traversability: format "directed", a CSV of every
/// cell of "directed/<profile>" (common/layers.h) that refuses some heading, with the headings it
/// refuses. The cost layer that "ros" and "png" write is isotropic (the stricter value); this is
/// the file for whoever needs the one-way cells (an 8 cm drop the Pioneer may drive down and not
/// up).

namespace cairn::mapstore::io {

class FormatRegistry;

/// <stem>.csv: header "x_m,y_m,mask,refused_headings_deg"; one row per cell whose mask is
/// non-zero, at its centre (world frame), the refused headings world-frame degrees in [0, 360)
/// separated by ';', or "all" for 255. Rows in storage order (x fastest).
/// @throws nothing; kInvalidArgument when `layer` is not in `map`.
common::Result<std::string> WriteDirectedCsv(const std::string& folder, const std::string& stem,
                                             const common::GridMap& map, const std::string& layer);

/// Registers the "directed" export (needs --profile).
void RegisterDirectedCsvFormats(FormatRegistry* registry);

}  // namespace cairn::mapstore::io
