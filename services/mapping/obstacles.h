#pragma once

#include <vector>

#include "common/grid_map.h"
#include "common/obstacle.h"
#include "common/robot_profile.h"
#include "services/mapping/traversability.h"

/// @file
/// The obstacle registry: connected terrain features with their measurements, and per-profile
/// verdicts computed from those measurements alone (so a stored registry can be re-labelled for
/// any profile without the elevation). CONTRACT shared with the map store: keep these signatures.
///
/// Features are found from the elevation and the geometric layers (traversability.h), never
/// from a profile:
/// - ditch: cells of a negative obstacle (layers::kDitchDepth), with the unseen gap and the
///   bottom the sensor saw, and trenches whose whole bottom was seen (seen_ditch_max_width_m);
///   width is the gap between the rims (the lower quartile of its cells' narrowest lines),
///   depth NaN when no bottom cell was seen;
/// - step (up or down): a height difference over one or two cells along x or y (two when a
///   vertical face left an intermediate height in the cell it cuts) that stands out from the
///   differences just before and after it along the same line (a ramp rises evenly, a step
///   does not), plus drops into a gap the sensor looked into; up when it rises from the larger
///   of the two surfaces it separates (see surface_continuity_m), down when it falls from it;
/// - wall_or_object: the same discontinuities, at least wall_min_height_m high;
/// - ramp: inclined cells away from any edge that meet flatter ground at creases (a hillside is
///   terrain, not a ramp: see min_ramp_crease_fraction); its slope is the larger of the sustained
///   slope (75th percentile of the interior cells, so a steep section is not averaged away) and the
///   slope of the plane fitted to its heights (robust where only part of it was seen).
/// - terrace: the ramps and steps that lead onto one raised level platform, one entry with those
///   as its parts (terraces.h); its verdict is the whole's: crossable, one-way (onto it over one
///   part, off over another) or blocked.

namespace cairn::common {
class YamlMap;
}  // namespace cairn::common

namespace cairn::mapping {

struct ObstacleParams {
  double min_ramp_slope_rad{0.035};  ///< slopes below this are flat ground
  /// Height differences below this are not steps. The shipped mapper config raises it to 1.5 cm
  /// for the HDL-32E: under that, what the map holds is its range noise (1.8 cm) and the pose's
  /// small tilt errors between revolutions, seen as millimetre-high "steps" along lidar rings on
  /// smooth ground (the outdoor world listed a dozen of them).
  double min_step_height_m{0.006};
  int min_cells{4};  ///< smaller components are noise ...
  /// ... unless they stand this high (m) over two cells or more: a small rock seen from afar
  /// as two or three cells of its face. <= 0: min_cells alone.
  double min_small_feature_height_m{0.1};
  /// A height difference is a step when it exceeds this multiple of the differences just
  /// before and after it along the same line.
  double step_contrast{1.5};
  /// A height difference is a step only when it exceeds this many standard deviations of
  /// itself: both cells' elevation variances plus the spread of a sloped cell's height across
  /// the cell (a lidar ring's returns on an incline land anywhere in it). On a hillside seen at
  /// grazing angles that is a centimetre or two; on level, well-observed floor a few
  /// millimetres. 0 turns the test off.
  double step_noise_sigmas{3.0};
  /// Discontinuities at least this high are walls or objects, not steps.
  double wall_min_height_m{0.3};
  /// Walls and objects whose cells come this close (m), with no floor seen between them, are one
  /// object: the faces of a house or a rock seen as pieces, with unseen, raised or unclassified
  /// cells between them (the shipped config: 0.6). Two walls with floor seen between them (a
  /// doorway) stay two. Whether two pieces join depends on the cells at the limit, so two maps
  /// of one recording (live and replayed) may list one object as one entry or two; both cover
  /// the same cells. 0 (the default): off.
  double object_join_gap_m{0.0};
  /// Two wall pieces in one line, each running on for at least object_opening_run_m along the
  /// line between their ends, with an opening up to this wide (m) between them, are one wall with
  /// a doorway (a house's front and its door). The cost layer keeps the doorway open; the entry's
  /// outline is the hull of its pieces. 0 (the default): off; the shipped config: 1.5.
  double object_opening_max_m{0.0};
  double object_opening_run_m{0.8};
  /// A drop into a gap the sensor looked into counts from this depth (m).
  double min_drop_height_m{0.05};
  /// Steps lower than this must be edge lines (at least min_small_step_length_m long and
  /// min_small_step_elongation times longer than wide): a compact patch of centimetre
  /// differences is lidar noise, not a step.
  double small_step_height_m{0.02};
  double min_small_step_length_m{1.0};
  double min_small_step_elongation{2.0};
  /// Ramps smaller than this are the rims of other features, not ramps (m²).
  double min_ramp_area_m2{0.5};
  /// A ramp meets flatter ground: of the featureless ground two cells beyond its edge, at least
  /// this fraction slopes at most half as much as the ramp (its foot and top, where a built
  /// ramp creases). Inclined ground that fades out into ground almost as steep is a hillside,
  /// terrain rather than a feature (the cost layer still judges its slope). 0: every incline.
  double min_ramp_crease_fraction{0.25};
  /// Neighbouring cells closer in height than this lie on one surface (m). A step rises from
  /// the larger surface it separates onto the smaller one (a block on the ground is a step up,
  /// the edge of a raised platform a step down).
  double surface_continuity_m{0.05};
  /// The widest ditch (m) whose bottom the sensor saw that the registry lists as one: a trench
  /// between two rims at least min_drop_height_m above its floor, with ground at rim level
  /// beyond them (the cost layer judges such a floor by its steps). Wider gaps are floors
  /// between raised ground. 0: only ditches with an unseen gap are listed.
  double seen_ditch_max_width_m{1.2};
  /// The largest platform (m²) whose ramps and faces are one registry entry, a terrace with its
  /// parts (a ramp, the platform it leads onto and the drop at the far end; a slab and its faces):
  /// a level region outside every feature, not the ground (the largest such region), that two or
  /// more ramps or steps reach at their high side. Larger raised regions are ground whose edges
  /// are listed one by one. 0: off.
  double max_terrace_area_m2{100.0};
  /// Outline simplification tolerance, as a fraction of the resolution.
  double outline_tolerance_cells{0.5};

