#include "simulator/scene_rays.h"

#include <chrono>

namespace cairn::sim {

SceneRays::SceneRays(const mjModel* model, int threads)
    : model_(model), scene_(std::make_unique<RayScene>(model)) {
  if (threads > 1) pool_ = std::make_unique<ThreadPool>(threads);
  caster_ = std::make_unique<RayCaster>(pool_.get());
  intensity_.resize(model->ngeom);
  for (int g = 0; g < model->ngeom; ++g) {
    const int mat = model->geom_matid[g];
    const float* rgba = mat >= 0 ? model->mat_rgba + 4 * mat : model->geom_rgba + 4 * g;
    intensity_[g] = 100.f * (0.299f * rgba[0] + 0.587f * rgba[1] + 0.114f * rgba[2]);
  }
}

SceneRays::~SceneRays() = default;

void SceneRays::Cast(const mjData* data, int robot_index, const common::Pose3& sensor,
                     const RayPattern& pattern, int group_begin, int group_end, double max_range_m,
                     std::vector<RayHit>* hits) {
  Cast(data, robot_index, sensor, pattern, group_begin, group_end, max_range_m, hits->data(), 0);
}

void SceneRays::Cast(const mjData* data, int robot_index, const common::Pose3& sensor,
                     const RayPattern& pattern, int group_begin, int group_end, double max_range_m,
                     RayHit* hits, int first_ray) {
  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::now();
  if (dirty_) {
    scene_->Update(data);
    dirty_ = false;
  }
  const Eigen::Matrix3d rotation = sensor.orientation.toRotationMatrix();
  if (use_mj_ray_) {
    RayCaster::CastWithMjRay(model_, data, sensor.position_m, rotation, pattern, group_begin,
                             group_end, max_range_m, hits, first_ray);
  } else {
    caster_->Cast(*scene_, data, sensor.position_m, rotation, pattern, group_begin, group_end,
                  max_range_m, robot_index, hits, first_ray);
  }
  rays_cast_ += pattern.groups[group_end - 1].end - pattern.groups[group_begin].begin;
  ray_s_ += std::chrono::duration<double>(Clock::now() - t0).count();
}

void SceneRays::CastAll(const mjData* data, int robot_index, const common::Pose3& sensor,
                        const RayPattern& pattern, double max_range_m, std::vector<RayHit>* hits) {
  Cast(data, robot_index, sensor, pattern, 0, static_cast<int>(pattern.groups.size()), max_range_m,
       hits);
}

}  // namespace cairn::sim
