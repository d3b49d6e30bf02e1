#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include "common/check.h"
#include "common/layers.h"
#include "services/mapping/obstacles.h"
#include "services/mapping/terrain_map.h"
#include "services/mapping/terrain_map_tile.h"
#include "services/mapping/traversability.h"

// TerrainMap's derived layers (geometric, feature and cost layers, recomputed in windows around
// what changed), its registry and its exports; terrain_map.cc fuses the measurements.

namespace cairn::mapping {

using internal::FeatureLayers;
using internal::FloorDiv;
using internal::GeometricLayers;
using internal::Grow;

namespace {
constexpr float kNaN = internal::kTerrainNaN;
}  // namespace

common::GridMap TerrainMap::Window(const CellRect& r, const std::vector<std::string>& names) const {
  common::GridGeometry g;
  g.resolution_m = params_.resolution_m;
  g.size_x = r.x1 - r.x0;
  g.size_y = r.y1 - r.y0;
  g.origin = {r.x0 * params_.resolution_m, r.y0 * params_.resolution_m, 0.0};
  common::GridMap out;
  WindowInto(r, names, g, &out);
  return out;
}

common::GridMap& TerrainMap::Scratch(const CellRect& r, const std::vector<std::string>& names) {
  // Windows of the recomputation share one buffer of a fixed size in local coordinates (cell
  // (0, 0) is the window's first cell), so no memory is allocated per window.
  const int side = params_.tile_size_cells +
                   2 * (DependencyRadiusCells(params_.traversability, params_.resolution_m) + 1);
  common::GridGeometry g;
  g.resolution_m = params_.resolution_m;
  g.size_x = std::max(side, r.x1 - r.x0);
  g.size_y = std::max(side, r.y1 - r.y0);
  WindowInto(r, names, g, &scratch_);
  return scratch_;
}

void TerrainMap::WindowInto(const CellRect& r, const std::vector<std::string>& names,
                            const common::GridGeometry& g, common::GridMap* out_map) const {
  if (out_map->geometry() != g || out_map->size_x() == 0) *out_map = common::GridMap(g);
  common::GridMap& out = *out_map;
  for (const auto& name : names) {
    if (out.HasLayer(name)) {
      out.at(name).setConstant(kNaN);
    } else {
      out.AddLayer(name);
    }
  }
  const int T = params_.tile_size_cells;
  const int64_t tx0 = FloorDiv(r.x0, T), tx1 = FloorDiv(r.x1 - 1, T);
  const int64_t ty0 = FloorDiv(r.y0, T), ty1 = FloorDiv(r.y1 - 1, T);
  for (int64_t ty = ty0; ty <= ty1; ++ty) {
    for (int64_t tx = tx0; tx <= tx1; ++tx) {
      const Tile* tile = FindTile(static_cast<int>(tx), static_cast<int>(ty));
      if (tile == nullptr) continue;
      const int64_t x0 = std::max<int64_t>(r.x0, tx * T),
                    x1 = std::min<int64_t>(r.x1, (tx + 1) * T);
      const int64_t y0 = std::max<int64_t>(r.y0, ty * T),
                    y1 = std::min<int64_t>(r.y1, (ty + 1) * T);
      for (const auto& name : names) {
        if (!tile->layers.HasLayer(name)) continue;
        out.at(name).block(x0 - r.x0, y0 - r.y0, x1 - x0, y1 - y0) =
            tile->layers.at(name).block(x0 - tx * T, y0 - ty * T, x1 - x0, y1 - y0);
      }
    }
  }
}

void TerrainMap::WriteBack(const common::GridMap& window, int64_t ox, int64_t oy, const CellRect& r,
                           const std::vector<std::string>& names) {
  const int T = params_.tile_size_cells;
  const int64_t tx0 = FloorDiv(r.x0, T), tx1 = FloorDiv(r.x1 - 1, T);
  const int64_t ty0 = FloorDiv(r.y0, T), ty1 = FloorDiv(r.y1 - 1, T);
  for (int64_t ty = ty0; ty <= ty1; ++ty) {
    for (int64_t tx = tx0; tx <= tx1; ++tx) {
      auto it = tiles_.find({static_cast<int>(tx), static_cast<int>(ty)});
      if (it == tiles_.end()) continue;
      Tile* tile = it->second.get();
      const int64_t x0 = std::max<int64_t>(r.x0, tx * T),
                    x1 = std::min<int64_t>(r.x1, (tx + 1) * T);
      const int64_t y0 = std::max<int64_t>(r.y0, ty * T),
                    y1 = std::min<int64_t>(r.y1, (ty + 1) * T);
      for (const auto& name : names) {
        if (!tile->layers.HasLayer(name)) {
          tile->layers.AddLayer(name);
          if (name == layers::kSlope) tile->slope = tile->layers.at(name).data();
          if (name == kNormalXLayer) tile->normal_x = tile->layers.at(name).data();
          if (name == kNormalYLayer) tile->normal_y = tile->layers.at(name).data();
        }
        tile->layers.at(name).block(x0 - tx * T, y0 - ty * T, x1 - x0, y1 - y0) =
            window.at(name).block(x0 - ox, y0 - oy, x1 - x0, y1 - y0);
      }
      ++tile->derived_version;
    }
  }
}

std::vector<CellRect> TerrainMap::RectsOfBlocks(const std::set<Key>& blocks) const {
  // One rectangle per tile: the bounding box of the tile's blocks in the set, restricted to
  // allocated tiles (derived layers exist only there).
  const int T = params_.tile_size_cells, B = block_cells_, per_tile = T / B;
  std::map<Key, CellRect> per;  // ordered: deterministic processing order
  for (const auto& [bx, by] : blocks) {
    const int tx = static_cast<int>(FloorDiv(bx, per_tile));
    const int ty = static_cast<int>(FloorDiv(by, per_tile));
    if (FindTile(tx, ty) == nullptr) continue;
    const CellRect b{bx * B, by * B, (bx + 1) * B, (by + 1) * B};
    auto it = per.find({ty, tx});
    if (it == per.end()) {
      per.emplace(Key{ty, tx}, b);
    } else {
      it->second = {std::min(it->second.x0, b.x0), std::min(it->second.y0, b.y0),
                    std::max(it->second.x1, b.x1), std::max(it->second.y1, b.y1)};
    }
  }
  std::vector<CellRect> rects;
  for (const auto& [key, r] : per) rects.push_back(r);
  return rects;
}

void TerrainMap::RecomputeCosts(const std::vector<CellRect>& rects, const RobotContext& robot,
                                const std::vector<const common::RobotProfile*>& which) {
  if (which.empty()) return;
  // The cost of a cell reads the geometric layers of its 4-neighbours and the elevation and
  // ground bound around it.
  std::vector<std::string> in{layers::kElevation, layers::kGroundBound};
  for (const auto& n : GeometricLayers()) in.push_back(n);
  std::vector<std::string> out;
  for (const auto* p : which) {
    out.push_back(layers::CostLayer(p->name));
    out.push_back(layers::DirectedLayer(p->name));
  }
  const int margin = CostRadiusCells(params_.resolution_m);
  for (const CellRect& r : rects) {
    const CellRect w = Grow(r, margin);
    common::GridMap& window = Scratch(w, in);
    const CellRect local{margin, margin, margin + r.x1 - r.x0, margin + r.y1 - r.y0};
    // The window is in local coordinates: so is the robot.
    RobotContext local_robot = robot;
    if (robot.xy_m) {
      local_robot.xy_m = *robot.xy_m - common::Vector2(w.x0, w.y0) * params_.resolution_m;
    }
    for (const auto* p : which) {
      ComputeCostLayer(&window, *p, params_.traversability, local_robot, local);
    }
    WriteBack(window, w.x0, w.y0, r, out);
  }
}

std::set<TerrainMap::Key> TerrainMap::TakeChangedRegion() {
  // Every block whose derived values can depend on a changed block.
  const int geo_radius = DependencyRadiusCells(params_.traversability, params_.resolution_m);
  const int dilate = (geo_radius + FeatureRadiusCells() + block_cells_ - 1) / block_cells_;
  std::set<Key> region;
  for (const auto& [bx, by] : dirty_blocks_) {
    for (int dy = -dilate; dy <= dilate; ++dy) {
      for (int dx = -dilate; dx <= dilate; ++dx) region.insert({bx + dx, by + dy});
    }
  }
  dirty_blocks_.clear();
  has_last_dirty_ = false;
  return region;
}

void TerrainMap::AddBlocksAround(const common::Vector2& xy, double radius_m,
                                 std::set<Key>* region) const {
  const int B = block_cells_;
  const int64_t cx0 = static_cast<int64_t>(std::floor((xy.x() - radius_m) / params_.resolution_m));
  const int64_t cx1 = static_cast<int64_t>(std::floor((xy.x() + radius_m) / params_.resolution_m));
  const int64_t cy0 = static_cast<int64_t>(std::floor((xy.y() - radius_m) / params_.resolution_m));
  const int64_t cy1 = static_cast<int64_t>(std::floor((xy.y() + radius_m) / params_.resolution_m));
  for (int64_t by = FloorDiv(cy0, B); by <= FloorDiv(cy1, B); ++by) {
    for (int64_t bx = FloorDiv(cx0, B); bx <= FloorDiv(cx1, B); ++bx) {
      region->insert({static_cast<int>(bx), static_cast<int>(by)});
    }
  }
}

int64_t TerrainMap::RecomputeGeometry(const std::vector<CellRect>& rects) {
  // Geometric layers first (each rectangle reads its own margin) ...
  const int geo_radius = DependencyRadiusCells(params_.traversability, params_.resolution_m);
  std::vector<std::string> base_in{layers::kElevation, layers::kGroundBound};
  int64_t cells = 0;
  for (const CellRect& r : rects) {
    const CellRect w = Grow(r, geo_radius);
    common::GridMap& window = Scratch(w, base_in);
    const CellRect local{geo_radius, geo_radius, geo_radius + r.x1 - r.x0,
                         geo_radius + r.y1 - r.y0};
    ComputeGeometricLayers(&window, params_.traversability, local);
    WriteBack(window, w.x0, w.y0, r, GeometricLayers());
    cells += static_cast<int64_t>(r.x1 - r.x0) * (r.y1 - r.y0);
  }
  // ... then the feature layers from them.
  std::vector<std::string> feature_in{layers::kElevation, layers::kElevationVariance,
                                      layers::kGroundBound};
  for (const auto& n : GeometricLayers()) feature_in.push_back(n);
  const int fm = FeatureRadiusCells() + 1;
  for (const CellRect& r : rects) {
    const CellRect w = Grow(r, fm);
    common::GridMap& window = Scratch(w, feature_in);
    ComputeFeatureLayers(&window, params_.obstacles, {fm, fm, fm + r.x1 - r.x0, fm + r.y1 - r.y0});
    WriteBack(window, w.x0, w.y0, r, FeatureLayers());
  }
  return cells;
}

// A cell seen only before its normal could be trusted (the first revolutions, or a lone cell
// whose neighbours came later) kept the height of where its points lay: a hillside seen once
// along a ring line reads as a contour of equal heights, a terrace. Committed again with the
// normals derived since, it is carried to its centre like every cell seen later; a changed
// height marks its block dirty, so the derived layers follow within the same update.
void TerrainMap::RecommitUnsettled(const std::vector<CellRect>& rects) {
  const int T = params_.tile_size_cells;
  limited_tile_ = nullptr;
  interpolates_tile_ = nullptr;
  for (const CellRect& r : rects) {  // one tile each (RectsOfBlocks)
    if (r.x1 <= r.x0 || r.y1 <= r.y0) continue;
    const int64_t tx = FloorDiv(r.x0, T), ty = FloorDiv(r.y0, T);
    auto it = tiles_.find({static_cast<int>(tx), static_cast<int>(ty)});
    if (it == tiles_.end()) continue;
    Tile* tile = it->second.get();
    const int64_t x1 = std::min<int64_t>(r.x1, (tx + 1) * T);
    const int64_t y1 = std::min<int64_t>(r.y1, (ty + 1) * T);
    for (int64_t cy = r.y0; cy < y1; ++cy) {
      for (int64_t cx = r.x0; cx < x1; ++cx) {
        const size_t i = static_cast<size_t>((cx - tx * T) + (cy - ty * T) * T);
        if (tile->carried[i] || std::isnan(tile->filter_height[i])) continue;
        CommitHeight(tile, i, cx, cy, /*only_to_carry=*/true);
      }
    }
  }
  limited_tile_ = nullptr;
  interpolates_tile_ = nullptr;
}

DerivedStats TerrainMap::UpdateDerived(const RobotContext& robot) {
  DerivedStats stats;
  // Cells of the last update's region that were committed without a trusted normal, committed
  // again with the normals it derived, before this update derives from their heights.
  RecommitUnsettled(RectsOfBlocks(last_region_));
  std::set<Key> region = TakeChangedRegion();
  // Cost-only blocks: the blind zone at the robot's previous and current position, and with
  // IMU compensation the robot's surroundings (the pitch changes every cell's slope there).
  std::set<Key> cost_region = region;
  const double zone = params_.traversability.blind_zone_half_size_m + params_.resolution_m;
  if (last_robot_xy_) AddBlocksAround(*last_robot_xy_, zone, &cost_region);
  if (robot.xy_m && robot.xy_m->allFinite()) {
    const bool compensating = params_.traversability.imu_pitch_compensation;
    AddBlocksAround(*robot.xy_m, compensating ? params_.max_range_m : zone, &cost_region);
    last_robot_xy_ = robot.xy_m;
  }
  stats.geometric_cells = RecomputeGeometry(RectsOfBlocks(region));
  // The cost layers of every profile.
  std::vector<const common::RobotProfile*> all;
  for (const auto& p : profiles_) all.push_back(&p);
  const std::vector<CellRect> cost_rects = RectsOfBlocks(cost_region);
  RecomputeCosts(cost_rects, robot, all);
  for (const CellRect& r : cost_rects) {
    stats.cost_cells += static_cast<int64_t>(r.x1 - r.x0) * (r.y1 - r.y0) * all.size();
  }
  last_region_ = std::move(region);
  return stats;
}

common::ObstacleRegistry TerrainMap::BuildRegistry() const {
  if (tiles_.empty()) return {};
  std::vector<std::string> names{layers::kElevation, layers::kGroundBound, layers::kSlope,
                                 layers::kDitchDepth, layers::kDitchWidth};
  for (const auto& n : FeatureLayers()) names.push_back(n);
  const common::GridGeometry g = AllocatedBounds();
  const int x0 = static_cast<int>(std::lround(g.origin.x_m / params_.resolution_m));
  const int y0 = static_cast<int>(std::lround(g.origin.y_m / params_.resolution_m));
  WindowInto({x0, y0, x0 + g.size_x, y0 + g.size_y}, names, g, &registry_scratch_);
  common::ObstacleRegistry registry = AssembleObstacles(registry_scratch_, params_.obstacles);
  LabelObstacles(&registry, profiles_);
  return registry;
}

common::GridMap TerrainMap::Export(const std::vector<std::string>& names) const {
  return Export(names, Bounds());
}

common::GridMap TerrainMap::Export(const std::vector<std::string>& names,
                                   const common::GridGeometry& window) const {
  const double res = params_.resolution_m;
  CAIRN_THROW_UNLESS(window.resolution_m == res && window.origin.yaw_rad == 0.0,
                     "export window must share the map's resolution and axes");
  const double fx = window.origin.x_m / res, fy = window.origin.y_m / res;
  CAIRN_THROW_UNLESS(std::fabs(fx - std::round(fx)) < 1e-6 && std::fabs(fy - std::round(fy)) < 1e-6,
                     "export window must be aligned with the map's cells");
  const std::vector<std::string> known_derived = DerivedLayers();
  for (const auto& n : names) {
    const bool ok =
        std::find(known_derived.begin(), known_derived.end(), n) != known_derived.end() ||
        n == layers::kElevation || n == layers::kElevationVariance ||
        n == layers::kObservationCount || n == layers::kLastSeen || n == layers::kGroundBound ||
        std::find(FeatureLayers().begin(), FeatureLayers().end(), n) != FeatureLayers().end();
    CAIRN_THROW_UNLESS(ok, "the terrain map has no layer '" << n << "'");
  }
  const int64_t x0 = std::llround(fx), y0 = std::llround(fy);
  common::GridMap out =
      Window({static_cast<int>(x0), static_cast<int>(y0), static_cast<int>(x0 + window.size_x),
              static_cast<int>(y0 + window.size_y)},
             names);
  return out;
}

}  // namespace cairn::mapping
