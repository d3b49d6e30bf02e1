#include "services/explore/nbv.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <queue>
#include <stdexcept>

namespace cairn::explore {
namespace {

// The least height of steep points in a cell that hides what is behind it (Evaluate).
constexpr float kMinWallHeightM = 0.5f;

constexpr double kPi = 3.14159265358979323846;

void RequireUnit(double v, const char* name) {
  if (!(v >= 0.0 && v <= 1.0)) {
    throw std::invalid_argument(std::string("nbv: ") + name + " must lie in [0, 1]");
  }
}

void RequirePositive(double v, const char* name) {
  if (!(v > 0.0) || !std::isfinite(v)) {
    throw std::invalid_argument(std::string("nbv: ") + name + " must be positive");
  }
}

struct Preset {
  const char* name;
  const char* source;
  NbvWeights weights;
  NbvStrategy strategy;
};

// Seed 002's tables 6-2 (simple world), 6-4 (structured), 6-6 (unstructured), 6-8 (CARTIF)
// and 6-9 (El Pinarón), plus the greedy-mapping baseline of table 6-2's experiment IV.
const Preset kPresets[] = {
    {"simple-balanced", "6.2.1.I", {0.43, 0.35, 0.22, 0.09}, NbvStrategy::kUtility},
    {"simple-information", "6.2.1.II", {0.65, 0.25, 0.10, 0.09}, NbvStrategy::kUtility},
    {"simple-quality", "6.2.1.III", {0.36, 0.50, 0.14, 0.09}, NbvStrategy::kUtility},
    {"greedy", "6.2.1.IV", {1.0, 0.0, 0.0, 0.09}, NbvStrategy::kGreedy},
    {"structured-zones-quality", "6.2.2.I", {0.20, 0.55, 0.25, 0.09}, NbvStrategy::kUtility},
    {"structured-information", "6.2.2.II", {0.65, 0.25, 0.10, 0.08}, NbvStrategy::kUtility},
    {"unstructured-balanced", "6.2.3.I", {0.40, 0.35, 0.25, 0.125}, NbvStrategy::kUtility},
    {"unstructured-information", "6.2.3.II", {0.65, 0.30, 0.05, 0.08}, NbvStrategy::kUtility},
    {"cartif-fast", "6.3.1.I", {0.84, 0.10, 0.05, 0.05}, NbvStrategy::kUtility},
    {"cartif-quality", "6.3.1.II", {0.35, 0.40, 0.15, 0.40}, NbvStrategy::kUtility},
    {"pinaron", "6.3.2.I", {0.55, 0.30, 0.15, 0.16}, NbvStrategy::kUtility},
};

}  // namespace

void NbvParams::Validate() const {
  RequireUnit(weights.w_a, "w_a");
  RequireUnit(weights.w_q, "w_q");
  RequireUnit(weights.w_o, "w_o");
  RequirePositive(weights.w_c, "w_c");
  RequirePositive(d_max_m, "d_max_m");
  RequireUnit(min_global_quality, "min_global_quality");
  RequireUnit(safe_cnc, "safe_cnc");
  RequirePositive(candidate_spacing_m, "candidate_spacing_m");
  if (candidate_fraction < 1) {
    throw std::invalid_argument("nbv: candidate_fraction must be >= 1");
  }
  if (!(candidate_clearance_m >= 0.0) || !std::isfinite(candidate_clearance_m)) {
    throw std::invalid_argument("nbv: candidate_clearance_m must be >= 0");
  }
  if (!(robot_free_radius_m >= 0.0) || !std::isfinite(robot_free_radius_m)) {
    throw std::invalid_argument("nbv: robot_free_radius_m must be >= 0");
  }
  if (!(revisit_radius_m >= 0.0) || !std::isfinite(revisit_radius_m)) {
    throw std::invalid_argument("nbv: revisit_radius_m must be >= 0");
  }
  RequireUnit(occlusion_cnc, "occlusion_cnc");
  RequirePositive(gain_range_m, "gain_range_m");
  if (!(scanner_height_m >= 0.0) || !std::isfinite(scanner_height_m)) {
    throw std::invalid_argument("nbv: scanner_height_m must be >= 0");
  }
  RequirePositive(pan_step_rad, "pan_step_rad");
  RequirePositive(tilt_step_rad, "tilt_step_rad");
  RequirePositive(a_max_m2, "a_max_m2");
  RequireUnit(w_a_quality, "w_a_quality");
  RequireUnit(w_n_quality, "w_n_quality");
  if (w_a_quality + w_n_quality <= 0.0) {
    throw std::invalid_argument("nbv: w_a_quality and w_n_quality cannot both be 0");
  }
  RequireUnit(greedy_min_gain, "greedy_min_gain");
  if (!(missed_view_step_m >= 0.0) || !std::isfinite(missed_view_step_m)) {
    throw std::invalid_argument("nbv: missed_view_step_m must be >= 0");
  }
}

NbvParams NbvPreset(const std::string& name, NbvParams base) {
  for (const Preset& p : kPresets) {
    if (name == p.name) {
      base.weights = p.weights;
      base.strategy = p.strategy;
      return base;
    }
  }
  std::string known;
  for (const Preset& p : kPresets) known += std::string(known.empty() ? "" : ", ") + p.name;
  throw std::invalid_argument("nbv: unknown preset '" + name + "' (known: " + known + ")");
}

std::vector<std::string> NbvPresetNames() {
  std::vector<std::string> names;
  for (const Preset& p : kPresets) names.emplace_back(p.name);
  return names;
}

double Utility(const NbvWeights& w, double info_gain, double quality_gain, double zone_gain,
               double path_cost) {
  const double numerator = w.w_a * info_gain + w.w_q * quality_gain + w.w_o * zone_gain;
  return numerator / (w.w_c * std::max(path_cost, 1e-9));
}

double StopThreshold(double w_c, double d_max_m) { return 0.5 / (w_c * d_max_m); }

double CombineQuality(double area_score, double incidence_score, double w_a, double w_n) {
  const double a = w_a * area_score, n = w_n * incidence_score;
  return std::sqrt(a * a + n * n) / std::sqrt(w_a * w_a + w_n * w_n);
}

std::vector<int64_t> NavigationTree::PathTo(int64_t cell) const {
  std::vector<int64_t> path;
  if (cell < 0 || cell >= static_cast<int64_t>(cost.size()) || !Reachable(cell)) return path;
  for (int64_t c = cell; c != -1; c = parent[c]) path.push_back(c);
  std::reverse(path.begin(), path.end());
  return path;
}

NavigationTree BuildNavigationTree(const InfoMap& map, int64_t root, double safe_cnc,
                                   double free_radius_m, float root_ground_z_m) {
  if (root < 0 || root >= map.num_nodes()) {
    throw std::invalid_argument("navigation tree: the root node is off the map");
  }
  NavigationTree tree;
  tree.root = root;
  const size_t nodes = static_cast<size_t>(map.num_nodes());
  tree.cost.assign(nodes, std::numeric_limits<float>::infinity());
  tree.parent.assign(nodes, -1);
  // The ground each reached node stands on: its own, or (unexplored under the robot) its
  // parent's. A move into a cell of two levels takes the level nearest it.
  std::vector<float> ground(nodes, std::numeric_limits<float>::quiet_NaN());
  using Entry = std::pair<float, int64_t>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> open;
  tree.cost[root] = 0.f;
  ground[root] = std::isnan(map.GroundHeight(root)) ? root_ground_z_m : map.GroundHeight(root);
  open.push({0.f, root});
  const int sx = map.size_x(), sy = map.size_y();
  const float res = static_cast<float>(map.geometry().resolution_m);
  const float safe = static_cast<float>(safe_cnc);
  const common::CellIndex root_cell = map.Cell(root);
  const double free_radius_cells =
      std::isfinite(free_radius_m) && free_radius_m > 0.0 ? free_radius_m / res : 0.0;
  // Unexplored cells this near the root: the robot stands there (its scanner cannot see them).
  const auto under_robot = [&](int64_t j) {
    const common::CellIndex c = map.Cell(j);
    const double dx = static_cast<double>(c.ix - root_cell.ix);
    const double dy = static_cast<double>(c.iy - root_cell.iy);
    return !map.CellExplored(j) && dx * dx + dy * dy <= free_radius_cells * free_radius_cells;
  };
  while (!open.empty()) {
    const auto [c, i] = open.top();
    open.pop();
    if (c > tree.cost[i]) continue;
    const int64_t cell = map.NodeCell(i);
    const int ix = static_cast<int>(cell % sx), iy = static_cast<int>(cell / sx);
    const int64_t neighbours[4] = {ix > 0 ? cell - 1 : -1, ix + 1 < sx ? cell + 1 : -1,
                                   iy > 0 ? cell - sx : -1, iy + 1 < sy ? cell + sx : -1};
    for (int64_t n : neighbours) {
      if (n < 0) continue;
      const bool free_under_robot = under_robot(n);
      const int64_t j = free_under_robot ? n : map.NearestLevel(n, ground[i]);
      const float cnc = free_under_robot ? 1.f : map.Navigability(j);
      if (!(map.Explored(j) || free_under_robot) || !(cnc > safe)) continue;
      const float next = c + res / cnc;
      if (next < tree.cost[j]) {
        tree.cost[j] = next;
        tree.parent[j] = i;
        const float h = map.GroundHeight(j);
        ground[j] = std::isnan(h) ? ground[i] : h;
        open.push({next, j});
      }
    }
  }
  return tree;
}

uint64_t CandidateRank(int64_t cell, uint64_t seed) {
  uint64_t z = seed * 0x9E3779B97F4A7C15ull + static_cast<uint64_t>(cell) + 0x632BE59BD9B4E019ull;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

std::vector<int64_t> SampleCandidates(const InfoMap& map, const NbvParams& params,
                                      const common::Vector2& robot_m, uint64_t seed,
                                      const std::vector<common::Vector2>& visited) {
  const double revisit2 = params.revisit_radius_m * params.revisit_radius_m;
  const float safe = static_cast<float>(params.safe_cnc);
  auto is_safe = [&](int64_t i) { return map.Explored(i) && map.Navigability(i) > safe; };
  const double res = map.geometry().resolution_m;
  const int clearance_cells = static_cast<int>(std::ceil(params.candidate_clearance_m / res));
  std::vector<int64_t> safe_cells;
  for (int64_t i = 0; i < map.num_nodes(); ++i) {
    if (is_safe(i)) safe_cells.push_back(i);
  }
  const size_t limit = safe_cells.size() / static_cast<size_t>(params.candidate_fraction);
  std::vector<std::pair<uint64_t, int64_t>> ranked;
  ranked.reserve(safe_cells.size());
  for (int64_t i : safe_cells) ranked.emplace_back(CandidateRank(i, seed), i);
  std::sort(ranked.begin(), ranked.end());
  for (size_t k = 0; k < ranked.size(); ++k) safe_cells[k] = ranked[k].second;
  std::vector<int64_t> chosen;
  std::vector<common::Vector2> chosen_xy;
  const double spacing2 = params.candidate_spacing_m * params.candidate_spacing_m;
  for (int64_t i : safe_cells) {
    if (chosen.size() >= limit) break;
    if (!map.InWorkArea(i)) continue;
    const common::CellIndex cell = map.Cell(i);
    const common::Vector2 xy = map.geometry().CenterOf(cell);
    if ((xy - robot_m).squaredNorm() <= spacing2) continue;
    bool revisit = false;
    for (const auto& v : visited) {
      if ((xy - v).squaredNorm() < revisit2) {
        revisit = true;
        break;
      }
    }
    if (revisit) continue;
    bool far = true;
    for (const auto& other : chosen_xy) {
      if ((xy - other).squaredNorm() <= spacing2) {
        far = false;
        break;
      }
    }
    if (!far) continue;
    bool clear = true;
    for (int dy = -clearance_cells; dy <= clearance_cells && clear; ++dy) {
      for (int dx = -clearance_cells; dx <= clearance_cells; ++dx) {
        if ((dx * dx + dy * dy) * res * res >
            params.candidate_clearance_m * params.candidate_clearance_m + 1e-9) {
          continue;
        }
        const common::CellIndex n{cell.ix + dx, cell.iy + dy};
        if (!map.geometry().Contains(n) ||
            !is_safe(map.NearestLevel(map.Linear(n), map.GroundHeight(i)))) {
          clear = false;
          break;
        }
      }
    }
    if (!clear) continue;
    chosen.push_back(i);
    chosen_xy.push_back(xy);
  }
  return chosen;
}

ViewEvaluator::ViewEvaluator(const InfoMap& map, const NbvParams& params, const MissedViews* missed)
    : map_(map), params_(params), missed_(missed), stamp_(static_cast<size_t>(map.num_cells()), 0) {
  params_.Validate();
  if (missed_ && missed_->num_cells() != map.num_cells()) {
    throw std::invalid_argument("nbv: the missed-view counts do not match the map");
  }
}

ViewGains ViewEvaluator::Evaluate(int64_t cell, const std::vector<InterestZone>& zones,
                                  bool list_unexplored) {
  ViewGains gains;
  if (++epoch_ == 0) {
    std::fill(stamp_.begin(), stamp_.end(), 0);
    epoch_ = 1;
  }
  visible_.clear();
  const common::GridGeometry& g = map_.geometry();
  const double res = g.resolution_m;
  const double range = params_.gain_range_m;
  const common::CellIndex c = map_.Cell(cell);
  const int64_t own_cell = map_.NodeCell(cell);
  const common::Vector2 origin = g.CenterOf(c);
  const Eigen::Vector3f ground = map_.Centroid(cell);
  const float ground_z = std::isfinite(ground.z()) ? ground.z() : 0.f;
  const int64_t cells = map_.num_cells();
  const float level_gap = static_cast<float>(map_.params().level_gap_m);
  const Eigen::Vector3f scanner(static_cast<float>(origin.x()), static_cast<float>(origin.y()),
                                ground_z + static_cast<float>(params_.scanner_height_m));
  const float occlusion = static_cast<float>(params_.occlusion_cnc);

  // Visible cells: rays every ~0.7 cells of arc at the range's end, stepping half a cell.
  const int rays = std::max(16, static_cast<int>(std::ceil(2.0 * kPi * range / (0.7 * res))));
  const int steps = static_cast<int>(std::ceil(range / (0.5 * res)));
  const double inv_res = 1.0 / res;
  const double x0 = (origin.x() - g.origin.x_m) * inv_res;
  const double y0 = (origin.y() - g.origin.y_m) * inv_res;
  for (int r = 0; r < rays; ++r) {
    const double angle = 2.0 * kPi * r / rays;
    const double dx = 0.5 * std::cos(angle), dy = 0.5 * std::sin(angle);
    for (int s = 0; s <= steps; ++s) {
      const double fx = x0 + dx * s, fy = y0 + dy * s;
      if (fx < 0.0 || fy < 0.0) break;
      const int ix = static_cast<int>(fx), iy = static_cast<int>(fy);
      if (ix >= g.size_x || iy >= g.size_y) break;
      const int64_t i = ix + static_cast<int64_t>(iy) * g.size_x;
      if (stamp_[i] != epoch_) {
        stamp_[i] = epoch_;
        visible_.push_back(i);
      }
      // A cell blocks the view when it is an obstacle (C_nc below occlusion_cnc) or a wall
      // spans the scanner's height in it: a wall's foot cell also holds ground, so its C_nc
      // alone says little about what the wall hides. A wall is at least kMinWallHeightM of
      // steep points: a few steep normals on rough ground at the scanner's height are not one.
      // With two levels, an obstacle blocks only if it reaches within the level gap of the
      // scanner's height: the walls of a canyon below a scanner on its rim do not hide the
      // other rim, a deck above a scanner on the road does not hide the road.
      if (i == own_cell || !map_.CellExplored(i)) continue;
      bool blocks = map_.SteepLow(i) < scanner.z() && map_.SteepHigh(i) > scanner.z() &&
                    map_.SteepHigh(i) - map_.SteepLow(i) > kMinWallHeightM;
      for (int l = 0; l < map_.num_levels() && !blocks; ++l) {
        const int64_t node = i + l * cells;
        blocks = map_.Explored(node) && map_.Navigability(node) < occlusion &&
                 (level_gap <= 0.f || map_.Centroid(node).z() > scanner.z() - level_gap);
      }
      if (blocks) break;
    }
  }

  // Cells of the work area within range: the normaliser of A and Q.
  const int reach = static_cast<int>(std::ceil(range * inv_res));
  int64_t in_range = 0;
  const int64_t reach2 = static_cast<int64_t>(std::floor(range * range * inv_res * inv_res));
  for (int dy = std::max(-reach, -c.iy); dy <= std::min(reach, g.size_y - 1 - c.iy); ++dy) {
    const int64_t row = static_cast<int64_t>(c.iy + dy) * g.size_x;
    for (int dx = std::max(-reach, -c.ix); dx <= std::min(reach, g.size_x - 1 - c.ix); ++dx) {
      if (static_cast<int64_t>(dx) * dx + static_cast<int64_t>(dy) * dy > reach2) continue;
      in_range += map_.InWorkArea(row + c.ix + dx);
    }
  }
  if (in_range == 0) return gains;

  const double sin_pan = std::sin(params_.pan_step_rad);
  const double sin_tilt = std::sin(params_.tilt_step_rad);
  // The quality a scan from here would give a cell at range r met at `incidence` (the cosine
  // between the ray and the surface normal): eq. 4.8's area part, A_max over the area per point
  // across the ray (r^2 sin(res_p) sin(res_t)), with eq. 4.9's incidence (eq. 4.10).
  auto expected_quality = [&](double r, double incidence) {
    const double area = r * r * sin_pan * sin_tilt;
    const double area_score = area <= params_.a_max_m2 ? 1.0 : params_.a_max_m2 / area;
    return CombineQuality(area_score, incidence, params_.w_a_quality, params_.w_n_quality);
  };
  double unexplored = 0.0;
  double quality_sum = 0.0;
  for (int64_t i : visible_) {
    if (!map_.InWorkArea(i)) continue;
    const int64_t ddx = i % g.size_x - c.ix, ddy = i / g.size_x - c.iy;
    if (ddx * ddx + ddy * ddy > reach2) continue;
    if (!map_.CellExplored(i)) {
      if (list_unexplored) gains.unexplored.push_back(i);
      const double d_m = std::sqrt(static_cast<double>(ddx * ddx + ddy * ddy)) * res;
      const double weight = missed_ ? missed_->Weight(i, MissedViews::Sector(-ddx, -ddy), d_m,
                                                      params_.missed_view_step_m)
                                    : 1.0;
      unexplored += weight;
      // Q counts it too (its Q_a is 0, eq. 4.10 sums over every cell in range): the quality a
      // scan from here would give flat ground there, met at the scanner's height.
      const double h = params_.scanner_height_m;
      const double r = std::sqrt(d_m * d_m + h * h);
      if (r > 1e-6) quality_sum += weight * expected_quality(r, h / r);
      continue;
    }
    // The quality a scan from here would give this cell, from its distance and the incidence on
    // its mean normal, above its Q_a.
    const Eigen::Vector3f to = map_.CellCentroid(i) - scanner;
    const double r = to.norm();
    if (!(r > 1e-6)) continue;
    const Eigen::Vector3f n = map_.CellMeanNormal(i);
    const double incidence = n.squaredNorm() > 0.f ? std::abs(to.dot(n)) / r : 1.0;
    quality_sum += std::max(0.0, expected_quality(r, incidence) - map_.CellQuality(i));
  }
  gains.info_gain = std::min(1.0, unexplored / static_cast<double>(in_range));
  gains.quality_gain = std::min(1.0, quality_sum / in_range);

  double zone_total = 0.0, zone_sum = 0.0;
  for (size_t z = 0; z < zones.size(); ++z) {
    const InterestZone& zone = zones[z];
    const double area = zone.normal.norm();
    zone_total += area;
    const Eigen::Vector3f to = zone.center_m - scanner;
    const double d2 = to.head<2>().squaredNorm();
    if (d2 > range * range || !(to.norm() > 1e-6)) continue;
    const auto zone_cell = g.IndexOf({zone.center_m.x(), zone.center_m.y()});
    if (!zone_cell || stamp_[map_.Linear(*zone_cell)] != epoch_) continue;
    zone_sum += std::abs(to.normalized().dot(zone.normal));
    gains.zones_seen.push_back(z);
  }
  gains.zone_gain = zone_total > 0.0 ? std::min(1.0, zone_sum / zone_total) : 0.0;
  return gains;
}

MissedViews::MissedViews(int64_t num_cells)
    : nearest_m(static_cast<size_t>(num_cells) * kSectors, std::numeric_limits<float>::infinity()),
      count(static_cast<size_t>(num_cells) * kSectors, 0) {}

int MissedViews::Sector(int64_t dx, int64_t dy) {
  // Octants by sign and by which axis dominates, without a trigonometric call: 0 for bearings in
  // [0, 45) degrees, 1 for [45, 90), ..., 7 for [315, 360), but for due west (180), which falls
  // in 3.
  const int64_t ax = dx < 0 ? -dx : dx, ay = dy < 0 ? -dy : dy;
  if (dy >= 0) {
    if (dx > 0) return ax > ay ? 0 : 1;
    return ay > ax ? 2 : 3;
  }
  if (dx < 0) return ax > ay ? 4 : 5;
  return ay > ax ? 6 : 7;
}

double MissedViews::Weight(int64_t cell, int sector, double d_m, double step_m) const {
  const size_t k = static_cast<size_t>(cell) * kSectors + static_cast<size_t>(sector);
  const int misses = count[k];
  if (misses == 0 || d_m < nearest_m[k] - step_m) return 1.0;
  return std::ldexp(1.0, -misses);
}

int64_t RecordMissedView(const InfoMap& map, int64_t cell, const std::vector<int64_t>& unexplored,
                         MissedViews* missed) {
  if (missed->num_cells() != map.num_cells()) {
    throw std::invalid_argument("nbv: the missed views do not match the map");
  }
  const common::CellIndex c = map.Cell(cell);
  const double res = map.geometry().resolution_m;
  int64_t first = 0;
  for (int64_t i : unexplored) {
    const common::CellIndex u = map.Cell(i);
    const float d_m = static_cast<float>(std::hypot(u.ix - c.ix, u.iy - c.iy) * res);
    const size_t base = static_cast<size_t>(i) * MissedViews::kSectors;
    bool never = true;
    for (int s = 0; s < MissedViews::kSectors; ++s) never = never && missed->count[base + s] == 0;
    first += never;
    const size_t k = base + static_cast<size_t>(MissedViews::Sector(c.ix - u.ix, c.iy - u.iy));
    if (missed->count[k] < 255) ++missed->count[k];
    missed->nearest_m[k] = std::min(missed->nearest_m[k], d_m);
  }
  return first;
}

NbvPlanner::NbvPlanner(const NbvParams& params) : params_(params) { params_.Validate(); }

const char* OutcomeName(NbvDecision::Outcome outcome) {
  switch (outcome) {
    case NbvDecision::Outcome::kGoTo:
      return "go";
    case NbvDecision::Outcome::kStopUtility:
      return "stop";
    case NbvDecision::Outcome::kNoCandidate:
      return "no candidate";
  }
  return "?";
}

NbvDecision NbvPlanner::Decide(const InfoMap& map, const std::vector<InterestZone>& zones,
                               const common::Vector2& robot_m, const MissedViews* missed,
                               const std::vector<common::Vector2>& visited,
                               float robot_ground_z_m) {
  const auto robot_cell = map.geometry().IndexOf(robot_m);
  if (!robot_cell) throw std::invalid_argument("nbv: the robot is off the information map");
  NbvDecision decision;
  decision.stop_threshold = StopThreshold(params_.weights.w_c, params_.d_max_m);
  decision.global_quality = map.MeanQuality();
  decision.coverage = map.Coverage();
  const int64_t root = map.NearestLevel(map.Linear(*robot_cell), robot_ground_z_m);
  const NavigationTree tree = BuildNavigationTree(map, root, params_.safe_cnc,
                                                  params_.robot_free_radius_m, robot_ground_z_m);
  const std::vector<int64_t> cells = SampleCandidates(map, params_, robot_m, params_.seed, visited);
  ViewEvaluator evaluator(map, params_, missed);
  const bool greedy = params_.strategy == NbvStrategy::kGreedy;
  int reachable = 0;
  for (int64_t cell : cells) {
    Candidate cand;
    cand.cell = cell;
    cand.position_m = map.geometry().CenterOf(map.Cell(cell));
    cand.reachable = tree.Reachable(cell);
    if (cand.reachable) {
      ++reachable;
      cand.path_cost = tree.cost[cell];
      const ViewGains gains = evaluator.Evaluate(cell, zones);
      cand.info_gain = gains.info_gain;
      cand.quality_gain = gains.quality_gain;
      cand.zone_gain = gains.zone_gain;
      cand.utility = greedy ? cand.info_gain
                            : Utility(params_.weights, cand.info_gain, cand.quality_gain,
                                      cand.zone_gain, cand.path_cost);
      const bool better =
          !decision.best || cand.utility > decision.best->utility ||
          (cand.utility == decision.best->utility && cand.path_cost < decision.best->path_cost);
      if (better) decision.best = cand;
    }
    decision.candidates.push_back(cand);
  }
  char line[256];
  if (!decision.best) {
    decision.outcome = NbvDecision::Outcome::kNoCandidate;
    std::snprintf(line, sizeof(line), "no reachable candidate (%zu sampled, %d reachable)",
                  cells.size(), reachable);
    decision.reason = line;
    return decision;
  }
  {
    Candidate& chosen = *decision.best;
    chosen.ground_z_m = map.GroundHeight(chosen.cell);
    chosen.path_nodes = tree.PathTo(chosen.cell);
    for (int64_t c : chosen.path_nodes) {
      const common::Vector2 p = map.geometry().CenterOf(map.Cell(c));
      if (!chosen.path_m.empty()) chosen.path_length_m += (p - chosen.path_m.back()).norm();
      chosen.path_m.push_back(p);
    }
  }
  const Candidate& best = *decision.best;
  if (greedy) {
    if (best.info_gain < params_.greedy_min_gain) {
      decision.outcome = NbvDecision::Outcome::kStopUtility;
      std::snprintf(line, sizeof(line), "greedy: the most new information is %.3f < %.3f",
                    best.info_gain, params_.greedy_min_gain);
    } else {
      decision.outcome = NbvDecision::Outcome::kGoTo;
      std::snprintf(line, sizeof(line), "greedy: most new information A %.3f at %.1f m",
                    best.info_gain, best.path_cost);
    }
  } else if (best.utility < decision.stop_threshold &&
             decision.global_quality >= params_.min_global_quality) {
    decision.outcome = NbvDecision::Outcome::kStopUtility;
    std::snprintf(line, sizeof(line), "best utility %.4f < C_p %.4f with quality %.3f >= %.3f",
                  best.utility, decision.stop_threshold, decision.global_quality,
                  params_.min_global_quality);
  } else {
    decision.outcome = NbvDecision::Outcome::kGoTo;
    std::snprintf(line, sizeof(line), "u %.4f (A %.3f Q %.3f O %.3f C %.1f) of %d reachable",
                  best.utility, best.info_gain, best.quality_gain, best.zone_gain, best.path_cost,
                  reachable);
  }
  decision.reason = line;
  return decision;
}

}  // namespace cairn::explore
