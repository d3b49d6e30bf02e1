#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include <mujoco/mujoco.h>

#include "common/types.h"
#include "simulator/ray_caster.h"

/// @file
/// SceneRays: the ray casting every range sensor of a simulation shares. It owns the scene's
/// sensor-visible geometry (RayScene), the caster and its thread pool, brings the geometry up
/// to date lazily after things moved, and counts the rays cast and the time spent.

namespace cairn::sim {

class SceneRays {
 public:
  /// @param threads threads casting rays (1: the calling thread only).
  SceneRays(const mjModel* model, int threads);
  ~SceneRays();
  SceneRays(const SceneRays&) = delete;
  SceneRays& operator=(const SceneRays&) = delete;

  /// Casts groups [group_begin, group_end) of `pattern` from a sensor of robot `robot_index` at
  /// pose `sensor` into (*hits)[ray index]; the robot's own geoms are not seen. `hits` must hold
  /// one entry per ray of the pattern.
  void Cast(const mjData* data, int robot_index, const common::Pose3& sensor,
            const RayPattern& pattern, int group_begin, int group_end, double max_range_m,
            std::vector<RayHit>* hits);
  /// The same into a buffer holding only the rays cast: hits[ray index - first_ray].
  void Cast(const mjData* data, int robot_index, const common::Pose3& sensor,
            const RayPattern& pattern, int group_begin, int group_end, double max_range_m,
            RayHit* hits, int first_ray);
  /// The same for every group of the pattern.
  void CastAll(const mjData* data, int robot_index, const common::Pose3& sensor,
               const RayPattern& pattern, double max_range_m, std::vector<RayHit>* hits);

  /// Intensity of a return from `geom`: the brightness of its surface colour, 0..100.
  float intensity(int geom) const { return intensity_[geom]; }
  /// The same for every geom (indexed by geom id), for tight loops.
  const float* intensities() const { return intensity_.data(); }

  /// Things moved (physics, objects, robots): the geometry is refreshed before the next cast.
  void MarkMoved() { dirty_ = true; }
  RayScene& scene() { return *scene_; }
  const RayScene& scene() const { return *scene_; }

  /// Casts with a plain mj_ray loop instead of the caster (benchmark baseline).
  void set_use_mj_ray(bool use) { use_mj_ray_ = use; }
  int64_t rays_cast() const { return rays_cast_; }
  double ray_s() const { return ray_s_; }

 private:
  const mjModel* model_;
  std::unique_ptr<RayScene> scene_;
  std::unique_ptr<ThreadPool> pool_;
  std::unique_ptr<RayCaster> caster_;
  std::vector<float> intensity_;
  bool dirty_{true};
  bool use_mj_ray_{false};
  int64_t rays_cast_{0};
  double ray_s_{0.0};
};

}  // namespace cairn::sim
