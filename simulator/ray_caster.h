#pragma once

#include <cstdint>
#include <vector>

#include <mujoco/mujoco.h>

#include "simulator/thread_pool.h"
#include <Eigen/Core>

/// @file
/// Ray casting for the simulated range sensors, on MuJoCo's own ray-geom intersection routines
/// (mju_rayGeom, mj_rayHfield, mj_rayMesh), with a broad phase that MuJoCo 2.2's mj_ray lacks:
///
/// - RayScene keeps a world-aligned bounding box per sensor-visible geom, refreshed after the
///   physics moved things;
/// - a RayPattern splits a sensor's rays into groups of neighbouring directions; for each group,
///   only the geoms whose box meets the pyramid holding the group's rays within range are
///   considered, sorted by distance, so a ray stops testing as soon as the nearest hit is
///   closer than the next candidate's box, or it has left the candidates' height range;
/// - each ray first retries the geom hit by its neighbour (coherence).
///
/// Results equal a plain mj_ray loop over the same rays (tested), at a fraction of the cost.
/// Casting reads a const model and data and is safe from several threads at once.

namespace cairn::sim {

/// The sensor-visible geometry of a scene.
class RayScene {
 public:
  /// Geoms are visible when their group is below 4 and their colour is not fully transparent
  /// (mj_ray's rule); planes and height fields always are.
  explicit RayScene(const mjModel* model);
  RayScene(const RayScene&) = delete;
  RayScene& operator=(const RayScene&) = delete;

  /// Marks a geom as belonging to robot `owner` (>= 0) so that robot's sensors skip it.
  void SetOwner(int geom, int owner);
  /// Shows or hides a geom for every sensor (spawned and removed objects).
  void SetVisible(int geom, bool visible);
  bool visible(int geom) const { return visible_[geom] != 0; }
  /// Recomputes the bounding boxes from the current poses (after mj_step or mj_kinematics).
  void Update(const mjData* data);

  const mjModel* model() const { return model_; }

  struct Bound {
    int geom{-1};
    int type{0};
    int owner{-1};
    bool infinite{false};  ///< planes: no box, always a candidate
    bool exact{false};     ///< an axis-aligned box: the bounding box is the geom itself
    double lo[3]{0, 0, 0};
    double hi[3]{0, 0, 0};
    double center[3]{0, 0, 0};
    double radius{0};
  };
  const std::vector<Bound>& bounds() const { return bounds_; }

 private:
  const mjModel* model_;
  std::vector<uint8_t> visible_;
  std::vector<int> owner_;
  std::vector<Bound> bounds_;
};

/// Ray directions of a sensor in its own frame, grouped for the broad phase.
struct RayPattern {
  struct Group {
    int begin{0};
    int end{0};
    Eigen::Vector3d axis{Eigen::Vector3d::UnitX()};  ///< unit, sensor frame
    /// A pyramid with its apex at the sensor holding every ray of the group: a direction d
    /// belongs to it when d . planes[k] <= 0 for all k (sensor frame). Unused when !bounded.
    Eigen::Vector3d planes[4];
    bool bounded{false};
  };
  std::vector<Eigen::Vector3d> directions;  ///< unit vectors, sensor frame
  std::vector<Group> groups;
  /// Ray i retries the geom hit by ray i - warm_stride of the same group first.
  int warm_stride{1};
  /// The directions again, as three arrays (x, y, z) of directions.size() + 4 doubles each (the
  /// last direction repeated), so that four neighbouring rays load at once. Set by BuildGroups
  /// and BuildComponents; when it is out of date, casting gathers the directions (slower).
  std::vector<double> components;

  /// Splits the directions into consecutive groups of `group_size` rays and computes each
  /// group's bounding pyramid; fills `components`.
  void BuildGroups(int group_size);
  /// Fills `components` from `directions` (for patterns whose groups are made by hand).
  void BuildComponents();
};

/// Ray against a height-field geom: the same surface as mj_rayHfield (two triangles per cell,
/// split along the (r, c)-(r+1, c+1) diagonal, over a base box), found by walking the cells
/// under the ray in order instead of testing every cell of the ray's bounding rectangle.
/// Returns the distance along the unit direction `vec`, or -1.
double RayHeightField(const mjModel* model, const mjData* data, int geom, const double pnt[3],
                      const double vec[3]);

/// One ray's result: distance to the first surface, or -1 when nothing is hit within range.
struct RayHit {
  double range_m{-1.0};
  int geom{-1};
};

/// Casts sensor patterns against a RayScene.
class RayCaster {
 public:
  /// @param pool optional; with it, groups are cast in parallel.
  /// @param lanes rays cast together (SIMD): 2, or 4 where the processor has AVX2; 0 (the
  ///     default) takes the most the processor has, and 4 where it has not falls back to 2.
  explicit RayCaster(ThreadPool* pool = nullptr, int lanes = 0);

  /// Rays this caster casts together.
  int lanes() const { return lanes_; }
  /// The most rays cast together on this processor: 4 with AVX2 (x86-64), 2 otherwise.
  static int MostLanes();

  /// Casts groups [group_begin, group_end) of `pattern` from a sensor at `origin` with
  /// orientation `rotation` (sensor to world). Results go to hits[ray index - hits_base] (a
  /// buffer holding just the rays cast, e.g. one lidar slice, with hits_base its first ray);
  /// rays of other groups are untouched. Geoms owned by `exclude_owner` are skipped (-1: none).
  void Cast(const RayScene& scene, const mjData* data, const Eigen::Vector3d& origin,
            const Eigen::Matrix3d& rotation, const RayPattern& pattern, int group_begin,
            int group_end, double max_range_m, int exclude_owner, RayHit* hits,
            int hits_base = 0) const;

  /// The reference: MuJoCo's mj_ray for each ray of the groups (geom groups 0-2 only, so every
  /// robot is excluded), single-threaded.
  static void CastWithMjRay(const mjModel* model, const mjData* data, const Eigen::Vector3d& origin,
                            const Eigen::Matrix3d& rotation, const RayPattern& pattern,
                            int group_begin, int group_end, double max_range_m, RayHit* hits,
                            int hits_base = 0);

 private:
  void CastGroup(const RayScene& scene, const mjData* data, const Eigen::Vector3d& origin,
                 const Eigen::Matrix3d& rotation, const RayPattern& pattern, int group,
                 double max_range_m, int exclude_owner, RayHit* hits, int hits_base) const;

  ThreadPool* pool_;
  int lanes_;
};

}  // namespace cairn::sim
