#include "simulator/ground_truth.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

#include "common/check.h"
#include "simulator/thread_pool.h"

namespace cairn::sim {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// Below each hit, the next cast starts this much lower.
constexpr double kPeelStep_m = 1e-6;
// A column never has more surfaces than this (a bug guard, not a limit of real worlds).
constexpr int kMaxHitsPerColumn = 1024;
constexpr char kDoorPrefix[] = "door_";
const double kDown[3] = {0.0, 0.0, -1.0};
const double kUp[3] = {0.0, 0.0, 1.0};

// Half extents of a geom's world-aligned bounding box (planes: none).
void WorldHalfExtents(const mjModel* m, const mjData* d, int g, double out[3]) {
  const double* s = m->geom_size + 3 * g;
  double half[3] = {0, 0, 0};
  switch (m->geom_type[g]) {
    case mjGEOM_SPHERE:
      half[0] = half[1] = half[2] = s[0];
      break;
    case mjGEOM_CAPSULE:
      half[0] = half[1] = s[0];
      half[2] = s[1] + s[0];
      break;
    case mjGEOM_CYLINDER:
      half[0] = half[1] = s[0];
      half[2] = s[1];
      break;
    case mjGEOM_BOX:
    case mjGEOM_ELLIPSOID:
      half[0] = s[0];
      half[1] = s[1];
      half[2] = s[2];
      break;
    case mjGEOM_HFIELD: {
      const double* h = m->hfield_size + 4 * m->geom_dataid[g];
      half[0] = h[0];
      half[1] = h[1];
      half[2] = std::max(h[2], h[3]);  // the surface rises to h[2], the base reaches -h[3]
      break;
    }
    default:  // meshes and anything else: MuJoCo's bounding sphere
      half[0] = half[1] = half[2] = m->geom_rbound[g];
      break;
  }
  const double* r = d->geom_xmat + 9 * g;  // row-major rotation, geom to world
  for (int i = 0; i < 3; ++i) {
    out[i] = std::abs(r[3 * i]) * half[0] + std::abs(r[3 * i + 1]) * half[1] +
             std::abs(r[3 * i + 2]) * half[2];
  }
}

// Distance along the unit `dir` from `p` to geom g's surface, or -1: MuJoCo's routine per type.
double RayToGeom(const mjModel* m, const mjData* d, int g, const double p[3], const double dir[3]) {
  switch (m->geom_type[g]) {
    case mjGEOM_HFIELD:
      return mj_rayHfield(m, d, g, p, dir);
    case mjGEOM_MESH:
      return mj_rayMesh(m, d, g, p, dir);
    default:
      return mju_rayGeom(d->geom_xpos + 3 * g, d->geom_xmat + 9 * g, m->geom_size + 3 * g, p, dir,
                         m->geom_type[g]);
  }
}

// Same as cairn-sim's MujocoSim::SetDoor(open) followed by placing the hinge there.
void OpenDoors(const mjModel* m, mjData* d) {
  for (int a = 0; a < m->nu; ++a) {
    const char* name = mj_id2name(m, mjOBJ_ACTUATOR, a);
    if (name == nullptr || std::string(name).rfind(kDoorPrefix, 0) != 0) continue;
    if (m->actuator_trntype[a] != mjTRN_JOINT) continue;
    const int joint = m->actuator_trnid[2 * a];
    double target = m->jnt_limited[joint] ? m->jnt_range[2 * joint + 1] : M_PI / 2;
    if (target == 0.0) target = m->jnt_range[2 * joint];
    d->qpos[m->jnt_qposadr[joint]] = target;
  }
}

}  // namespace

void TruthRasterParams::Validate() const {
  CAIRN_THROW_UNLESS(std::isfinite(band_low_m) && band_low_m > 0.0,
                     "band_low_m must be > 0 (got " << band_low_m << ")");
  CAIRN_THROW_UNLESS(std::isfinite(band_high_m) && band_high_m > band_low_m,
                     "band_high_m must be finite and above band_low_m (got " << band_high_m << ")");
  CAIRN_THROW_UNLESS(samples_per_side >= 1 && samples_per_side <= 16,
                     "samples_per_side must be in [1, 16] (got " << samples_per_side << ")");
  CAIRN_THROW_UNLESS(std::isfinite(terrain_min_extent_m) && terrain_min_extent_m > 0.0,
                     "terrain_min_extent_m must be > 0 (got " << terrain_min_extent_m << ")");
  CAIRN_THROW_UNLESS(std::isfinite(terrain_max_height_m) && terrain_max_height_m > 0.0,
                     "terrain_max_height_m must be > 0 (got " << terrain_max_height_m << ")");
  CAIRN_THROW_UNLESS(
      std::isfinite(stack_tolerance_m) && stack_tolerance_m >= 0.0 &&
          stack_tolerance_m < band_low_m,
      "stack_tolerance_m must be in [0, band_low_m) (got " << stack_tolerance_m << ")");
  CAIRN_THROW_UNLESS(threads >= 1 && threads <= 64,
                     "threads must be in [1, 64] (got " << threads << ")");
}

