#pragma once

#include <string>
#include <vector>

#include <mujoco/mujoco.h>

#include "common/grid_map.h"
#include "simulator/mujoco_model.h"

/// @file
/// Ground truth of a world's geometry as grid layers, for judging maps (`cairn-map eval`,
/// mapstore/map_eval.h). The world is loaded on its own (no robot, no spawn pool), doors are
/// set as cairn-sim starts them (open), and over every cell of a grid vertical rays are cast
/// downwards with MuJoCo's mj_ray from above the model's highest point (samples_per_side² per
/// cell, at the centres of equal sub-squares).
///
/// Peeling. After each hit the ray is cast again from 1 µm below it. What mj_ray (MuJoCo 2.2)
/// does from inside a geom: a primitive (box, sphere, capsule, cylinder, ellipsoid) or a mesh
/// returns its far side (the geom's bottom); a plane is hit from above only (solid below, within
/// its size when it has one); a height field returns, from below its surface, the surface
/// prism's base (its z = 0 level) and then the bottom of its base box. Where two surfaces lie at
/// the same distance mj_ray reports one of them and the peel never sees the other: the floor
/// under a box standing on it, a table leg whose top is the table top's underside and whose foot
/// is on the floor (the arena has both). So the peel tells which geoms a line meets, planes and
/// the geoms whose world footprint holds the line are added to them, and each is then measured
/// along the line with MuJoCo's ray routine for its type (mju_rayGeom, mj_rayHfield,
/// mj_rayMesh): its top from above, its bottom from below (a plane is solid all the way down, a
/// height field down to its base). That gives one solid span per geom (a mesh's span is from its
/// lowest to its highest surface on the line).
///
/// Ground and objects. Planes, height fields, and geoms whose world footprint is at least
/// terrain_min_extent_m along both x and y and at most terrain_max_height_m tall (the tunnel's
/// decks, ramps and platforms) are terrain; every other colliding geom is an object (walls,
/// furniture, rocks, and a solid building, whose roof is no ground). The ground of a
/// sample is the top of the lowest stack of terrain spans, each starting at most
/// stack_tolerance_m above the top of the one below (a deck on the ground plane, a ramp sunk
/// into a deck); terrain above a gap (a large slab overhead) is not ground. Geoms that do not
/// collide (contype and conaffinity 0) are ignored; colliding ones count whatever their group or
/// colour (a fully transparent one, which mj_ray skips, is found by its footprint).
///
/// Layers (world z in metres, NaN unknown):
/// - `truth/ground`: the mean ground height of the cell's samples that have ground;
/// - `truth/occupied`: 1 where at any sample some solid span meets
///   [ground + band_low_m, ground + band_high_m] of that sample, else 0; NaN where no sample
///   has ground (outside the world);
/// - `truth/top`: the highest surface over the cell's samples (NaN where no ray hits).

namespace cairn::sim {

inline constexpr char kTruthGroundLayer[] = "truth/ground";
inline constexpr char kTruthOccupiedLayer[] = "truth/occupied";
inline constexpr char kTruthTopLayer[] = "truth/top";

struct TruthRasterParams {
  /// Geometry between ground + band_low_m and ground + band_high_m occupies the cell (a robot
  /// body's height band: lower things are terrain detail, higher ones pass overhead).
  double band_low_m{0.05};
  double band_high_m{1.0};
  /// Rays per cell side (samples_per_side² per cell).
  int samples_per_side{3};
  /// Non-plane, non-height-field geoms at least this wide along both world x and y are terrain.
  double terrain_min_extent_m{3.0};
  /// ... and at most this tall (world z extent): a taller one is a building, an object.
  double terrain_max_height_m{2.0};
  /// A terrain span starting at most this far above the ground below it extends that ground.
  double stack_tolerance_m{0.01};
  /// Doors (hinge `door_<name>` with a position actuator) open, as cairn-sim starts them.
  bool open_doors{true};
  /// Threads casting (1: the calling thread only).
  int threads{1};

  /// @throws std::invalid_argument naming the first bad field.
  void Validate() const;
};

/// One solid stretch of a vertical line through a geom.
struct SolidSpan {
  double bottom_m{0.0};  ///< -inf below a plane
  double top_m{0.0};
  int geom{-1};
  bool terrain{false};
};

/// What a vertical line at one (x, y) meets.
struct ColumnProfile {
  std::vector<SolidSpan> spans;  ///< ordered by top, highest first
  double ground_m{0.0};          ///< NaN when no terrain lies under the line
  double top_m{0.0};             ///< highest surface; NaN when nothing is hit
};

/// A world model and the pose its geometry is judged in (doors set, kinematics done).
class GroundTruthWorld {
 public:
  /// Takes a compiled world (no robots needed) and brings its geometry to the start pose.
  GroundTruthWorld(MjModelPtr model, const TruthRasterParams& params);
  /// Loads an MJCF world file. @throws std::runtime_error with MuJoCo's message.
  static GroundTruthWorld FromFile(const std::string& path, const TruthRasterParams& params);
  /// Compiles MJCF text as if it were the file at `path` (assets resolve beside it).
  static GroundTruthWorld FromText(const std::string& xml, const std::string& path,
                                   const TruthRasterParams& params);

  /// The peeled profile of the vertical line at world (x_m, y_m).
  ColumnProfile Column(double x_m, double y_m) const;

  /// The truth layers over `grid`. @throws std::invalid_argument for an invalid grid.
  common::GridMap Rasterise(const common::GridGeometry& grid) const;

  const mjModel* model() const { return model_.get(); }
  const TruthRasterParams& params() const { return params_; }
  /// Height rays start from: 1 m above the highest point of the model.
  double ray_start_z_m() const { return start_z_m_; }
  bool is_terrain(int geom) const { return terrain_[geom] != 0; }

 private:
  MjModelPtr model_;
  MjDataPtr data_;
  TruthRasterParams params_;
  double start_z_m_{0.0};
  std::vector<char> terrain_;
  std::vector<char> solid_;  ///< collides with something
  struct Footprint {
    double x_lo{0}, x_hi{0}, y_lo{0}, y_hi{0};
  };
  std::vector<Footprint> footprint_;  ///< world x-y bounds per geom (planes: unused)
  std::vector<int> planes_;
};

/// Loads `world_path` and rasterises it over `grid`.
common::GridMap RasteriseGroundTruth(const std::string& world_path,
                                     const common::GridGeometry& grid,
                                     const TruthRasterParams& params = {});

}  // namespace cairn::sim
