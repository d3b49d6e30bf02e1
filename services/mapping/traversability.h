#pragma once

#include <optional>
#include <string>

#include "common/grid_map.h"
#include "common/robot_profile.h"

/// @file
/// Traversability from an elevation map (seed 000), per robot profile.
/// CONTRACT shared with the map store and the planner: keep these signatures.
///
/// Two stages:
/// 1. ComputeGeometricLayers: profile-independent layers from layers::kElevation (and, when
///    present, layers::kGroundBound): slope (PCA normal over a radius, slope = acos(n_z)),
///    step (largest height difference to a 4-neighbour), roughness (RMS residual of the plane
///    fit), the normal's horizontal components, and the ditch layers (cells inside a negative
///    obstacle, with the depth below its rims and the gap width).
/// 2. ComputeCostLayer: one profile's cost from those layers. The rules are the ones seed 000
///    intends (its text), not what its listing does:
///    - a cell is lethal if any rule says so (obstacle wins; the listing's first-match chain
///      let a cell be free or keep the previous cell's label);
///    - slope >= min(max_slope_up, max_slope_down) is lethal (the slope is unsigned, so a
///      non-directional grid must respect both limits);
///    - a 4-neighbour higher by more than max_step_up or lower by more than max_step_down is
///      lethal; the bounds are inclusive (exactly the limit is crossable) and every neighbour is
///      checked (the listing initialised only one of its four neighbour values);
///    - a neighbour the sensor looked into without a return (ground bound) counts as lower by at
///      least the bound's depth: a drop into an unseen gap is a step down;
///    - a ditch wider than max_ditch_width is lethal; narrower ones are bridged (graded);
///    - roughness above max_roughness is lethal;
///    - an unknown cell is free inside the blind zone around the robot's current position (the
///      listing used the centre of its robot-centric map window, on every update), else
///      unknown; a known cell with a neighbour outside the map is unknown;
///    - the directed layer beside the cost says which of a lethal cell's headings are refused:
///      one-way steps and slopes (see ComputeCostLayer);
///    - everything else gets 0 when it uses at most free_fraction of every limit, else a graded
///      cost in [1, graded_cost_max] growing with the most used limit, rounded to a whole number
///      (a ROS occupancy grid's values; the map store packs such a layer into bytes).

namespace cairn::common {
class YamlMap;
}  // namespace cairn::common

namespace cairn::mapping {

/// Layer names local to the terrain layers (the shared ones are in common/layers.h).
inline constexpr char kNormalXLayer[] = "normal_x";  ///< x component of the unit surface normal
inline constexpr char kNormalYLayer[] = "normal_y";  ///< y component (n_z = sqrt(1 - x² - y²))

struct TraversabilityParams {
  double normal_radius_m{0.3};  ///< PCA window for normals (3 x 3 cells at 0.2 m)
  /// Where the normal window cannot support a slope (fewer than min_normal_cells known cells,
  /// cells on one line, or a gradient standard error above max_slope_error_rad, estimated from
  /// the heights' scatter about the plane), the plane is fitted over this wider window instead
  /// (0.5 m: 21 cells at 0.2 m), when it holds more cells. Far or grazing ground seen by a few
  /// noisy rays: a 3 x 3 fit through heights with 1 cm of noise is off by about 1.2 deg.
  double wide_normal_radius_m{0.5};
  int min_normal_cells{6};
  /// 0.49: off. At 0.5 deg (0.0087) the outdoor world's far hills read better, but the cost
  /// beside the tunnel's cube flickered as scatter crossed the bounds, and the navigator
  /// replanned for ever (navigator_stack_test).
  double max_slope_error_rad{0.49};
  /// ... counting only scatter up to this (m) as noise: more is structure (a step, a block),
  /// which the normal window keeps sharp.
  double max_fit_noise_m{0.008};
  double blind_zone_half_size_m{0.5};  ///< cells within this of the robot count as free
  bool imu_pitch_compensation{false};  ///< add the robot's pitch to the map slope
  bool unknown_is_lethal{false};       ///< else unknown stays NaN in the cost layer
  double graded_cost_max{90.0};        ///< highest graded cost (free terrain costs 0)
  /// Terrain using at most this fraction of every profile limit costs 0 (free).
  double free_fraction{0.3};
  /// A gap is a ditch when the terrain in it lies at least this far below both rims (m).
  double min_ditch_depth_m{0.05};
  /// A gap is a ditch only when its depth below the rims, over half its width, is at least the
  /// tangent of this (its walls are steeper than this on average): a wide gentle dip seen only
  /// partly (a valley's shadow behind a crest) is natural ground, not a negative obstacle.
  double min_ditch_wall_slope_rad{0.087};
  /// How far (m) the ditch analysis looks for the rims on both sides of a gap; wider gaps are
  /// not recognised as ditches (they stay unknown).
  double max_ditch_search_m{1.8};
  /// A cell next to an unknown cell whose ground a ray proved at least this far below it (a
  /// drop whose bottom was never seen) is lethal for every profile: the bound is only a lower
  /// bound of the drop's depth, which grows as the robot nears the edge (seed 000: a gap the
  /// sensor cannot see into counts as a ditch, not as free). With the profile's step-down
  /// limit instead (0 here), a 20 cm drop reads lethal only once the sensor is within about a
  /// metre of its edge. Once the floor below is seen, the measured step decides.
  double unseen_drop_m{0.05};
  /// Slack on height comparisons (m), for float elevations: makes the inclusive bounds hold.
  double height_tolerance_m{1e-5};
  /// A step between two cells is lethal only when the edge is at least this many cells long:
  /// with 2, one of the two cell pairs beside it (across the same edge) must exceed the limit
  /// too. A real step edge is a line; a lone pair over the limit is elevation noise (a ramp
  /// near a profile's step limit at 0.2 m cells rises 1.75 cm per cell at 5 deg, and a few
  /// millimetres of noise on two cells make a false 3 cm step). This is the idea of
  /// traversability_estimation's critical_cell_number. 1 gives the seed's per-pair rule.
  int min_step_edge_cells{2};
  /// The directed layer lets a slope over one of the profile's slope limits be driven the way
  /// the other limit allows (down a slope too steep to climb) only up to this (rad, 20 deg):
  /// steeper cells are an object's flank, not ground, and block every heading. The Pioneer 3-AT
  /// has no downhill limit (seed 000), so without this bound a rock's side would read as a slope
  /// it may drive down.
  double max_one_way_slope_rad{0.35};

