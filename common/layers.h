#pragma once

#include <string>

/// @file
/// Names of grid-map layers and the cost convention shared by mapper, map store and planner.
///
/// Cost layers ("cost/<profile>") hold per cell: 0 free, a whole number in [1, 99] graded
/// (harder terrain costs more), 100 lethal, NaN unknown. This matches the ROS occupancy
/// convention (0..100, -1 unknown) that exports use, and a cost layer stored or sent by the map
/// store packs into one byte per cell without loss.

namespace cairn::layers {

// Robot-agnostic base layers (stored once per site).
/// Pseudo layer names a resend request may carry (they cannot be layer names): a mapper or a
/// push client asked for "#obstacles" sends its obstacle registry again, "#octomap" its OctoMap.
inline constexpr char kResendObstacles[] = "#obstacles";
inline constexpr char kResendOctomap[] = "#octomap";

inline constexpr char kElevation[] = "elevation";                   // m, world z
inline constexpr char kElevationVariance[] = "elevation_variance";  // m^2
inline constexpr char kObservationCount[] = "observation_count";    // fused measurements
inline constexpr char kLastSeen[] = "last_seen_s";                  // sim time, s
inline constexpr char kOccupancyLogOdds[] = "occupancy_logodds";    // 2-D log-odds
inline constexpr char kOccupancy[] = "occupancy";                   // 2-D occupancy, 100·p
inline constexpr char kStaticMap[] = "static";                      // 0..100, seed 001 static map
inline constexpr char kShortTerm[] = "short_term";                  // 0..100
inline constexpr char kLongTerm[] = "long_term";                    // 0..100
inline constexpr char kFinal[] = "final";                           // max(short, long)
// Lowest height at which a lidar ray crossed the cell without a return (m, world z): the
// terrain there lies below it. Lets the terrain layers tell a gap the sensor saw into (a ditch)
// from one it never looked at.
inline constexpr char kGroundBound[] = "ground_bound";
// The imaging sonar's obstacles (seed 004), 0..100 percent, NaN unknown: the base layer of an
// AUV's map, scanned in the plane of the vehicle's depth.
inline constexpr char kSonarOccupancy[] = "sonar/occupancy";

// Geometric layers derived from the elevation (profile independent).
inline constexpr char kSlope[] = "slope";             // rad, unsigned
inline constexpr char kStepMax[] = "step";            // m, largest height difference to a neighbour
inline constexpr char kRoughness[] = "roughness";     // m, residual of the local plane fit
inline constexpr char kDitchDepth[] = "ditch_depth";  // m below the rims (a lower bound if unseen)
inline constexpr char kDitchWidth[] = "ditch_width";  // m, gap between the rims

inline std::string CostLayer(const std::string& profile) { return "cost/" + profile; }
inline bool IsCostLayer(const std::string& name) { return name.rfind("cost/", 0) == 0; }

// Directed traversability ("directed/<profile>"), the companion of the cost layer. Per cell: NaN
// where the cost is NaN; otherwise a whole number in [0, 255] (or kUnseenDrop, below) whose bit k
// is set when the profile may not drive out of the cell towards heading k * 45 degrees (grid frame,
// counter-clockwise from +x: bit 0 is +x, bit 2 is +y, odd bits reach the diagonal neighbours),
// because the step or the slope that way exceeds the profile's limit for that direction (step up or
// down, slope up or down). kAllHeadingsBlocked marks a cell that no heading may cross for a reason
// that does not depend on the direction (an object, a ditch too wide, roughness, an unseen drop
// already proven deeper than the step down).
// The cost layer stays isotropic: it is lethal wherever this layer is non-zero (the stricter
// value), so exports and renders keep one number per cell; planners that read both may cross a
// one-way cell in the headings it allows.
inline std::string DirectedLayer(const std::string& profile) { return "directed/" + profile; }
inline bool IsDirectedLayer(const std::string& name) { return name.rfind("directed/", 0) == 0; }
inline constexpr int kHeadingBins = 8;
inline constexpr float kAllHeadingsBlocked = 255.f;
// kUnseenDrop marks a cell blocked every way because beside it the ground falls out of sight
// (the rays over the unknown cells beyond prove a drop of at least unseen_drop_m, but not how
// deep): lethal like kAllHeadingsBlocked for whoever reads a value above 255 as 255, and a cell
// that a planner may treat as unknown ground to go and look (planner/README.md, "Unseen drops").
inline constexpr float kUnseenDrop = 256.f;

inline constexpr float kCostFree = 0.f;
inline constexpr float kCostLethal = 100.f;

}  // namespace cairn::layers
