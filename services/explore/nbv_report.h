#pragma once

#include <string>
#include <vector>

#include "common/status.h"
#include "services/explore/nbv_mission.h"

/// @file
/// What a next-best-view mission leaves behind: seed 002's summary table (distance, quality,
/// coverage, scans; one row per view point) and PNG renders of the information map (C_nc and
/// Q_a) with the driven path and the numbered view points.

namespace cairn::explore {

/// The summary table, lines ending in '\n': a header with the mission's figures, then one row
/// per scan (number, position, time, points, coverage, quality, zones).
std::string NbvSummaryTable(const NbvMission& mission, const std::string& preset);

/// The view points and the chosen paths as info-map nodes, CSV with a header line:
///   kind,index,x_m,y_m,level,ground_z_m,cnc_when_chosen,cnc_final
/// kind "view" (index: the scan's number; ground under the scanner) or "path" (index: the leg's
/// number, 1 for the way to scan 2; ground: the node's in the final map). cnc_when_chosen is the
/// node's C_nc when the leg was chosen, cnc_final its C_nc in the final map; "nan" where the node
/// was (or is) unexplored. Every safety claim of a mission (seed 002 test 25) is checkable here.
std::string NbvPathCsv(const NbvMission& mission);

/// Writes nbv_summary.txt, nbv_path.csv, nbv_navigability.png and nbv_quality.png into `dir`
/// (created if missing). Returns the paths written.
common::Result<std::vector<std::string>> WriteNbvReport(const NbvMission& mission,
                                                        const std::string& preset,
                                                        const std::string& dir);

}  // namespace cairn::explore