  /// @throws std::invalid_argument naming a bad field.
  void Validate() const;
};

/// Reads a `traversability` section (every key optional) over the defaults.
/// @throws common::ConfigError naming the file and line of a bad or unknown key.
TraversabilityParams LoadTraversabilityParams(common::YamlMap& map);

/// A half-open rectangle of cells [x0, x1) x [y0, y1).
struct CellRect {
  int x0{0};
  int y0{0};
  int x1{0};
  int y1{0};
  bool empty() const { return x1 <= x0 || y1 <= y0; }
  /// The whole grid.
  static CellRect All(const common::GridMap& map) { return {0, 0, map.size_x(), map.size_y()}; }
};

/// Where the robot is and how it is tilted, for the blind-zone rule and IMU compensation.
struct RobotContext {
  std::optional<common::Vector2> xy_m;  ///< world position (blind zone), none to skip the rule
  std::optional<double> yaw_rad;        ///< heading; lets the pitch tilt the normals exactly
  double pitch_rad{0.0};                ///< nose up positive (common::Pose3::pitch_rad)
};

/// Adds the profile-independent layers (layers::kSlope, kStepMax, kRoughness) computed from
/// layers::kElevation. @throws std::invalid_argument if the map has no elevation layer.
void ComputeGeometricLayers(common::GridMap* map, const TraversabilityParams& params);

/// As above, but writes only the cells of `rect` (the layers are created when missing). Cells
/// outside `rect` are read, never written, so computing a window of a larger map with enough
/// margin around `rect` gives the same values as computing the whole map.
void ComputeGeometricLayers(common::GridMap* map, const TraversabilityParams& params,
                            const CellRect& rect);

/// How far (cells) a geometric or cost value depends on its neighbours: a window computed with
/// this much margin around the written rectangle matches the whole-map computation.
int DependencyRadiusCells(const TraversabilityParams& params, double resolution_m);
/// How far (cells) a cell's cost reads the elevation and ground bound around it (through the
/// unknown cells past a drop), given the geometric layers.
int CostRadiusCells(double resolution_m);

/// Adds layers::CostLayer(profile.name): 0 free, [1, 99] graded (whole numbers), 100 lethal,
/// NaN unknown; and beside it layers::DirectedLayer(profile.name) (contract in common/layers.h):
/// NaN where the cost is NaN, 0 where it is below lethal, and for a lethal cell the headings it
/// may not be left towards. A step or drop to a 4-neighbour that is crossable the other way (an
/// 8 cm drop for a profile stepping 3 cm up and 10 cm down: the cell below refuses heading
/// "towards the platform") sets that heading's bit; a slope between the uphill and downhill
/// limits sets the bits of the headings that climb (or descend) it; every other reason (an edge
/// crossable neither way, an unseen drop, a ditch too wide, roughness, a slope over both limits
/// or max_one_way_slope_rad, an unknown cell read as lethal) gives layers::kAllHeadingsBlocked.
/// Computes the geometric layers first when they are missing. `robot_xy_m` applies the
/// blind-zone rule around the robot; `robot_pitch_rad` the IMU compensation when enabled.
/// Without a heading, the compensation is the seed's worst case (slope + pitch).
void ComputeCostLayer(common::GridMap* map, const common::RobotProfile& profile,
                      const TraversabilityParams& params,
                      std::optional<common::Vector2> robot_xy_m = std::nullopt,
                      double robot_pitch_rad = 0.0);

/// As above with the robot's heading (exact IMU compensation: the map normals and the offsets
/// to the neighbours are tilted by the pitch about the robot's lateral axis, so level ground
/// ahead of a pitched robot stays level instead of the seed's slope + pitch), writing only the
/// cells of `rect`. The geometric layers must exist; cells outside `rect` are only read.
/// @throws std::invalid_argument if they do not or the profile is invalid.
void ComputeCostLayer(common::GridMap* map, const common::RobotProfile& profile,
                      const TraversabilityParams& params, const RobotContext& robot,
                      const CellRect& rect);

}  // namespace cairn::mapping
