#include "services/mapping/terrain_mapper_layer.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "common/check.h"
#include "common/layers.h"
#include "common/yaml_reader.h"

namespace cairn::mapping {
namespace {

double Seconds(std::chrono::steady_clock::time_point a, std::chrono::steady_clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

std::string Num(double v) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.9g", v);
  return buf;
}

// The registry in a stable text form (obstacles.yaml).
std::string RegistryYaml(const common::ObstacleRegistry& registry) {
  std::ostringstream obs;
  obs << "obstacles:\n";
  for (const auto& o : registry.obstacles) {
    obs << "  - id: " << o.id << "\n    kind: " << common::ObstacleKindName(o.kind)
        << "\n    centroid_m: [" << Num(o.centroid_m.x()) << ", " << Num(o.centroid_m.y())
        << "]\n    slope_rad: " << Num(o.slope_rad) << "\n    height_m: " << Num(o.height_m)
        << "\n    width_m: " << Num(o.width_m) << "\n    length_m: " << Num(o.length_m)
        << "\n    depth_m: " << Num(o.depth_m) << "\n    area_m2: " << Num(o.area_m2)
        << "\n    num_cells: " << o.num_cells
        << "\n    downhill_heading_rad: " << Num(o.downhill_heading_rad) << "\n    outline_m: [";
    for (size_t k = 0; k < o.outline_m.size(); ++k) {
      obs << (k ? ", " : "") << "[" << Num(o.outline_m[k].x()) << ", " << Num(o.outline_m[k].y())
          << "]";
    }
    obs << "]\n    verdicts:\n";
    for (const auto& v : o.verdicts) {
      obs << "      - {profile: " << v.profile
          << ", crossable: " << (v.crossable ? "true" : "false") << ", reason: \"" << v.reason
          << "\"}\n";
    }
    if (o.parts.empty()) continue;
    obs << "    parts:\n";
    for (const auto& p : o.parts) {
      obs << "      - kind: " << common::ObstacleKindName(p.kind) << "\n        centroid_m: ["
          << Num(p.centroid_m.x()) << ", " << Num(p.centroid_m.y())
          << "]\n        slope_rad: " << Num(p.slope_rad)
          << "\n        height_m: " << Num(p.height_m)
          << "\n        heading_in_rad: " << Num(p.heading_in_rad) << "\n        verdicts:\n";
      for (const auto& v : p.verdicts) {
        obs << "          - {profile: " << v.profile
            << ", crossable: " << (v.crossable ? "true" : "false") << ", reason: \"" << v.reason
            << "\"}\n";
      }
    }
  }
  return obs.str();
}

}  // namespace

void TerrainMapperLayerParams::Validate() const {
  map.Validate();
  for (double p : {publish_period_s, slow_publish_period_s, registry_period_s}) {
    CAIRN_THROW_UNLESS(p > 0, "terrain publish periods must be positive, got " << p);
  }
  CAIRN_THROW_UNLESS(max_announce_without_data_s > 0,
                     "max_announce_without_data_s must be positive, got "
                         << max_announce_without_data_s);
}

TerrainMapperLayerParams LoadTerrainMapperLayerParams(common::YamlMap& map) {
  TerrainMapperLayerParams p;
  p.map = LoadTerrainMapParams(map);
  return p;
}

TerrainMapperLayer::TerrainMapperLayer(const TerrainMapperLayerParams& params)
    : params_((params.Validate(), params)), map_(params.map) {}

const std::string& TerrainMapperLayer::name() const {
  static const std::string kName = "terrain";
  return kName;
}

LayerSchedule TerrainMapperLayer::schedule() const {
  LayerSchedule s;
  s.publish_period_s = params_.publish_period_s;
  return s;
}

std::vector<std::string> TerrainMapperLayer::OwnedLayers() const {
  std::vector<std::string> names = TerrainMap::BaseLayers();
  for (const auto& n : map_.DerivedLayers()) names.push_back(n);
  return names;
}

void TerrainMapperLayer::OnRevolution(const RevolutionInput& input, RevolutionReport* report) {
  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::now();
  report->terrain = map_.Integrate(input.revolution, input.time_s);
  const auto t1 = Clock::now();
  report->derived = map_.UpdateDerived(input.robot);
  const auto t2 = Clock::now();
  report->elevation_s = Seconds(t0, t1);
  report->derived_s = Seconds(t1, t2);
}

std::optional<double> TerrainMapperLayer::GroundHeightUnder(const common::Vector2& xy_m) const {
  common::GridGeometry g;
  g.resolution_m = params_.map.resolution_m;
  g.size_x = g.size_y = 3;
  g.origin = {std::floor(xy_m.x() / g.resolution_m - 1) * g.resolution_m,
              std::floor(xy_m.y() / g.resolution_m - 1) * g.resolution_m, 0.0};
  const common::GridMap under = map_.Export({layers::kElevation}, g);
  double sum = 0;
  int n = 0;
  for (int64_t i = 0; i < under.at(layers::kElevation).size(); ++i) {
    const float h = under.at(layers::kElevation).data()[i];
    if (!std::isnan(h)) {
      sum += h;
      ++n;
    }
  }
  if (n == 0) return std::nullopt;
  return sum / n;
}

common::Status TerrainMapperLayer::WriteOutputs(const std::string& dir, std::ostream& yaml) const {
  if (map_.empty()) {
    yaml << "terrain:\n";
  } else {
    std::vector<std::string> names = TerrainMap::BaseLayers();
    for (const auto& n : map_.DerivedLayers()) names.push_back(n);
    const common::Status s = WriteGridSection(dir, "terrain", map_.Export(names), names, yaml);
    if (!s.ok()) return s;
  }
  std::ofstream(dir + "/obstacles.yaml", std::ios::trunc) << RegistryYaml(map_.BuildRegistry());
  yaml << "obstacles: obstacles.yaml\n";
  return common::Status::Ok();
}

}  // namespace cairn::mapping
