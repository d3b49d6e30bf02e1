#include "services/mapping/terraces.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>
#include <string>
#include <utility>

#include "common/layers.h"
#include "services/mapping/obstacle_shape.h"

namespace cairn::mapping::internal {
namespace {

using common::Obstacle;
using common::ObstacleKind;
using common::ObstaclePart;
using common::Vector2;

constexpr double kRadToDeg = 180.0 / M_PI;
constexpr double kTol = 1e-6;
constexpr std::array<std::array<int, 2>, 4> kNeighbours4{{{1, 0}, {-1, 0}, {0, 1}, {0, -1}}};
// How far (cells) a platform may lie from the ramp or face that leads onto it: the cells at a
// crease or beside a face have normals the edge tilts, so they belong to neither.
constexpr int kReachCells = 2;

// Level regions: 4-connected known cells outside every feature, flatter than `max_slope`, whose
// neighbours differ by less than `continuity`. -1 for cells on none.
struct Regions {
  std::vector<int32_t> id;
  std::vector<int64_t> size;
  std::vector<double> height_sum;
  double MeanHeight(int32_t r) const { return height_sum[r] / static_cast<double>(size[r]); }
};

Regions LabelLevelRegions(const common::GridMap& map, const std::vector<int32_t>& label,
                          double max_slope, double continuity) {
  const int sx = map.size_x(), sy = map.size_y();
  const float* h = map.at(layers::kElevation).data();
  const float* slope = map.at(layers::kSlope).data();
  const size_t n = static_cast<size_t>(sx) * sy;
  auto level = [&](int64_t i) {
    return label[i] == 0 && !std::isnan(h[i]) && slope[i] < max_slope;
  };
  Regions r;
  r.id.assign(n, -1);
  std::vector<int64_t> stack;
  for (size_t start = 0; start < n; ++start) {
    if (r.id[start] >= 0 || !level(static_cast<int64_t>(start))) continue;
    const int32_t id = static_cast<int32_t>(r.size.size());
    int64_t count = 0;
    double sum = 0;
    r.id[start] = id;
    stack.assign(1, static_cast<int64_t>(start));
    while (!stack.empty()) {
      const int64_t i = stack.back();
      stack.pop_back();
      ++count;
      sum += h[i];
      const int x = static_cast<int>(i % sx), y = static_cast<int>(i / sx);
      for (const auto& d : kNeighbours4) {
        const int nx = x + d[0], ny = y + d[1];
        if (nx < 0 || ny < 0 || nx >= sx || ny >= sy) continue;
        const int64_t j = nx + static_cast<int64_t>(ny) * sx;
        if (r.id[j] >= 0 || !level(j) || std::fabs(double(h[j]) - h[i]) >= continuity) continue;
        r.id[j] = id;
        stack.push_back(j);
      }
    }
    r.size.push_back(count);
    r.height_sum.push_back(sum);
  }
  return r;
}

// Where one feature meets one region: the sum of the unit vectors from its cells into it.
struct Contact {
  Vector2 direction{Vector2::Zero()};
};

int Find(std::vector<int>* parent, int a) {
  while ((*parent)[a] != a) a = (*parent)[a] = (*parent)[(*parent)[a]];
  return a;
}

bool LeadsUp(ObstacleKind kind) {
  return kind == ObstacleKind::kRamp || kind == ObstacleKind::kStepUp ||
         kind == ObstacleKind::kStepDown;
}

// What a face rises onto its platform: from the lowest known ground up to kFallCells beyond each
// of its cells (away from the platform) to the platform's level, the median over its cells. A
// face whose foot lay in the edge's lidar shadow when it was measured reads lower between the
// surfaces beside it (the cells at its foot mix both levels) than the drop the platform ends in.
constexpr int kFallCells = 4;
double FallBeyond(const common::GridMap& map, const std::vector<int64_t>& cells, Vector2 outward,
                  double platform_m) {
  const int sx = map.size_x(), sy = map.size_y();
  const float* h = map.at(layers::kElevation).data();
  if (!(outward.norm() > 0)) return 0.0;
  outward.normalize();
  std::vector<double> falls;
  for (int64_t i : cells) {
    const double cx = static_cast<double>(i % sx), cy = static_cast<double>(i / sx);
    double lowest = std::numeric_limits<double>::infinity();
    for (int t = 0; t <= kFallCells; ++t) {
      const int x = static_cast<int>(std::lround(cx + t * outward.x()));
      const int y = static_cast<int>(std::lround(cy + t * outward.y()));
      if (x < 0 || y < 0 || x >= sx || y >= sy) break;
      const float v = h[x + static_cast<int64_t>(y) * sx];
      if (!std::isnan(v)) lowest = std::min(lowest, double(v));
    }
    if (std::isfinite(lowest)) falls.push_back(platform_m - lowest);
  }
  return falls.empty() ? 0.0 : Median(falls);
}

// The terrace of a group of features and the platforms they lead onto.
Obstacle BuildTerrace(const common::GridMap& map, const ObstacleParams& params,
                      const std::vector<MeasuredFeature>& features, const std::vector<int>& members,
                      const std::vector<int64_t>& platform_cells,
                      const std::map<int, Vector2>& heading_in,
                      const std::map<int, double>& platform_height) {
  Obstacle t;
  t.kind = ObstacleKind::kTerrace;
  std::vector<int64_t> cells = platform_cells;
  for (int k : members) {
    cells.insert(cells.end(), features[k].cells.begin(), features[k].cells.end());
  }
  std::sort(cells.begin(), cells.end());
  cells.erase(std::unique(cells.begin(), cells.end()), cells.end());
  MeasureShape(map, cells, params, &t);
  t.slope_rad = 0.0;
  t.height_m = 0.0;
  t.depth_m = 0.0;
  for (int k : members) {
    const Obstacle& o = features[k].obstacle;
    ObstaclePart p;
    p.kind = o.kind == ObstacleKind::kRamp ? ObstacleKind::kRamp : ObstacleKind::kStepUp;
    p.centroid_m = o.centroid_m;
    p.outline_m = o.outline_m;
    p.slope_rad = p.kind == ObstacleKind::kRamp ? o.slope_rad : 0.0;
    p.height_m = o.height_m;
    p.width_m = o.width_m;
    p.length_m = o.length_m;
    p.area_m2 = o.area_m2;
    p.num_cells = o.num_cells;
    const Vector2 d = heading_in.at(k);
    // Cell offsets are in the grid's frame; the heading is the world's.
    p.heading_in_rad =
        std::remainder(std::atan2(d.y(), d.x()) + map.geometry().origin.yaw_rad, 2 * M_PI);
    if (p.kind == ObstacleKind::kStepUp) {
      p.height_m =
          std::max(p.height_m, FallBeyond(map, features[k].cells, -d, platform_height.at(k)));
    }
    t.slope_rad = std::max(t.slope_rad, p.slope_rad);
    t.height_m = std::max(t.height_m, p.height_m);
    t.parts.push_back(std::move(p));
  }
  // Parts in the order of their centroids (y, then x), as the registry numbers its entries.
  std::stable_sort(t.parts.begin(), t.parts.end(),
                   [](const ObstaclePart& a, const ObstaclePart& b) {
                     if (a.centroid_m.y() != b.centroid_m.y())
                       return a.centroid_m.y() < b.centroid_m.y();
                     return a.centroid_m.x() < b.centroid_m.x();
                   });
  if (t.parts.size() > static_cast<size_t>(common::kMaxObstacleParts)) {
    t.parts.resize(common::kMaxObstacleParts);
  }
  return t;
}

}  // namespace

void JoinTerraces(const common::GridMap& map, const std::vector<int32_t>& label,
                  const ObstacleParams& params, std::vector<MeasuredFeature>* features) {
  if (!(params.max_terrace_area_m2 > 0) || features->size() < 2) return;
  const int sx = map.size_x(), sy = map.size_y();
  const double res = map.resolution_m();
  const float* h = map.at(layers::kElevation).data();
  const float* low = map.HasLayer(kFeatureLowLayer) ? map.at(kFeatureLowLayer).data() : nullptr;
  const float* high = map.HasLayer(kFeatureHighLayer) ? map.at(kFeatureHighLayer).data() : nullptr;
  const Regions regions =
      LabelLevelRegions(map, label, params.min_ramp_slope_rad, params.surface_continuity_m);
  if (regions.size.size() < 2) return;
  const int32_t ground = static_cast<int32_t>(
      std::max_element(regions.size.begin(), regions.size.end()) - regions.size.begin());
  const int64_t max_cells =
      static_cast<int64_t>(std::floor(params.max_terrace_area_m2 / (res * res) + 1e-9));
  auto candidate = [&](int32_t r) {
    return r >= 0 && r != ground && regions.size[r] >= params.min_cells &&
           regions.size[r] <= max_cells;
  };
  // Contacts of the ramps and steps with candidate platforms on their high side.
  std::map<std::pair<int32_t, int>, Contact> contacts;  // (region, feature) -> contact
  for (size_t k = 0; k < features->size(); ++k) {
    const MeasuredFeature& f = (*features)[k];
    if (!LeadsUp(f.obstacle.kind) || f.cells.empty()) continue;
    std::vector<double> heights;
    for (int64_t i : f.cells) {
      if (!std::isnan(h[i])) heights.push_back(h[i]);
    }
    if (heights.empty()) continue;
    // The level halfway up the feature: of a ramp, the middle of its heights; of a step, the
    // middle of its two sides (the cells of a drop into a gap lie on its high side alone).
    double mid = Median(heights) + 0.25 * f.obstacle.height_m;
    if (f.obstacle.kind != ObstacleKind::kRamp && low != nullptr && high != nullptr) {
      std::vector<double> lows, highs;
      for (int64_t i : f.cells) {
        if (std::isnan(low[i]) || std::isnan(high[i])) continue;
        lows.push_back(low[i]);
        highs.push_back(high[i]);
      }
      if (!lows.empty()) mid = 0.5 * (Median(lows) + Median(highs));
    }
    std::map<int32_t, Contact> mine;
    for (int64_t i : f.cells) {
      const int cx = static_cast<int>(i % sx), cy = static_cast<int>(i / sx);
      for (int dy = -kReachCells; dy <= kReachCells; ++dy) {
        for (int dx = -kReachCells; dx <= kReachCells; ++dx) {
          const int nx = cx + dx, ny = cy + dy;
          if ((dx == 0 && dy == 0) || nx < 0 || ny < 0 || nx >= sx || ny >= sy) continue;
          const int32_t r = regions.id[nx + static_cast<int64_t>(ny) * sx];
          if (!candidate(r)) continue;
          mine[r].direction += Vector2(dx, dy).normalized();
        }
      }
    }
    for (const auto& [r, c] : mine) {
      // The platform is on the feature's high side.
      if (regions.MeanHeight(r) > mid) contacts[{r, int(k)}] = c;
    }
  }
  // Features that lead onto one platform are one terrace.
  std::map<int32_t, std::vector<int>> onto;  // platform -> features
  for (const auto& [key, c] : contacts) onto[key.first].push_back(key.second);
  std::vector<int> parent(features->size());
  std::iota(parent.begin(), parent.end(), 0);
  std::vector<int32_t> platforms;
  for (const auto& [r, ks] : onto) {
    if (ks.size() < 2) continue;
    platforms.push_back(r);
    for (size_t m = 1; m < ks.size(); ++m) parent[Find(&parent, ks[m])] = Find(&parent, ks[0]);
  }
  if (platforms.empty()) return;
  std::map<int, std::vector<int>> groups;  // root -> members
  std::map<int, Vector2> heading_in;       // feature -> summed direction onto its platforms
  std::map<int, double> platform_height;   // feature -> the highest platform it leads onto
  for (int32_t r : platforms) {
    for (int k : onto[r]) {
      groups[Find(&parent, k)].push_back(k);
      heading_in[k] += contacts[{r, k}].direction;
      const auto it = platform_height.find(k);
      platform_height[k] = it == platform_height.end()
                               ? regions.MeanHeight(r)
                               : std::max(it->second, regions.MeanHeight(r));
    }
  }
  std::map<int, std::vector<int64_t>> platform_cells;  // root -> platform cells
  std::map<int32_t, int> root_of_platform;
  for (int32_t r : platforms) root_of_platform[r] = Find(&parent, onto[r][0]);
  for (size_t i = 0; i < regions.id.size(); ++i) {
    const auto it = root_of_platform.find(regions.id[i]);
    if (regions.id[i] >= 0 && it != root_of_platform.end()) {
      platform_cells[it->second].push_back(static_cast<int64_t>(i));
    }
  }
  std::vector<bool> joined(features->size(), false);
  std::vector<MeasuredFeature> terraces;
  for (auto& [root, members] : groups) {
    std::sort(members.begin(), members.end());
    members.erase(std::unique(members.begin(), members.end()), members.end());
    MeasuredFeature t;
    t.obstacle = BuildTerrace(map, params, *features, members, platform_cells[root], heading_in,
                              platform_height);
    for (int k : members) {
      joined[k] = true;
      t.cells.insert(t.cells.end(), (*features)[k].cells.begin(), (*features)[k].cells.end());
    }
    terraces.push_back(std::move(t));
  }
  std::vector<MeasuredFeature> out;
  for (size_t k = 0; k < features->size(); ++k) {
    if (!joined[k]) out.push_back(std::move((*features)[k]));
  }
  for (auto& t : terraces) out.push_back(std::move(t));
  *features = std::move(out);
}

PartJudgement JudgePart(const ObstaclePart& part, const common::RobotProfile& profile,
                        const std::string& hash) {
  PartJudgement j;
  j.verdict.profile = profile.name;
  j.verdict.profile_hash = hash;
  const bool ramp = part.kind == ObstacleKind::kRamp;
  if (ramp) {
    j.onto = part.slope_rad < profile.max_slope_up_rad;
    j.off = part.slope_rad < profile.max_slope_down_rad;
  } else {
    j.onto = part.height_m <= profile.max_step_up_m + kTol;
    j.off = part.height_m <= profile.max_step_down_m + kTol;
  }
  j.verdict.crossable = j.onto && j.off;
  if (j.verdict.crossable) return j;
  std::string& why = j.verdict.reason;
  if (!j.onto && !j.off) {
    why = ramp ? FormatNumbers("slope %.1f deg >= %.1f deg up and >= %.1f deg down",
                               part.slope_rad * kRadToDeg, profile.max_slope_up_rad * kRadToDeg,
                               profile.max_slope_down_rad * kRadToDeg)
               : FormatNumbers("step %.3f m > %.3f m up and > %.3f m down", part.height_m,
                               profile.max_step_up_m, profile.max_step_down_m);
  } else if (!j.onto) {
    why = ramp ? FormatNumbers("slope %.1f deg >= %.1f deg up", part.slope_rad * kRadToDeg,
                               profile.max_slope_up_rad * kRadToDeg)
               : FormatNumbers("step up %.3f m > %.3f m", part.height_m, profile.max_step_up_m);
    why += common::kOneWayMarker + FormatNumbers("off the platform only, heading %.0f deg",
                                                 HeadingDeg(part.heading_in_rad + M_PI));
  } else {
    why = ramp ? FormatNumbers("slope %.1f deg >= %.1f deg down", part.slope_rad * kRadToDeg,
                               profile.max_slope_down_rad * kRadToDeg)
               : FormatNumbers("step down %.3f m > %.3f m", part.height_m, profile.max_step_down_m);
    why += common::kOneWayMarker + FormatNumbers("onto the platform only, heading %.0f deg",
                                                 HeadingDeg(part.heading_in_rad));
  }
  return j;
}

common::ObstacleVerdict JudgeTerrace(const Obstacle& terrace, const common::RobotProfile& profile,
                                     const std::string& hash) {
  common::ObstacleVerdict v;
  v.profile = profile.name;
  v.profile_hash = hash;
  if (terrace.parts.empty()) {
    v.reason = "a terrace without parts";
    return v;
  }
  std::vector<PartJudgement> js;
  for (const auto& p : terrace.parts) js.push_back(JudgePart(p, profile, hash));
  auto name = [&](size_t k) {
    return "part " + std::to_string(k + 1) +
           (terrace.parts[k].kind == ObstacleKind::kRamp ? " (ramp)" : " (face)");
  };
  // What keeps each part from being crossed both ways, without its one-way clause.
  std::string limits;
  for (size_t k = 0; k < js.size(); ++k) {
    if (js[k].verdict.crossable) continue;
    std::string why = js[k].verdict.reason;
    const size_t marker = why.find(common::kOneWayMarker);
    if (marker != std::string::npos) why.resize(marker);
    limits += (limits.empty() ? "" : ", ") + name(k) + ": " + why;
  }
  int both = 0;
  for (const auto& j : js) both += j.onto && j.off;
  if (both >= 2) {
    v.crossable = true;  // onto it over one part and off over another, both ways
    return v;
  }
  for (size_t a = 0; a < js.size(); ++a) {
    for (size_t b = 0; b < js.size(); ++b) {
      if (a == b || !js[a].onto || !js[b].off) continue;
      const Vector2 d = terrace.parts[b].centroid_m - terrace.parts[a].centroid_m;
      v.reason =
          limits + common::kOneWayMarker +
          FormatNumbers("crossable heading %.0f deg only", HeadingDeg(std::atan2(d.y(), d.x()))) +
          ": onto it over " + name(a) + ", off over " + name(b);
      return v;
    }
  }
  bool any_onto = false, any_off = false;
  for (const auto& j : js) {
    any_onto |= j.onto;
    any_off |= j.off;
  }
  if (!any_onto) {
    v.reason = "no way onto the platform: " + limits;
  } else if (!any_off) {
    v.reason = "no way off the platform: " + limits;
  } else {
    size_t only = 0;
    for (size_t k = 0; k < js.size(); ++k) {
      if (js[k].onto && js[k].off) only = k;
    }
    v.reason = "onto the platform and off it over " + name(only) + " only: " + limits;
  }
  return v;
}

}  // namespace cairn::mapping::internal
