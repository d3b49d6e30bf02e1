#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "common/grid_map.h"
#include "common/obstacle.h"
#include "services/mapping/obstacles.h"

/// @file
/// Shape measurements of the obstacle registry's features (internal to the mapping core):
/// statistics of a feature's values, the plane through its heights, its outline, and the numbers
/// in its verdicts' text.

namespace cairn::mapping::internal {

/// printf-style text of up to three numbers (verdict reasons: "step up 0.080 m > 0.030 m").
std::string FormatNumbers(const char* fmt, double a, double b = 0.0, double c = 0.0);
/// A heading (rad) in whole degrees in [0, 360) as the verdicts print it (359.5 and up is 0).
double HeadingDeg(double heading_rad);

/// Median (the mean of the two middle values for an even count); NaN for none.
double Median(std::vector<double> v);
/// Linear-interpolated percentile (q in [0, 1]); NaN for none.
double Percentile(std::vector<double> v, double q);

/// Slope (rad) of the least-squares plane z = a·x + b·y + c through the known heights of
/// `cells` (indices into `map`, x fastest); 0 when the fit is degenerate.
double PlaneSlope(const common::GridMap& map, const std::vector<int64_t>& cells);

/// The heading (rad, world frame) of travel down a ramp or step over `cells`: the mean of the
/// cells' downhill directions (the elevation's gradient over up to two cells either way), when
/// they agree (the mean is at least 0.7 long); NaN otherwise (a step around a block falls every
/// way).
double DownhillHeading(const common::GridMap& map, const std::vector<int64_t>& cells);

/// The outer boundary of a set of cells (indices into a grid `sx` cells wide) along the cell
/// edges, counter-clockwise, in cell corner coordinates, simplified to `tol` cells (Douglas-
/// Peucker). Cells touching at a corner stay one outline. Cells in several pieces (an object
/// whose faces were seen apart): the convex hull around all of them.
std::vector<common::Vector2> TraceOutline(const std::vector<int64_t>& cells, int sx, double tol);

/// Sorts the obstacles by centroid (y, then x) and numbers them from 1.
void NumberByCentroid(common::ObstacleRegistry* registry);

/// Measurements shared by every kind: centroid, outline, extents along the principal axes
/// (length, width), area and cell count.
void MeasureShape(const common::GridMap& map, const std::vector<int64_t>& cells,
                  const ObstacleParams& params, common::Obstacle* obstacle);

}  // namespace cairn::mapping::internal
