#pragma once

// The sonar obstacle layer as integration tests read it off the bus: the mapper's
// sonar/occupancy tiles assembled, and its occupied cells grouped into clusters.

#include <cmath>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "cairn/lcmt_grid_manifest.hpp"
#include "cairn/lcmt_occupancy_tile.hpp"

#include "common/channels.h"
#include "common/grid_map.h"
#include "services/runtime/layer_assembler.h"

namespace cairn::testing {

inline constexpr char kSonarLayer[] = "sonar/occupancy";

class SonarTiles {
 public:
  explicit SonarTiles(lcm::LCM& lcm, const std::string& robot) {
    lcm.subscribe(channels::ForRobot(robot, channels::kMapOccupancy), &SonarTiles::OnTile, this);
    lcm.subscribe(channels::ForRobot(robot, channels::kMapManifest), &SonarTiles::OnManifest, this);
  }
  /// The version of the layer's newest manifest (0 before one).
  int64_t version() const { return assembler_.version(kSonarLayer); }
  std::optional<common::GridMap> Layer() const { return assembler_.Layer(kSonarLayer); }

 private:
  void OnTile(const lcm::ReceiveBuffer*, const std::string&, const cairn::lcmt_occupancy_tile* t) {
    if (t->layer == kSonarLayer) assembler_.OnTile(*t);
  }
  void OnManifest(const lcm::ReceiveBuffer*, const std::string&,
                  const cairn::lcmt_grid_manifest* m) {
    if (m->layer == kSonarLayer) assembler_.OnManifest(*m);
  }
  runtime::LayerAssembler assembler_;
};

struct Cluster {
  int cells{0};
  common::Vector2 centre{0.0, 0.0};
};

// Groups of occupied cells linked when within `link_m` of each other (single linkage). The
// sonar places a peak at its 1 m bin's near edge, so one face's cells lie on range steps a bin
// apart: 1.5 m joins them and still parts objects farther apart than that.
inline std::vector<Cluster> Clusters(const common::GridMap& map, double link_m = 1.5) {
  const common::Layer& l = map.at(kSonarLayer);
  std::vector<common::Vector2> cells;
  for (int iy = 0; iy < map.size_y(); ++iy) {
    for (int ix = 0; ix < map.size_x(); ++ix) {
      const float v = l(ix, iy);
      if (!std::isnan(v) && v >= 50.f) cells.push_back(map.CenterOf({ix, iy}));
    }
  }
  std::vector<int> group(cells.size(), -1);
  std::vector<Cluster> out;
  for (size_t seed = 0; seed < cells.size(); ++seed) {
    if (group[seed] >= 0) continue;
    const int id = static_cast<int>(out.size());
    Cluster c;
    std::vector<size_t> stack{seed};
    group[seed] = id;
    while (!stack.empty()) {
      const size_t i = stack.back();
      stack.pop_back();
      ++c.cells;
      c.centre += cells[i];
      for (size_t j = 0; j < cells.size(); ++j) {
        if (group[j] < 0 && (cells[j] - cells[i]).norm() <= link_m) {
          group[j] = id;
          stack.push_back(j);
        }
      }
    }
    c.centre /= c.cells;
    out.push_back(c);
  }
  return out;
}

inline int CountCells(const common::GridMap& map, bool occupied) {
  int n = 0;
  const common::Layer& l = map.at(kSonarLayer);
  for (int iy = 0; iy < map.size_y(); ++iy) {
    for (int ix = 0; ix < map.size_x(); ++ix) {
      const float v = l(ix, iy);
      if (!std::isnan(v) && (v >= 50.f) == occupied) ++n;
    }
  }
  return n;
}

}  // namespace cairn::testing