GroundTruthWorld::GroundTruthWorld(MjModelPtr model, const TruthRasterParams& params)
    : model_(std::move(model)), params_(params) {
  params_.Validate();
  CAIRN_THROW_UNLESS(model_ != nullptr, "GroundTruthWorld needs a model");
  const mjModel* m = model_.get();
  data_.reset(mj_makeData(m));
  CAIRN_THROW_UNLESS(data_ != nullptr, "MuJoCo could not allocate the model's data");
  if (params_.open_doors) OpenDoors(m, data_.get());
  mj_kinematics(m, data_.get());

  const mjData* d = data_.get();
  terrain_.assign(m->ngeom, 0);
  solid_.assign(m->ngeom, 0);
  footprint_.assign(m->ngeom, Footprint{});
  double highest = -kInfinity;
  for (int g = 0; g < m->ngeom; ++g) {
    solid_[g] = (m->geom_contype[g] != 0 || m->geom_conaffinity[g] != 0) ? 1 : 0;
    const int type = m->geom_type[g];
    const double z = d->geom_xpos[3 * g + 2];
    if (type == mjGEOM_PLANE) {
      planes_.push_back(g);
      terrain_[g] = 1;
      highest = std::max(highest, z);
      continue;
    }
    double half[3];
    WorldHalfExtents(m, d, g, half);
    highest = std::max(highest, z + half[2]);
    const double* p = d->geom_xpos + 3 * g;
    footprint_[g] = {p[0] - half[0], p[0] + half[0], p[1] - half[1], p[1] + half[1]};
    terrain_[g] = type == mjGEOM_HFIELD || (2.0 * half[0] >= params_.terrain_min_extent_m &&
                                            2.0 * half[1] >= params_.terrain_min_extent_m &&
                                            2.0 * half[2] <= params_.terrain_max_height_m);
  }
  start_z_m_ = (std::isfinite(highest) ? highest : 0.0) + 1.0;
}

GroundTruthWorld GroundTruthWorld::FromFile(const std::string& path,
                                            const TruthRasterParams& params) {
  return GroundTruthWorld(LoadModelFromFile(path), params);
}

GroundTruthWorld GroundTruthWorld::FromText(const std::string& xml, const std::string& path,
                                            const TruthRasterParams& params) {
  return GroundTruthWorld(LoadModelFromText(xml, path), params);
}

