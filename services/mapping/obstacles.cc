#include "services/mapping/obstacles.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "common/check.h"
#include "common/layers.h"
#include "common/yaml_reader.h"
#include "services/mapping/ditch_detection.h"
#include "services/mapping/feature_classes.h"
#include "services/mapping/obstacle_shape.h"
#include "services/mapping/terraces.h"
#include "services/mapping/traversability.h"
#include <Eigen/Eigenvalues>

namespace cairn::mapping {
namespace {

using internal::kDitch;
using internal::kDrop;
using internal::kRamp;
using internal::kStep;
using internal::kWall;

using common::GridMap;
using common::Obstacle;
using common::ObstacleKind;
using common::Vector2;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kRadToDeg = 180.0 / M_PI;

constexpr std::array<std::array<int, 2>, 4> kNeighbours4{{{1, 0}, {-1, 0}, {0, 1}, {0, -1}}};
constexpr std::array<std::array<int, 2>, 8> kNeighbours8{
    {{1, 0}, {-1, 0}, {0, 1}, {0, -1}, {1, 1}, {1, -1}, {-1, 1}, {-1, -1}}};

// The classified grid: per cell its class and, for edges, the largest discontinuity.
struct Cells {
  int sx{0};
  int sy{0};
  const float* cls{nullptr};   // CellClass as float
  const float* edge{nullptr};  // height of the largest step/wall/drop at the cell
  const float* low{nullptr};   // lower side of that edge
  const float* high{nullptr};  // higher side of that edge
  const float* h{nullptr};     // elevation (NaN: unknown)
  int64_t Index(int x, int y) const { return x + static_cast<int64_t>(y) * sx; }
  bool Inside(int x, int y) const { return x >= 0 && y >= 0 && x < sx && y < sy; }
  uint8_t Class(int64_t i) const { return internal::ClassOf(cls[i]); }
};

// 8-connected components over the cells whose class is in `classes`, skipping labelled cells.
std::vector<std::vector<int64_t>> Components(const Cells& c, std::initializer_list<uint8_t> classes,
                                             std::vector<int32_t>* label, int32_t* next_label) {
  auto wanted = [&](uint8_t k) {
    for (uint8_t w : classes) {
      if (k == w) return true;
    }
    return false;
  };
  std::vector<std::vector<int64_t>> out;
  std::vector<int64_t> stack;
  for (int y = 0; y < c.sy; ++y) {
    for (int x = 0; x < c.sx; ++x) {
      const int64_t start = c.Index(x, y);
      if ((*label)[start] != 0 || !wanted(c.Class(start))) continue;
      const int32_t id = (*next_label)++;
      std::vector<int64_t> cells;
      stack.assign(1, start);
      (*label)[start] = id;
      while (!stack.empty()) {
        const int64_t i = stack.back();
        stack.pop_back();
        cells.push_back(i);
        const int cx = static_cast<int>(i % c.sx), cy = static_cast<int>(i / c.sx);
        for (const auto& d : kNeighbours8) {
          const int nx = cx + d[0], ny = cy + d[1];
          if (!c.Inside(nx, ny)) continue;
          const int64_t j = c.Index(nx, ny);
          if ((*label)[j] == 0 && wanted(c.Class(j))) {
            (*label)[j] = id;
            stack.push_back(j);
          }
        }
      }
      out.push_back(std::move(cells));
    }
  }
  return out;
}

// Surfaces: 4-connected known cells, walls excepted, whose neighbours differ by less than
// `continuity` (a ramp stays one surface, a step separates two). -1 for cells on none.
void LabelSurfaces(const Cells& c, const float* h, double continuity, std::vector<int32_t>* label,
                   std::vector<int64_t>* size) {
  const size_t n = static_cast<size_t>(c.sx) * c.sy;
  label->assign(n, -1);
  size->clear();
  std::vector<int64_t> stack;
  for (size_t start = 0; start < n; ++start) {
    if ((*label)[start] >= 0 || std::isnan(h[start]) || c.Class(start) == kWall) continue;
    const int32_t id = static_cast<int32_t>(size->size());
    int64_t count = 0;
    (*label)[start] = id;
    stack.assign(1, static_cast<int64_t>(start));
    while (!stack.empty()) {
      const int64_t i = stack.back();
      stack.pop_back();
      ++count;
      const int x = static_cast<int>(i % c.sx), y = static_cast<int>(i / c.sx);
      for (const auto& d : kNeighbours4) {
        if (!c.Inside(x + d[0], y + d[1])) continue;
        const int64_t j = c.Index(x + d[0], y + d[1]);
        if ((*label)[j] >= 0 || std::isnan(h[j]) || c.Class(j) == kWall) continue;
        if (std::fabs(double(h[j]) - h[i]) >= continuity) continue;
        (*label)[j] = id;
        stack.push_back(j);
      }
    }
    size->push_back(count);
  }
}

// A connected feature before measurement.
struct Found {
  ObstacleKind kind;
  std::vector<int64_t> cells;
};

// Grows a component by the unlabelled cells of `classes` within two cells of it.
void Absorb(const Cells& cells, std::initializer_list<uint8_t> classes, std::vector<int32_t>* label,
            std::vector<int64_t>* comp) {
  const int32_t id = (*label)[comp->front()];
  size_t ring_begin = 0;
  for (int ring = 0; ring < 2; ++ring) {
    const size_t ring_end = comp->size();
    for (size_t k = ring_begin; k < ring_end; ++k) {
      const int64_t i = (*comp)[k];
      const int cx = static_cast<int>(i % cells.sx), cy = static_cast<int>(i / cells.sx);
      for (const auto& d : kNeighbours8) {
        if (!cells.Inside(cx + d[0], cy + d[1])) continue;
        const int64_t j = cells.Index(cx + d[0], cy + d[1]);
        if ((*label)[j] != 0) continue;
        const uint8_t k2 = cells.Class(j);
        if (std::find(classes.begin(), classes.end(), k2) == classes.end()) continue;
        (*label)[j] = id;
        comp->push_back(j);
      }
    }
    ring_begin = ring_end;
  }
}

// True when the cells strictly between a and b (a straight line) hold no seen ground at the
// foot of a's edge: unknown cells (the object's unseen top or sides, its shadow) or raised ones
// (its seen top) lie between the faces of one object; floor seen between two walls is a gap
// the robot may pass (a doorway), and they stay two objects.
bool NothingFreeBetween(const Cells& c, int64_t a, int64_t b, double continuity_m) {
  const int ax = static_cast<int>(a % c.sx), ay = static_cast<int>(a / c.sx);
  const int bx = static_cast<int>(b % c.sx), by = static_cast<int>(b / c.sx);
  const int n = std::max(std::abs(bx - ax), std::abs(by - ay));
  const double foot = std::isnan(c.low[a]) ? c.h[a] : c.low[a];
  for (int t = 1; t < n; ++t) {
    const int x = ax + static_cast<int>(std::lround(double(bx - ax) * t / n));
    const int y = ay + static_cast<int>(std::lround(double(by - ay) * t / n));
    const int64_t i = c.Index(x, y);
    // Walls are the object's; anything else known at the foot's level is floor (a doorway's
    // floor between two wall ends may read as a narrow trench).
    if (std::isnan(c.h[i]) || c.Class(i) == internal::kWall) continue;
    if (!(c.h[i] > foot + continuity_m)) return false;
  }
  return true;
}

// The centre line of the piece labelled like cell a near it (its raised cells within `radius`
// cells), when that much of it is elongated: a point on it and its direction (unit), in cells;
// nullopt for a bulky object or a corner.
struct Line {
  Eigen::Vector2d point;
  Eigen::Vector2d dir;
};
std::optional<Line> LocalAxis(const Cells& c, const std::vector<int32_t>& label, int64_t a,
                              int radius) {
  const int ax = static_cast<int>(a % c.sx), ay = static_cast<int>(a / c.sx);
  Eigen::Vector2d sum = Eigen::Vector2d::Zero();
  Eigen::Matrix2d outer = Eigen::Matrix2d::Zero();
  int n = 0;
  for (int dy = -radius; dy <= radius; ++dy) {
    for (int dx = -radius; dx <= radius; ++dx) {
      if (!c.Inside(ax + dx, ay + dy)) continue;
      const int64_t i = c.Index(ax + dx, ay + dy);
      // The wall itself, not the floor cells at its feet (they widen it into a blob at its end).
      if (label[i] != label[a] || !(c.h[i] >= 0.5 * (double(c.low[i]) + c.high[i]))) continue;
      const Eigen::Vector2d p(dx, dy);
      sum += p;
      outer += p * p.transpose();
      ++n;
    }
  }
  if (n < radius) return std::nullopt;
  const Eigen::Vector2d mean = sum / n;
  const Eigen::Matrix2d cov = outer / n - mean * mean.transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(cov);
  // Along at least four times across (variances): a wall over the radius; not a corner.
  if (!(eig.eigenvalues()(1) >= 4.0 * std::max(eig.eigenvalues()(0), 1e-9))) return std::nullopt;
  return Line{Eigen::Vector2d(ax, ay) + mean, eig.eigenvectors().col(1)};
}

// True when a and b end two pieces of one straight wall: near each end the piece runs along
// the line between them (within 20 degrees) and the two pieces' centre lines agree (1.5 cells):
// a wall with an opening in it, not two walls side by side, offset, or two bulky objects.
bool InLine(const Cells& c, const std::vector<int32_t>& label, int64_t a, int64_t b, int run,
            std::map<int64_t, std::optional<Line>>* axes) {
  auto axis = [&](int64_t i) -> const std::optional<Line>& {
    auto it = axes->find(i);
    if (it == axes->end()) it = axes->emplace(i, LocalAxis(c, label, i, run)).first;
    return it->second;
  };
  const std::optional<Line>& la = axis(a);
  const std::optional<Line>& lb = axis(b);
  if (!la || !lb) return false;
  const Eigen::Vector2d d = lb->point - la->point;
  if (d.norm() < 1e-9) return false;
  const double cos_limit = std::cos(20.0 * M_PI / 180.0);
  for (const Line* l : {&*la, &*lb}) {
    if (std::fabs(l->dir.dot(d.normalized())) < cos_limit) return false;
    if (std::fabs(l->dir.x() * d.y() - l->dir.y() * d.x()) > 1.5) return false;
  }
  return true;
}

// Joins the components whose cells come within `gap_cells` of each other (Chebyshev) with no
// seen floor between them (NothingFreeBetween), relabelling the cells of each joined group with
// its first component's id: the faces of one object (a house's walls, a rock's sides) that the
// sensor saw as pieces, with unseen or unclassified cells between them; and, within
// `opening_cells`, two pieces of one straight wall across an opening (InLine).
void JoinNearby(const Cells& c, int gap_cells, int opening_cells, int run_cells,
                double continuity_m, std::vector<int32_t>* label,
                std::vector<std::vector<int64_t>>* comps) {
  const int reach = std::max(gap_cells, opening_cells);
  if (reach <= 0 || comps->size() < 2) return;
  std::map<int32_t, size_t> index_of;  // label id -> component
  for (size_t k = 0; k < comps->size(); ++k) index_of[(*label)[(*comps)[k].front()]] = k;
  std::vector<size_t> parent(comps->size());
  for (size_t k = 0; k < parent.size(); ++k) parent[k] = k;
  std::map<int64_t, std::optional<Line>> axes;  // LocalAxis of the cells looked at
  auto root = [&parent](size_t k) {
    while (parent[k] != k) k = parent[k] = parent[parent[k]];
    return k;
  };
  for (size_t k = 0; k < comps->size(); ++k) {
    for (const int64_t i : (*comps)[k]) {
      const int cx = static_cast<int>(i % c.sx), cy = static_cast<int>(i / c.sx);
      for (int dy = -reach; dy <= reach; ++dy) {
        for (int dx = -reach; dx <= reach; ++dx) {
          if (!c.Inside(cx + dx, cy + dy)) continue;
          const int64_t j = c.Index(cx + dx, cy + dy);
          const auto it = index_of.find((*label)[j]);
          if (it == index_of.end() || it->second == k || root(it->second) == root(k)) continue;
          const int d = std::max(std::abs(dx), std::abs(dy));
          const bool close = d <= gap_cells && NothingFreeBetween(c, i, j, continuity_m);
          const bool opening = d <= opening_cells && InLine(c, *label, i, j, run_cells, &axes);
          if (!close && !opening) continue;
          parent[root(it->second)] = root(k);
        }
      }
    }
  }
  std::vector<std::vector<int64_t>> joined;
  std::map<size_t, size_t> joined_of;  // root -> index in `joined`
  for (size_t k = 0; k < comps->size(); ++k) {
    const size_t r = root(k);
    auto [it, fresh] = joined_of.emplace(r, joined.size());
    if (fresh) joined.emplace_back();
    std::vector<int64_t>& group = joined[it->second];
    const int32_t id = group.empty() ? (*label)[(*comps)[k].front()] : (*label)[group.front()];
    for (const int64_t i : (*comps)[k]) {
      (*label)[i] = id;
      group.push_back(i);
    }
  }
  comps->swap(joined);
}

// A step or ditch whose every cell lies within `gap_cells` of one wall or object is part of it:
// the lower faces of a rock (under wall_min_height_m where the ground rises towards it), the
// shadowed ground behind it, a wall's foot seen apart from the wall. The object takes its cells.
// A feature that only touches an object (a step across a lane, from wall to wall) reaches
// farther and stays itself.
void JoinFringes(const Cells& c, int gap_cells, std::vector<int32_t>* label,
                 std::vector<Found>* found) {
  if (gap_cells <= 0) return;
  std::map<int32_t, size_t> object_of;  // label id -> index in `found`
  for (size_t k = 0; k < found->size(); ++k) {
    if ((*found)[k].kind == ObstacleKind::kWallOrObject && !(*found)[k].cells.empty()) {
      object_of[(*label)[(*found)[k].cells.front()]] = k;
    }
  }
  if (object_of.empty()) return;
  std::vector<bool> merged(found->size(), false);
  for (size_t k = 0; k < found->size(); ++k) {
    Found& f = (*found)[k];
    if (f.kind != ObstacleKind::kStepUp && f.kind != ObstacleKind::kDitch) continue;
    std::set<size_t> near;  // objects within reach of every cell so far
    bool first = true;
    for (const int64_t i : f.cells) {
      std::set<size_t> here;
      const int cx = static_cast<int>(i % c.sx), cy = static_cast<int>(i / c.sx);
      for (int dy = -gap_cells; dy <= gap_cells; ++dy) {
        for (int dx = -gap_cells; dx <= gap_cells; ++dx) {
          if (!c.Inside(cx + dx, cy + dy)) continue;
          const auto it = object_of.find((*label)[c.Index(cx + dx, cy + dy)]);
          if (it != object_of.end() && (first || near.count(it->second))) here.insert(it->second);
        }
      }
      near.swap(here);
      first = false;
      if (near.empty()) break;
    }
    if (near.empty()) continue;
    Found& object = (*found)[*near.begin()];
    const int32_t id = (*label)[object.cells.front()];
    for (const int64_t i : f.cells) {
      (*label)[i] = id;
      object.cells.push_back(i);
    }
    merged[k] = true;
  }
  std::vector<Found> kept;
  for (size_t k = 0; k < found->size(); ++k) {
    if (!merged[k]) kept.push_back(std::move((*found)[k]));
  }
  found->swap(kept);
}

// The connected features, each cell in one (`label` holds its component's id). Ditches
// first: step, drop and ramp cells near a ditch are its rims and walls (a wall face seen at an
// angle looks like a short ramp). Then walls and objects: low steps at their feet are partly
// seen faces. Then steps and drops, then ramps.
std::vector<Found> FindFeatures(const Cells& cells, int object_gap_cells, int opening_cells,
                                int run_cells, double continuity_m, std::vector<int32_t>* label) {
  std::vector<Found> found;
  int32_t next_label = 1;
  for (auto& comp : Components(cells, {kDitch}, label, &next_label)) {
    Absorb(cells, {kStep, kDrop, kRamp}, label, &comp);
    found.push_back({ObstacleKind::kDitch, std::move(comp)});
  }
  std::vector<std::vector<int64_t>> objects = Components(cells, {kWall}, label, &next_label);
  JoinNearby(cells, object_gap_cells, opening_cells, run_cells, continuity_m, label, &objects);
  for (auto& comp : objects) {
    Absorb(cells, {kStep, kDrop}, label, &comp);
    found.push_back({ObstacleKind::kWallOrObject, std::move(comp)});
  }
  for (auto& comp : Components(cells, {kStep, kDrop}, label, &next_label)) {
    found.push_back({ObstacleKind::kStepUp, std::move(comp)});
  }
  JoinFringes(cells, object_gap_cells, label, &found);
  for (auto& comp : Components(cells, {kRamp}, label, &next_label)) {
    found.push_back({ObstacleKind::kRamp, std::move(comp)});
  }
  return found;
}

// Measures the features of one map, kind by kind.
class FeatureMeasurer {
 public:
  FeatureMeasurer(const GridMap& map, const Cells& cells, const std::vector<int32_t>& label,
                  const ObstacleParams& params, const float* ditch_depth, const float* ditch_width)
      : map_(map),
        cells_(cells),
        label_(label),
        params_(params),
        sx_(map.size_x()),
        h_(map.at(layers::kElevation).data()),
        slope_(map.at(layers::kSlope).data()),
        ddepth_(ditch_depth),
        dwidth_(ditch_width),
        ring_stamp_(static_cast<size_t>(cells.sx) * cells.sy, 0) {}

