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

/// Writes nbv_summary.txt, nbv_navigability.png and nbv_quality.png into `dir` (created if
/// missing). Returns the paths written.
common::Result<std::vector<std::string>> WriteNbvReport(const NbvMission& mission,
                                                        const std::string& preset,
                                                        const std::string& dir);

}  // namespace cairn::explore