ColumnProfile GroundTruthWorld::Column(double x_m, double y_m) const {
  const mjModel* m = model_.get();
  const mjData* d = data_.get();
  ColumnProfile out;
  out.ground_m = kNaN;
  out.top_m = kNaN;

  // 1. Discovery: peel the surfaces with mj_ray, every geom group included.
  static const mjtByte kAllGroups[mjNGROUP] = {1, 1, 1, 1, 1, 1};
  std::vector<int> met;
  double z = start_z_m_;
  for (int n = 0; n < kMaxHitsPerColumn; ++n) {
    const double p[3] = {x_m, y_m, z};
    int geom = -1;
    const double t = mj_ray(m, d, p, kDown, kAllGroups, 1, -1, &geom);
    if (t < 0.0 || geom < 0) break;
    if (std::find(met.begin(), met.end(), geom) == met.end()) met.push_back(geom);
    z = z - t - kPeelStep_m;
  }
  // Surfaces that coincide with the one mj_ray reported are masked (equal distances: one geom
  // wins): a floor under a box's bottom, a table leg whose top is the table top's underside and
  // whose foot is on the floor. Planes and every geom whose footprint holds the line are
  // therefore measured too.
  for (int g : planes_) {
    if (std::find(met.begin(), met.end(), g) == met.end()) met.push_back(g);
  }
  for (int g = 0; g < m->ngeom; ++g) {
    const Footprint& f = footprint_[g];
    if (!solid_[g] || m->geom_type[g] == mjGEOM_PLANE || x_m < f.x_lo || x_m > f.x_hi ||
        y_m < f.y_lo || y_m > f.y_hi) {
      continue;
    }
    if (std::find(met.begin(), met.end(), g) == met.end()) met.push_back(g);
  }

  // 2. Each geom met, measured exactly along the line: its top from above, its bottom from
  // below (a plane is solid all the way down).
  const double top_point[3] = {x_m, y_m, start_z_m_};
  for (int g : met) {
    if (!solid_[g]) continue;
    const double t_top = RayToGeom(m, d, g, top_point, kDown);
    if (t_top < 0.0) continue;  // a plane outside its size
    SolidSpan span;
    span.geom = g;
    span.terrain = terrain_[g] != 0;
    span.top_m = start_z_m_ - t_top;
    span.bottom_m = -kInfinity;
    if (m->geom_type[g] != mjGEOM_PLANE) {
      double half[3];
      WorldHalfExtents(m, d, g, half);
      const double below = d->geom_xpos[3 * g + 2] - half[2] - 1.0;
      const double bottom_point[3] = {x_m, y_m, below};
      const double t_bottom = RayToGeom(m, d, g, bottom_point, kUp);
      span.bottom_m = t_bottom >= 0.0 ? std::min(below + t_bottom, span.top_m) : span.top_m;
    }
    out.spans.push_back(span);
  }
  std::sort(out.spans.begin(), out.spans.end(),
            [](const SolidSpan& a, const SolidSpan& b) { return a.top_m > b.top_m; });
  if (!out.spans.empty()) out.top_m = out.spans.front().top_m;

  // 3. Ground: the top of the lowest stack of terrain spans.
  std::vector<const SolidSpan*> terrain;
  for (const SolidSpan& s : out.spans) {
    if (s.terrain) terrain.push_back(&s);
  }
  std::sort(terrain.begin(), terrain.end(), [](const SolidSpan* a, const SolidSpan* b) {
    return a->bottom_m < b->bottom_m || (a->bottom_m == b->bottom_m && a->top_m < b->top_m);
  });
  for (const SolidSpan* s : terrain) {
    if (std::isnan(out.ground_m)) {
      out.ground_m = s->top_m;
    } else if (s->bottom_m <= out.ground_m + params_.stack_tolerance_m) {
      out.ground_m = std::max(out.ground_m, s->top_m);
    } else {
      break;
    }
  }
  return out;
}

common::GridMap GroundTruthWorld::Rasterise(const common::GridGeometry& grid) const {
  common::GridMap out(grid);
  common::Layer& ground = out.AddLayer(kTruthGroundLayer);
  common::Layer& occupied = out.AddLayer(kTruthOccupiedLayer);
  common::Layer& top = out.AddLayer(kTruthTopLayer);
  const int n = params_.samples_per_side;
  const double res = grid.resolution_m;
  const double c = std::cos(grid.origin.yaw_rad), s = std::sin(grid.origin.yaw_rad);

  auto row = [&](int iy) {
    for (int ix = 0; ix < grid.size_x; ++ix) {
      double ground_sum = 0.0;
      int ground_count = 0;
      bool any_occupied = false;
      double highest = -kInfinity;
      for (int sy = 0; sy < n; ++sy) {
        for (int sx = 0; sx < n; ++sx) {
          const double mx = (ix + (sx + 0.5) / n) * res;
          const double my = (iy + (sy + 0.5) / n) * res;
          const double wx = grid.origin.x_m + c * mx - s * my;
          const double wy = grid.origin.y_m + s * mx + c * my;
          const ColumnProfile col = Column(wx, wy);
          if (std::isfinite(col.top_m)) highest = std::max(highest, col.top_m);
          if (std::isnan(col.ground_m)) continue;
          ground_sum += col.ground_m;
          ++ground_count;
          const double lo = col.ground_m + params_.band_low_m;
          const double hi = col.ground_m + params_.band_high_m;
          for (const SolidSpan& span : col.spans) {
            if (span.top_m >= lo && span.bottom_m <= hi) {
              any_occupied = true;
              break;
            }
          }
        }
      }
      if (ground_count > 0) {
        ground(ix, iy) = static_cast<float>(ground_sum / ground_count);
        occupied(ix, iy) = any_occupied ? 1.f : 0.f;
      }
      if (std::isfinite(highest)) top(ix, iy) = static_cast<float>(highest);
    }
  };
  if (params_.threads > 1) {
    ThreadPool pool(params_.threads);
    pool.ParallelFor(grid.size_y, row);
  } else {
    for (int iy = 0; iy < grid.size_y; ++iy) row(iy);
  }
  return out;
}

common::GridMap RasteriseGroundTruth(const std::string& world_path,
                                     const common::GridGeometry& grid,
                                     const TruthRasterParams& params) {
  return GroundTruthWorld::FromFile(world_path, params).Rasterise(grid);
}

}  // namespace cairn::sim