  /// @throws std::invalid_argument naming a bad field.
  void Validate() const;
};

/// Reads an `obstacles` section (every key optional) over the defaults.
/// @throws common::ConfigError naming the file and line of a bad or unknown key.
ObstacleParams LoadObstacleParams(common::YamlMap& map);

/// Per-cell feature layers (internal to the mapping core; kept in the live map so the registry
/// can be assembled without classifying every cell again).
inline constexpr char kFeatureClassLayer[] = "feature_class";  ///< 0 none, 1 ditch, 2 wall,
                                                               ///< 3 step, 4 drop, 5 ramp
inline constexpr char kFeatureEdgeLayer[] = "feature_edge";    ///< largest discontinuity (m)
inline constexpr char kFeatureLowLayer[] = "feature_low";      ///< its lower side (m, world z)
inline constexpr char kFeatureHighLayer[] = "feature_high";    ///< its higher side

/// Classifies the cells of `rect` into the feature layers, from the elevation, the geometric
/// layers and the ground bound. Reads up to FeatureRadiusCells() around `rect`.
/// @throws std::invalid_argument if a needed layer is missing.
void ComputeFeatureLayers(common::GridMap* map, const ObstacleParams& params, const CellRect& rect);
/// How far (cells) a feature cell depends on the elevation and geometric layers around it.
inline constexpr int FeatureRadiusCells() { return 4; }

/// Connected components of the feature layers, measured; no verdicts yet.
/// @throws std::invalid_argument if a needed layer is missing.
common::ObstacleRegistry AssembleObstacles(const common::GridMap& map,
                                           const ObstacleParams& params);

/// Finds features in a map holding elevation and the geometric layers; no verdicts yet.
/// Missing geometric layers are computed (with default TraversabilityParams) on a copy.
/// Obstacles are numbered from 1 in the order of their centroids (y, then x).
common::ObstacleRegistry ExtractObstacles(const common::GridMap& map, const ObstacleParams& params);

/// Whether `profile` can cross `obstacle`, with the reason when not:
/// ramp: slope < min(max_slope_up, max_slope_down); step up: height <= max_step_up;
/// step down: height <= max_step_down; ditch: width <= max_ditch_width (bridged) or a seen
/// bottom no deeper than both step limits; wall or object: height <= max_step_up; terrace: from
/// its parts (each judged onto the platform against the up limits and off it against the down
/// limits): crossable when two parts may be driven both ways, one-way when one part leads onto it
/// and another off it, else blocked.
/// LabelObstacles also labels each part of a terrace.
common::ObstacleVerdict JudgeObstacle(const common::Obstacle& obstacle,
                                      const common::RobotProfile& profile);

/// The verdicts of a terrace's parts for `profile`, one per part in order (none for other
/// kinds): crossable when the profile may drive the part both ways, one-way when onto the
/// platform or off it only.
std::vector<common::ObstacleVerdict> JudgeParts(const common::Obstacle& obstacle,
                                                const common::RobotProfile& profile);

/// Replaces each obstacle's verdict for each of `profiles` (other verdicts are kept), and each
/// part's.
void LabelObstacles(common::ObstacleRegistry* registry,
                    const std::vector<common::RobotProfile>& profiles);

}  // namespace cairn::mapping