  // The obstacle of a feature, or nullopt when it is too small or a noise patch.
  std::optional<Obstacle> Measure(const Found& f);

 private:
  void MeasureDitch(const std::vector<int64_t>& cells, Obstacle* o) const;
  void MeasureWall(const std::vector<int64_t>& cells, Obstacle* o) const;
  void MeasureStep(const std::vector<int64_t>& cells, Obstacle* o);
  // The heights next to a step, per surface (each ring cell once).
  std::map<int32_t, std::vector<double>> HeightsBeside(const std::vector<int64_t>& cells);
  void MeasureRamp(const std::vector<int64_t>& cells, Obstacle* o) const;
  bool MeetsFlatterGround(const std::vector<int64_t>& cells) const;

  const GridMap& map_;
  const Cells& cells_;
  const std::vector<int32_t>& label_;
  const ObstacleParams& params_;
  int sx_;
  const float* h_;
  const float* slope_;
  const float* ddepth_;
  const float* dwidth_;
  // Surfaces (for the direction of steps), labelled on first use.
  std::vector<int32_t> surface_;
  std::vector<int64_t> surface_size_;
  std::vector<int32_t> ring_stamp_;
};

void FeatureMeasurer::MeasureDitch(const std::vector<int64_t>& cells, Obstacle* o) const {
  std::vector<double> widths;
  double depth_seen = kNaN;
  for (int64_t i : cells) {
    if (std::isnan(ddepth_[i])) continue;  // a rim
    widths.push_back(dwidth_[i]);
    if (!std::isnan(h_[i])) {
      depth_seen = std::isnan(depth_seen) ? ddepth_[i] : std::max(depth_seen, double(ddepth_[i]));
    }
  }
  // Each cell's width is that of the narrowest line through it whose rims qualify. Where the
  // rims across are broken (a face cell, noise) only a diagonal may qualify, √2 wider: the
  // lower quartile is the width across where the rims were seen best.
  o->width_m = internal::Percentile(widths, 0.25);
  o->depth_m = depth_seen;
  o->height_m = std::isnan(depth_seen) ? 0.0 : depth_seen;
}

void FeatureMeasurer::MeasureWall(const std::vector<int64_t>& cells, Obstacle* o) const {
  double tallest = 0;
  for (int64_t i : cells) tallest = std::max(tallest, double(cells_.edge[i]));
  o->height_m = tallest;
}

std::map<int32_t, std::vector<double>> FeatureMeasurer::HeightsBeside(
    const std::vector<int64_t>& cells) {
  const int32_t own = label_[cells.front()];
  std::map<int32_t, std::vector<double>> beside;  // surface -> heights next to the step
  std::vector<int64_t> ring;
  for (int64_t i : cells) {
    const int cx = static_cast<int>(i % sx_), cy = static_cast<int>(i / sx_);
    for (int dy = -2; dy <= 2; ++dy) {
      for (int dx = -2; dx <= 2; ++dx) {
        if (!cells_.Inside(cx + dx, cy + dy)) continue;
        const int64_t j = cells_.Index(cx + dx, cy + dy);
        if (label_[j] == own || surface_[j] < 0) continue;
        ring.push_back(j);
      }
    }
  }
  // Each ring cell once (stamped with this component's label).
  for (int64_t j : ring) {
    if (ring_stamp_[j] == own) continue;
    ring_stamp_[j] = own;
    beside[surface_[j]].push_back(h_[j]);
  }
  return beside;
}

void FeatureMeasurer::MeasureStep(const std::vector<int64_t>& cells, Obstacle* o) {
  std::vector<double> heights;
  bool all_drops = true;
  for (int64_t i : cells) {
    heights.push_back(cells_.edge[i]);
    all_drops &= cells_.Class(i) == kDrop;
  }
  o->height_m = internal::Median(heights);
  if (all_drops) {
    o->kind = ObstacleKind::kStepDown;
    return;
  }
  // The step separates two surfaces: its height is the difference of their levels next to it
  // (a vertical face cut by a cell leaves intermediate edges that a median of the edges would
  // average in), and it goes up from the larger surface (the ground most of the site is on)
  // onto the smaller one, or down from it.
  if (surface_.empty()) {
    LabelSurfaces(cells_, h_, params_.surface_continuity_m, &surface_, &surface_size_);
  }
  std::map<int32_t, std::vector<double>> beside = HeightsBeside(cells);
  std::vector<std::pair<size_t, int32_t>> by_count;
  for (const auto& [id, hs] : beside) by_count.push_back({hs.size(), id});
  std::sort(by_count.rbegin(), by_count.rend());
  if (by_count.size() >= 2 && by_count[1].first >= 2) {
    const int32_t a = by_count[0].second, b = by_count[1].second;
    const double ha = internal::Median(beside[a]), hb = internal::Median(beside[b]);
    const int32_t lo = ha <= hb ? a : b, hi = ha <= hb ? b : a;
    o->height_m = std::fabs(ha - hb);
    o->kind =
        surface_size_[lo] >= surface_size_[hi] ? ObstacleKind::kStepUp : ObstacleKind::kStepDown;
    return;
  }
  // One surface on both sides (a small step within continuity): the edges tell.
  int64_t low_side = 0, high_side = 0;
  for (int64_t i : cells) {
    if (surface_[i] < 0) continue;
    const int64_t size = surface_size_[surface_[i]];
    if (double(h_[i]) <= 0.5 * (double(cells_.low[i]) + cells_.high[i])) {
      low_side = std::max(low_side, size);
    } else {
      high_side = std::max(high_side, size);
    }
  }
  o->kind = low_side >= high_side ? ObstacleKind::kStepUp : ObstacleKind::kStepDown;
}

void FeatureMeasurer::MeasureRamp(const std::vector<int64_t>& cells, Obstacle* o) const {
  // The sustained slope: the 75th percentile over the interior (cells whose 4-neighbours are
  // all ramp), which leaves out the tilted-normal cells at the foot and the top and does not
  // average a steep section away with a gentle one.
  std::vector<double> interior_slopes, all_slopes;
  double lo = 1e300, hi = -1e300;
  const int32_t own = label_[cells.front()];
  for (int64_t i : cells) {
    const int cx = static_cast<int>(i % sx_), cy = static_cast<int>(i / sx_);
    bool interior = true;
    for (const auto& d : kNeighbours4) {
      interior &=
          cells_.Inside(cx + d[0], cy + d[1]) && label_[cells_.Index(cx + d[0], cy + d[1])] == own;
    }
    all_slopes.push_back(slope_[i]);
    if (interior) interior_slopes.push_back(slope_[i]);
    lo = std::min(lo, double(h_[i]));
    hi = std::max(hi, double(h_[i]));
  }
  // ... and at least the slope of the plane fitted to the ramp's heights, which normals at the
  // edge of what was seen cannot flatten.
  o->slope_rad =
      std::max(internal::Percentile(interior_slopes.empty() ? all_slopes : interior_slopes, 0.75),
               internal::PlaneSlope(map_, cells));
  o->height_m = hi - lo;
}

// A ramp is built: it meets flatter ground at creases (its foot, its top), where the ground two
// cells beyond its edge slopes at most half as much as the ramp a cell inside it. A hillside fades
// out instead: just outside a patch of it the ground slopes almost as much. True when at least
// min_ramp_crease_fraction of the featureless known ground two cells beyond the ramp's edge is
// that much flatter.
bool FeatureMeasurer::MeetsFlatterGround(const std::vector<int64_t>& cells) const {
  const int32_t own = label_[cells.front()];
  int64_t beyond = 0, flatter = 0;
  for (int64_t i : cells) {
    const int cx = static_cast<int>(i % sx_), cy = static_cast<int>(i / sx_);
    for (const auto& d : kNeighbours4) {
      const int ex = cx + d[0], ey = cy + d[1];
      const int ox = cx + 2 * d[0], oy = cy + 2 * d[1];
      if (!cells_.Inside(ex, ey) || !cells_.Inside(ox, oy)) continue;
      if (label_[cells_.Index(ex, ey)] == own) continue;  // not the edge this way
      const int64_t j = cells_.Index(ox, oy);
      if (label_[j] != 0 || cells_.Class(j) != internal::kNone || std::isnan(slope_[j])) continue;
      // The ramp's own slope a cell in from its edge (the edge cell's normal is tilted by the
      // crease itself).
      const int ix = cx - d[0], iy = cy - d[1];
      const int64_t in =
          cells_.Inside(ix, iy) && label_[cells_.Index(ix, iy)] == own ? cells_.Index(ix, iy) : i;
      if (std::isnan(slope_[in])) continue;
      ++beyond;
      flatter += slope_[j] <= 0.5 * slope_[in];
    }
  }
  return beyond > 0 && flatter >= params_.min_ramp_crease_fraction * beyond;
}

std::optional<Obstacle> FeatureMeasurer::Measure(const Found& f) {
  const double res = map_.resolution_m();
  const bool small = static_cast<int>(f.cells.size()) < params_.min_cells;
  if (small && (f.cells.size() < 2 || !(params_.min_small_feature_height_m > 0))) {
    return std::nullopt;
  }
  if (f.kind == ObstacleKind::kRamp &&
      f.cells.size() * res * res + 1e-9 < params_.min_ramp_area_m2) {
    return std::nullopt;
  }
  Obstacle o;
  o.kind = f.kind;
  internal::MeasureShape(map_, f.cells, params_, &o);
  double max_slope = 0;
  for (int64_t i : f.cells) {
    if (!std::isnan(slope_[i])) max_slope = std::max(max_slope, double(slope_[i]));
  }
  o.slope_rad = max_slope;
  o.depth_m = 0.0;
  switch (f.kind) {
    case ObstacleKind::kDitch:
      MeasureDitch(f.cells, &o);
      break;
    case ObstacleKind::kWallOrObject:
      MeasureWall(f.cells, &o);
      break;
    case ObstacleKind::kStepUp:
      MeasureStep(f.cells, &o);
      o.downhill_heading_rad = internal::DownhillHeading(map_, f.cells);
      break;
    case ObstacleKind::kRamp:
      MeasureRamp(f.cells, &o);
      if (!MeetsFlatterGround(f.cells)) return std::nullopt;  // a hillside
      o.downhill_heading_rad = internal::DownhillHeading(map_, f.cells);
      break;
    case ObstacleKind::kTerrace:  // joined from measured features (terraces.h), never found
    case ObstacleKind::kStepDown:
      break;
  }
  if ((o.kind == ObstacleKind::kStepUp || o.kind == ObstacleKind::kStepDown) &&
      o.height_m < params_.small_step_height_m &&
      (o.length_m < params_.min_small_step_length_m ||
       o.length_m < params_.min_small_step_elongation * o.width_m)) {
    return std::nullopt;  // a noise patch
  }
  if (small && !(o.height_m >= params_.min_small_feature_height_m)) return std::nullopt;
  return o;
}

// A ditch's floor is the low ground around it: nothing within two cells lies `drop_m` below it
// (within two cells of a trench's floor are its faces and rims). The top of a wall seen from
// afar, its sides unseen and its edges unclassified, is no floor.
bool LowestAround(const internal::TerrainView& view, int x, int y, double drop_m) {
  const double floor_m = double(view.H(x, y)) - drop_m;
  for (int dy = -2; dy <= 2; ++dy) {
    for (int dx = -2; dx <= 2; ++dx) {
      if (view.Inside(x + dx, y + dy) && view.H(x + dx, y + dy) < floor_m) return false;
    }
  }
  return true;
}

// Known cells that lie in a ditch whose bottom was seen (internal::TestSeenBottom, at most
// seen_ditch_max_width_m wide) become ditch cells with that depth and width; their rims
// and faces join them as the rims of a ditch with an unseen gap do. Cells already in a ditch,
// walls and drops are left as they are.
void AddSeenDitches(const GridMap& map, const ObstacleParams& params, std::vector<float>* cls,
                    std::vector<float>* ddepth, std::vector<float>* dwidth) {
  if (!(params.seen_ditch_max_width_m > 0)) return;
  TraversabilityParams ditch;
  ditch.min_ditch_depth_m = params.min_drop_height_m;
  ditch.max_ditch_search_m = params.seen_ditch_max_width_m;
  const internal::TerrainView view{
      map.at(layers::kElevation).data(),
      map.HasLayer(layers::kGroundBound) ? map.at(layers::kGroundBound).data() : nullptr,
      map.size_x(), map.size_y()};
  const double res = map.resolution_m();
  for (int y = 0; y < view.sy; ++y) {
    for (int x = 0; x < view.sx; ++x) {
      const int64_t i = x + static_cast<int64_t>(y) * view.sx;
      const auto k = internal::ClassOf((*cls)[i]);
      if (std::isnan(view.h[i]) || !std::isnan((*ddepth)[i]) ||
          !(k == internal::kNone || k == kStep || k == kRamp)) {
        continue;
      }
      const auto bottom = internal::TestSeenBottom(view, x, y, ditch, res);
      // The neighbourhood is read only for the rare cell that passes the gap test.
      if (!bottom || !LowestAround(view, x, y, params.min_drop_height_m)) continue;
      (*cls)[i] = kDitch;
      (*ddepth)[i] = static_cast<float>(bottom->depth_m);
      (*dwidth)[i] = static_cast<float>(bottom->width_m);
    }
  }
}

// Numbered by centroid (y, then x): the same map always gives the same ids.

using internal::FormatNumbers;

// ", heading 90 deg +- 45 deg" for a heading (rad), "" when it is unknown (NaN).
std::string HeadingText(double heading_rad) {
  if (!std::isfinite(heading_rad)) return "";
  return FormatNumbers(", heading %.0f deg +- 45 deg", internal::HeadingDeg(heading_rad));
}

}  // namespace

void ObstacleParams::Validate() const {
  CAIRN_THROW_UNLESS(min_ramp_slope_rad >= 0 && min_ramp_slope_rad < M_PI / 2,
                     "min_ramp_slope_rad must be in [0, pi/2), got " << min_ramp_slope_rad);
  CAIRN_THROW_UNLESS(min_step_height_m > 0, "min_step_height_m must be positive");
  CAIRN_THROW_UNLESS(min_cells >= 1, "min_cells must be >= 1, got " << min_cells);
  CAIRN_THROW_UNLESS(
      std::isfinite(min_small_feature_height_m),
      "min_small_feature_height_m must be finite, got " << min_small_feature_height_m);
  CAIRN_THROW_UNLESS(step_contrast >= 1, "step_contrast must be >= 1, got " << step_contrast);
  CAIRN_THROW_UNLESS(std::isfinite(step_noise_sigmas) && step_noise_sigmas >= 0,
                     "step_noise_sigmas must be >= 0, got " << step_noise_sigmas);
  CAIRN_THROW_UNLESS(wall_min_height_m > min_step_height_m,
                     "wall_min_height_m must exceed min_step_height_m");
  CAIRN_THROW_UNLESS(min_drop_height_m > 0, "min_drop_height_m must be positive");
  CAIRN_THROW_UNLESS(min_ramp_area_m2 >= 0, "min_ramp_area_m2 must be >= 0");
  CAIRN_THROW_UNLESS(std::isfinite(object_join_gap_m) && object_join_gap_m >= 0,
                     "object_join_gap_m must be >= 0, got " << object_join_gap_m);
  CAIRN_THROW_UNLESS(std::isfinite(object_opening_max_m) && object_opening_max_m >= 0 &&
                         object_opening_max_m <= 5.0,
                     "object_opening_max_m must be in [0, 5], got " << object_opening_max_m);
  CAIRN_THROW_UNLESS(std::isfinite(object_opening_run_m) && object_opening_run_m > 0,
                     "object_opening_run_m must be > 0, got " << object_opening_run_m);
  CAIRN_THROW_UNLESS(
      min_ramp_crease_fraction >= 0 && min_ramp_crease_fraction <= 1,
      "min_ramp_crease_fraction must be in [0, 1], got " << min_ramp_crease_fraction);
  CAIRN_THROW_UNLESS(
      small_step_height_m >= 0 && min_small_step_length_m >= 0 && min_small_step_elongation >= 0,
      "small step limits must be >= 0");
  CAIRN_THROW_UNLESS(surface_continuity_m > 0, "surface_continuity_m must be positive");
  CAIRN_THROW_UNLESS(outline_tolerance_cells >= 0, "outline_tolerance_cells must be >= 0");
  CAIRN_THROW_UNLESS(std::isfinite(seen_ditch_max_width_m) && seen_ditch_max_width_m >= 0,
                     "seen_ditch_max_width_m must be >= 0, got " << seen_ditch_max_width_m);
  CAIRN_THROW_UNLESS(std::isfinite(max_terrace_area_m2) && max_terrace_area_m2 >= 0,
                     "max_terrace_area_m2 must be >= 0, got " << max_terrace_area_m2);
}

common::ObstacleRegistry ExtractObstacles(const GridMap& map_in, const ObstacleParams& params) {
  params.Validate();
  CAIRN_THROW_UNLESS(map_in.HasLayer(layers::kElevation),
                     "the map has no '" << layers::kElevation << "' layer");
  GridMap map = map_in;
  if (!map.HasLayer(layers::kSlope) || !map.HasLayer(layers::kDitchDepth) ||
      !map.HasLayer(kNormalXLayer) || !map.HasLayer(kNormalYLayer)) {
    ComputeGeometricLayers(&map, TraversabilityParams{});
  }
  ComputeFeatureLayers(&map, params, CellRect::All(map));
  return AssembleObstacles(map, params);
}

common::ObstacleRegistry AssembleObstacles(const GridMap& map, const ObstacleParams& params) {
  params.Validate();
  for (const char* name :
       {layers::kElevation, layers::kSlope, layers::kDitchDepth, layers::kDitchWidth,
        kFeatureClassLayer, kFeatureEdgeLayer, kFeatureLowLayer, kFeatureHighLayer}) {
    CAIRN_THROW_UNLESS(map.HasLayer(name), "the map has no '" << name << "' layer");
  }
  // Ditches whose bottom the sensor saw, which the ditch layers (the cost layer's) keep only
  // beside a gap nobody saw: working copies of the classes and the ditch layers.
  std::vector<float> cls(map.at(kFeatureClassLayer).data(),
                         map.at(kFeatureClassLayer).data() + map.at(kFeatureClassLayer).size());
  std::vector<float> ddepth(map.at(layers::kDitchDepth).data(),
                            map.at(layers::kDitchDepth).data() + cls.size());
  std::vector<float> dwidth(map.at(layers::kDitchWidth).data(),
                            map.at(layers::kDitchWidth).data() + cls.size());
  AddSeenDitches(map, params, &cls, &ddepth, &dwidth);
  Cells cells;
  cells.sx = map.size_x();
  cells.sy = map.size_y();
  cells.cls = cls.data();
  cells.edge = map.at(kFeatureEdgeLayer).data();
  cells.low = map.at(kFeatureLowLayer).data();
  cells.high = map.at(kFeatureHighLayer).data();
  cells.h = map.at(layers::kElevation).data();
  std::vector<int32_t> label(static_cast<size_t>(cells.sx) * cells.sy, 0);
  auto cells_of = [&](double m) {
    return static_cast<int>(std::floor(m / map.resolution_m() + 1e-9));
  };
  const std::vector<Found> found = FindFeatures(
      cells, cells_of(params.object_join_gap_m), cells_of(params.object_opening_max_m),
      std::max(3, cells_of(params.object_opening_run_m)), params.surface_continuity_m, &label);
  FeatureMeasurer measurer(map, cells, label, params, ddepth.data(), dwidth.data());
  std::vector<internal::MeasuredFeature> measured;
  for (const Found& f : found) {
    if (std::optional<Obstacle> o = measurer.Measure(f))
      measured.push_back({std::move(*o), f.cells});
  }
  internal::JoinTerraces(map, label, params, &measured);
  common::ObstacleRegistry registry;
  for (auto& m : measured) registry.obstacles.push_back(std::move(m.obstacle));
  internal::NumberByCentroid(&registry);
  return registry;
}

namespace {
common::ObstacleVerdict JudgeWithHash(const Obstacle& o, const common::RobotProfile& profile,
                                      const std::string& hash);
}  // namespace

common::ObstacleVerdict JudgeObstacle(const Obstacle& o, const common::RobotProfile& profile) {
  return JudgeWithHash(o, profile, profile.ContentHash());
}

namespace {
// The verdict with the profile's content hash computed once by the caller.
common::ObstacleVerdict JudgeWithHash(const Obstacle& o, const common::RobotProfile& profile,
                                      const std::string& hash) {
  common::ObstacleVerdict v;
  v.profile = profile.name;
  v.profile_hash = hash;
  v.crossable = true;
  constexpr double kTol = 1e-6;
  switch (o.kind) {
    case ObstacleKind::kRamp: {
      const double limit = std::min(profile.max_slope_up_rad, profile.max_slope_down_rad);
      if (!(o.slope_rad < limit)) {
        v.crossable = false;
        v.reason =
            FormatNumbers("slope %.1f deg >= %.1f deg", o.slope_rad * kRadToDeg, limit * kRadToDeg);
        // Within the other limit: the directed layer lets the robot drive it that way.
        if (o.slope_rad < std::max(profile.max_slope_up_rad, profile.max_slope_down_rad)) {
          const bool downhill = profile.max_slope_up_rad < profile.max_slope_down_rad;
          v.reason += std::string(common::kOneWayMarker) +
                      (downhill ? "crossable downhill only" : "crossable uphill only") +
                      HeadingText(o.downhill_heading_rad + (downhill ? 0.0 : M_PI));
        }
      }
      break;
    }
    case ObstacleKind::kStepUp:
      if (!(o.height_m <= profile.max_step_up_m + kTol)) {
        v.crossable = false;
        v.reason = FormatNumbers("step up %.3f m > %.3f m", o.height_m, profile.max_step_up_m);
        if (o.height_m <= profile.max_step_down_m + kTol) {
          v.reason += common::kOneWayMarker +
                      FormatNumbers("crossable downwards only (<= %.3f m step down)",
                                    profile.max_step_down_m) +
                      HeadingText(o.downhill_heading_rad);
        }
      }
      break;
    case ObstacleKind::kStepDown:
      if (!(o.height_m <= profile.max_step_down_m + kTol)) {
        v.crossable = false;
        v.reason = FormatNumbers("step down %.3f m > %.3f m", o.height_m, profile.max_step_down_m);
        if (o.height_m <= profile.max_step_up_m + kTol) {
          v.reason +=
              common::kOneWayMarker +
              FormatNumbers("crossable upwards only (<= %.3f m step up)", profile.max_step_up_m) +
              HeadingText(o.downhill_heading_rad + M_PI);
        }
      }
      break;
    case ObstacleKind::kDitch: {
      const bool bridged = o.width_m <= profile.max_ditch_width_m + kTol;
      const bool drivable =
          std::isfinite(o.depth_m) &&
          o.depth_m <= std::min(profile.max_step_down_m, profile.max_step_up_m) + kTol;
      if (!bridged && !drivable) {
        v.crossable = false;
        v.reason = std::isfinite(o.depth_m)
                       ? FormatNumbers("ditch %.2f m wide > %.2f m and too deep", o.width_m,
                                       profile.max_ditch_width_m)
                       : FormatNumbers("ditch %.2f m wide > %.2f m, bottom unseen", o.width_m,
                                       profile.max_ditch_width_m);
      }
      break;
    }
    case ObstacleKind::kTerrace:
      return internal::JudgeTerrace(o, profile, hash);
    case ObstacleKind::kWallOrObject:
      if (std::isnan(o.height_m)) {
        // A sonar contact: seen at the vehicle's depth, its height not measured.
        v.crossable = false;
        v.reason = "a contact of unmeasured height (sonar)";
      } else if (!(o.height_m <= profile.max_step_up_m + kTol)) {
        v.crossable = false;
        v.reason =
            FormatNumbers("wall or object %.2f m high > %.3f m", o.height_m, profile.max_step_up_m);
      }
      break;
  }
  return v;
}
}  // namespace

std::vector<common::ObstacleVerdict> JudgeParts(const Obstacle& o,
                                                const common::RobotProfile& profile) {
  std::vector<common::ObstacleVerdict> out;
  const std::string hash = profile.ContentHash();
  for (const auto& part : o.parts) out.push_back(internal::JudgePart(part, profile, hash).verdict);
  return out;
}

namespace {
// Replaces the verdict of `v.profile` in `verdicts` (others are kept).
void ReplaceVerdict(common::ObstacleVerdict v, std::vector<common::ObstacleVerdict>* verdicts) {
  verdicts->erase(
      std::remove_if(verdicts->begin(), verdicts->end(),
                     [&](const common::ObstacleVerdict& w) { return w.profile == v.profile; }),
      verdicts->end());
  verdicts->push_back(std::move(v));
}
}  // namespace

void LabelObstacles(common::ObstacleRegistry* registry,
                    const std::vector<common::RobotProfile>& profiles) {
  CAIRN_THROW_UNLESS(registry != nullptr, "no registry");
  std::vector<std::string> hashes;
  for (const auto& profile : profiles) hashes.push_back(profile.ContentHash());
  for (auto& o : registry->obstacles) {
    for (size_t k = 0; k < profiles.size(); ++k) {
      ReplaceVerdict(JudgeWithHash(o, profiles[k], hashes[k]), &o.verdicts);
      for (auto& part : o.parts) {
        ReplaceVerdict(internal::JudgePart(part, profiles[k], hashes[k]).verdict, &part.verdicts);
      }
    }
  }
}

ObstacleParams LoadObstacleParams(common::YamlMap& m) {
  ObstacleParams p;
  m.Get("min_ramp_slope_rad", &p.min_ramp_slope_rad);
  m.Get("min_step_height_m", &p.min_step_height_m);
  m.Get("min_cells", &p.min_cells);
  m.Get("min_small_feature_height_m", &p.min_small_feature_height_m);
  m.Get("step_contrast", &p.step_contrast);
  m.Get("step_noise_sigmas", &p.step_noise_sigmas);
  m.Get("wall_min_height_m", &p.wall_min_height_m);
  m.Get("min_drop_height_m", &p.min_drop_height_m);
  m.Get("min_ramp_area_m2", &p.min_ramp_area_m2);
  m.Get("object_join_gap_m", &p.object_join_gap_m);
  m.Get("object_opening_max_m", &p.object_opening_max_m);
  m.Get("object_opening_run_m", &p.object_opening_run_m);
  m.Get("min_ramp_crease_fraction", &p.min_ramp_crease_fraction);
  m.Get("small_step_height_m", &p.small_step_height_m);
  m.Get("min_small_step_length_m", &p.min_small_step_length_m);
  m.Get("min_small_step_elongation", &p.min_small_step_elongation);
  m.Get("surface_continuity_m", &p.surface_continuity_m);
  m.Get("outline_tolerance_cells", &p.outline_tolerance_cells);
  m.Get("seen_ditch_max_width_m", &p.seen_ditch_max_width_m);
  m.Get("max_terrace_area_m2", &p.max_terrace_area_m2);
  m.Finish();
  return p;
}

}  // namespace cairn::mapping
