#include "services/mapping/sonar_derive.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "common/check.h"
#include "common/layers.h"
#include "services/mapping/obstacle_shape.h"
#include "services/mapping/obstacles.h"
#include "services/mapping/sonar_mapper_layer.h"

namespace cairn::mapping {

void SonarDeriveParams::Validate() const {
  CAIRN_THROW_UNLESS(free_threshold >= 0 && free_threshold < occupied_threshold &&
                         occupied_threshold <= 100,
                     "sonar derivation needs 0 <= free_threshold < occupied_threshold <= 100");
  CAIRN_THROW_UNLESS(join_distance_m >= 0 && std::isfinite(join_distance_m),
                     "sonar join_distance_m must be finite and >= 0");
  CAIRN_THROW_UNLESS(min_cells >= 1, "sonar min_cells must be >= 1");
}

common::Layer SonarCost(const common::Layer& occupancy, const SonarDeriveParams& p) {
  common::Layer cost(occupancy.rows(), occupancy.cols());
  for (Eigen::Index i = 0; i < occupancy.size(); ++i) {
    const float v = occupancy.data()[i];
    float c;
    if (!(v >= 0.f)) {
      c = std::numeric_limits<float>::quiet_NaN();  // unknown (NaN, or -1 as ROS writes it)
    } else if (v >= p.occupied_threshold) {
      c = layers::kCostLethal;
    } else if (v <= p.free_threshold) {
      c = layers::kCostFree;
    } else {
      c = std::clamp(std::round(v), 1.f, 99.f);
    }
    cost.data()[i] = c;
  }
  return cost;
}

common::ObstacleRegistry ExtractSonarContacts(const common::GridMap& map, const std::string& layer,
                                              const SonarDeriveParams& p) {
  p.Validate();
  CAIRN_THROW_UNLESS(map.HasLayer(layer), "the map has no '" << layer << "' layer");
  const common::Layer& occ = map.at(layer);
  const int sx = map.size_x(), sy = map.size_y();
  const int reach = static_cast<int>(std::floor(p.join_distance_m / map.resolution_m() + 1e-9));
  const int64_t reach2 = static_cast<int64_t>(reach) * reach;
  auto occupied = [&](int ix, int iy) { return occ(ix, iy) >= p.occupied_threshold; };
  std::vector<uint8_t> seen(static_cast<size_t>(sx) * sy, 0);
  common::ObstacleRegistry registry;
  ObstacleParams shape;
  std::vector<int64_t> stack, cells;
  for (int iy = 0; iy < sy; ++iy) {
    for (int ix = 0; ix < sx; ++ix) {
      const int64_t start = static_cast<int64_t>(iy) * sx + ix;
      if (seen[start] || !occupied(ix, iy)) continue;
      // Single linkage: every occupied cell within the join distance of one in the group.
      cells.clear();
      stack.assign(1, start);
      seen[start] = 1;
      while (!stack.empty()) {
        const int64_t c = stack.back();
        stack.pop_back();
        cells.push_back(c);
        const int cx = static_cast<int>(c % sx), cy = static_cast<int>(c / sx);
        for (int dy = -std::max(reach, 1); dy <= std::max(reach, 1); ++dy) {
          for (int dx = -std::max(reach, 1); dx <= std::max(reach, 1); ++dx) {
            const int nx = cx + dx, ny = cy + dy;
            if (nx < 0 || ny < 0 || nx >= sx || ny >= sy) continue;
            // Touching cells always join; others within the distance.
            if (std::max(std::abs(dx), std::abs(dy)) > 1 && dx * dx + dy * dy > reach2) continue;
            const int64_t n = static_cast<int64_t>(ny) * sx + nx;
            if (seen[n] || !occupied(nx, ny)) continue;
            seen[n] = 1;
            stack.push_back(n);
          }
        }
      }
      if (static_cast<int>(cells.size()) < p.min_cells) continue;
      std::sort(cells.begin(), cells.end());
      common::Obstacle o;
      o.kind = common::ObstacleKind::kWallOrObject;
      internal::MeasureShape(map, cells, shape, &o);
      o.height_m = std::numeric_limits<double>::quiet_NaN();  // a sonar measures no height
      o.depth_m = std::numeric_limits<double>::quiet_NaN();
      registry.obstacles.push_back(std::move(o));
    }
  }
  internal::NumberByCentroid(&registry);
  return registry;
}

DerivedLayers DeriveSonarProfileLayers(const common::GridMap& base,
                                       const common::RobotProfile& profile,
                                       const SonarDeriveParams& params) {
  params.Validate();
  CAIRN_THROW_UNLESS(base.HasLayer(kSonarOccupancy),
                     "cannot derive profile layers: the map has neither an '"
                         << layers::kElevation << "' nor a '" << kSonarOccupancy << "' layer");
  profile.Validate();
  DerivedLayers out;
  out.layers = common::GridMap(base.geometry());
  const common::Layer& cost = out.layers.AddLayer(layers::CostLayer(profile.name)) =
      SonarCost(base.at(kSonarOccupancy), params);
  // No heading is refused anywhere: 0 where the cost is known, NaN where it is not.
  out.layers.AddLayer(layers::DirectedLayer(profile.name)) =
      cost.unaryExpr([](float c) { return std::isnan(c) ? c : 0.f; });
  out.registry = ExtractSonarContacts(base, kSonarOccupancy, params);
  LabelObstacles(&out.registry, {profile});
  return out;
}

}  // namespace cairn::mapping
