#include "services/mapping/terrain_map.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "common/check.h"
#include "common/layers.h"
#include "common/yaml_reader.h"
#include "services/mapping/terrain_map_tile.h"

namespace cairn::mapping {
namespace {

using internal::FloorDiv;
using internal::GeometricLayers;
constexpr float kNaN = internal::kTerrainNaN;

// std::floor for a finite value well inside int64_t, without the libm call (no SSE4.1 here).
inline int64_t FloorToInt(double v) {
  const int64_t t = static_cast<int64_t>(v);
  return t - (v < static_cast<double>(t) ? 1 : 0);
}

}  // namespace

IntegrateStats& IntegrateStats::operator+=(const IntegrateStats& o) {
  points += o.points;
  used += o.used;
  ignored_lower += o.ignored_lower;
  nonfinite += o.nonfinite;
  out_of_range += o.out_of_range;
  self += o.self;
  overhang += o.overhang;
  return *this;
}

void TerrainMapParams::Validate() const {
  CAIRN_THROW_UNLESS(std::isfinite(resolution_m) && resolution_m > 0,
                     "resolution_m must be positive, got " << resolution_m);
  CAIRN_THROW_UNLESS(tile_size_cells >= 8 && tile_size_cells <= 250,
                     "tile_size_cells must be in [8, 250], got " << tile_size_cells);
  filter.Validate();
  CAIRN_THROW_UNLESS(
      min_range_m >= 0 && max_range_m > min_range_m,
      "need 0 <= min_range_m < max_range_m, got " << min_range_m << ", " << max_range_m);
  CAIRN_THROW_UNLESS(max_height_above_sensor_m > 0, "max_height_above_sensor_m must be positive");
  CAIRN_THROW_UNLESS(self_filter_radius_m >= 0, "self_filter_radius_m must be >= 0");
  CAIRN_THROW_UNLESS(std::isfinite(ray_bound_length_m), "ray_bound_length_m must be finite");
  CAIRN_THROW_UNLESS(std::isfinite(ray_bound_margin_m) && ray_bound_margin_m >= 0,
                     "ray_bound_margin_m must be >= 0, got " << ray_bound_margin_m);
  CAIRN_THROW_UNLESS(commit_epsilon_m >= 0 && commit_epsilon_m < 0.05,
                     "commit_epsilon_m must be in [0, 0.05), got " << commit_epsilon_m);
  CAIRN_THROW_UNLESS(
      visibility_tolerance_m >= 0 && max_visibility_conflict_m >= visibility_tolerance_m,
      "need 0 <= visibility_tolerance_m <= max_visibility_conflict_m");
  traversability.Validate();
  obstacles.Validate();
}

TerrainMap::TerrainMap(const TerrainMapParams& params) : params_(params) {
  params_.Validate();
  const double cos_max_spread = std::cos(params_.filter.max_spread_slope_rad);
  min_spread_nz2_ = cos_max_spread * cos_max_spread;
  // Blocks (the unit of recomputation) divide the tile evenly.
  block_cells_ = params_.tile_size_cells;
  for (int b = 25; b >= 5; --b) {
    if (params_.tile_size_cells % b == 0) {
      block_cells_ = b;
      break;
    }
  }
}

TerrainMap::~TerrainMap() = default;

std::vector<std::string> TerrainMap::BaseLayers() {
  return {layers::kElevation, layers::kElevationVariance, layers::kObservationCount,
          layers::kLastSeen, layers::kGroundBound};
}

std::vector<std::string> TerrainMap::DerivedLayers() const {
  std::vector<std::string> names = GeometricLayers();
  for (const auto& p : profiles_) {
    names.push_back(layers::CostLayer(p.name));
    names.push_back(layers::DirectedLayer(p.name));
  }
  return names;
}

const common::RobotProfile* TerrainMap::FindProfile(const std::string& name) const {
  for (const auto& p : profiles_) {
    if (p.name == name) return &p;
  }
  return nullptr;
}

void TerrainMap::AddProfile(const common::RobotProfile& profile) {
  profile.Validate();
  auto it = std::find_if(profiles_.begin(), profiles_.end(),
                         [&](const auto& p) { return p.name == profile.name; });
  if (it != profiles_.end()) {
    *it = profile;
  } else {
    profiles_.push_back(profile);
  }
  // Its cost layer over every tile.
  std::vector<CellRect> rects;
  for (const auto& [key, tile] : tiles_) {
    const int T = params_.tile_size_cells;
    rects.push_back({key.first * T, key.second * T, (key.first + 1) * T, (key.second + 1) * T});
  }
  std::sort(rects.begin(), rects.end(), [](const CellRect& a, const CellRect& b) {
    return std::make_pair(a.y0, a.x0) < std::make_pair(b.y0, b.x0);
  });
  RobotContext robot;
  robot.xy_m = last_robot_xy_;
  RecomputeCosts(rects, robot, {FindProfile(profile.name)});
}

bool TerrainMap::RemoveProfile(const std::string& name) {
  auto it = std::find_if(profiles_.begin(), profiles_.end(),
                         [&](const auto& p) { return p.name == name; });
  if (it == profiles_.end()) return false;
  profiles_.erase(it);
  for (auto& [key, tile] : tiles_) {
    tile->layers.RemoveLayer(layers::CostLayer(name));
    tile->layers.RemoveLayer(layers::DirectedLayer(name));
    ++tile->derived_version;
  }
  return true;
}

TerrainMap::Tile* TerrainMap::GetTile(int tx, int ty) {
  const Key key{tx, ty};
  if (last_tile_ != nullptr && key == last_key_) return last_tile_;
  auto it = tiles_.find(key);
  if (it == tiles_.end()) {
    auto tile = std::make_unique<Tile>();
    tile->layers = common::GridMap(TileGeometry(tx, ty));
    for (const auto& name : BaseLayers()) tile->layers.AddLayer(name);
    tile->layers.at(layers::kObservationCount).setZero();
    const size_t n = static_cast<size_t>(params_.tile_size_cells) * params_.tile_size_cells;
    tile->filter_height.assign(n, kNaN);
    tile->hit_dx.assign(n, 0.f);
    tile->hit_dy.assign(n, 0.f);
    tile->raw_bound.assign(n, kNaN);
    tile->conflict_bound.assign(n, kNaN);
    tile->scan.assign(n, 0u);
    tile->carried.assign(n, 0);
    tile->elevation = tile->layers.at(layers::kElevation).data();
    tile->variance = tile->layers.at(layers::kElevationVariance).data();
    tile->count = tile->layers.at(layers::kObservationCount).data();
    tile->last_seen = tile->layers.at(layers::kLastSeen).data();
    tile->bound = tile->layers.at(layers::kGroundBound).data();
    it = tiles_.emplace(key, std::move(tile)).first;
  }
  last_key_ = key;
  last_tile_ = it->second.get();
  return last_tile_;
}

const TerrainMap::Tile* TerrainMap::FindTile(int tx, int ty) const {
  auto it = tiles_.find({tx, ty});
  return it == tiles_.end() ? nullptr : it->second.get();
}

TerrainMap::Tile* TerrainMap::TileForCell(int64_t cx, int64_t cy, int* lx, int* ly) {
  const int T = params_.tile_size_cells;
  const int64_t tx = FloorDiv(cx, T), ty = FloorDiv(cy, T);
  *lx = static_cast<int>(cx - tx * T);
  *ly = static_cast<int>(cy - ty * T);
  return GetTile(static_cast<int>(tx), static_cast<int>(ty));
}

void TerrainMap::MarkDirty(int64_t cx, int64_t cy) {
  // Points come ring by ring: most fall in the block the previous one marked.
  const Key key{static_cast<int>(FloorDiv(cx, block_cells_)),
                static_cast<int>(FloorDiv(cy, block_cells_))};
  if (has_last_dirty_ && key == last_dirty_) return;
  dirty_blocks_.insert(key);
  last_dirty_ = key;
  has_last_dirty_ = true;
}

common::GridGeometry TerrainMap::TileGeometry(int tx, int ty) const {
  common::GridGeometry g;
  g.resolution_m = params_.resolution_m;
  g.size_x = g.size_y = params_.tile_size_cells;
  g.origin = {tx * params_.tile_size_cells * params_.resolution_m,
              ty * params_.tile_size_cells * params_.resolution_m, 0.0};
  return g;
}

IntegrateStats TerrainMap::Integrate(const common::LidarRevolution& revolution, double time_s) {
  IntegrateStats stats;
  for (const auto& slice : revolution.slices) {
    stats += Integrate(slice.points, slice.sensor_pose, revolution.revolution, time_s);
  }
  return stats;
}

// One scan's constants for Integrate: the sensor's pose, the time stamp and the scan's tag.
struct TerrainMap::ScanFrame {
  Eigen::Matrix3d rotation;
  common::Vector3 origin;
  float time_f;
  uint32_t scan_tag;
};

// PlacePoint and FusePoint run once per point: inlined into Integrate's loop, as when they were
// its body (a call each costs 2 % of the mapping pipeline's instructions).
[[gnu::always_inline]] inline bool TerrainMap::PlacePoint(const ScanFrame& scan,
                                                          const common::LidarPoint& p,
                                                          common::Vector3* pw, double* range,
                                                          IntegrateStats* stats) const {
  const common::Vector3 ps(p.x_m, p.y_m, p.z_m);
  if (!ps.allFinite()) {
    ++stats->nonfinite;
    return false;
  }
  *range = ps.norm();
  if (*range < std::max(params_.min_range_m, 1e-6) || *range > params_.max_range_m) {
    ++stats->out_of_range;
    return false;
  }
  *pw = scan.origin + scan.rotation * ps;
  if (params_.self_filter_radius_m > 0 &&
      (pw->head<2>() - scan.origin.head<2>()).squaredNorm() <
          params_.self_filter_radius_m * params_.self_filter_radius_m) {
    ++stats->self;
    return false;
  }
  if (pw->z() > scan.origin.z() + params_.max_height_above_sensor_m) {
    ++stats->overhang;
    return false;
  }
  return true;
}

[[gnu::always_inline]] inline void TerrainMap::FusePoint(const ScanFrame& scan,
                                                         const common::Vector3& pw, double range,
                                                         int64_t cx, int64_t cy,
                                                         SpreadCache* spread,
                                                         IntegrateStats* stats) {
  const double res = params_.resolution_m;
  int lx, ly;
  Tile* tile = TileForCell(cx, cy, &lx, &ly);
  const size_t i = lx + static_cast<size_t>(ly) * params_.tile_size_cells;
  double var_z = PointHeightVariance(range, (pw.z() - scan.origin.z()) / range, params_.filter);
  if (tile->slope != nullptr) {
    const float slope = tile->slope[i];
    if (!(slope == spread->slope)) {
      spread->slope = slope;
      spread->variance = SlopeSpreadVariance(slope, res, params_.filter);
    }
    var_z += spread->variance;
  }
  const bool same_scan = tile->scan[i] == scan.scan_tag;
  float h = tile->filter_height[i], var = tile->variance[i];
  const float var_before = var;
  const FuseOutcome outcome = FuseHeight(&h, &var, pw.z(), var_z, same_scan, params_.filter);
  if (outcome == FuseOutcome::kIgnoredLower) {
    ++stats->ignored_lower;
    return;
  }
  ++stats->used;
  // The point's place in the cell, blended into the cell's like its height.
  const float px = static_cast<float>(pw.x() - (cx + 0.5) * res);
  const float py = static_cast<float>(pw.y() - (cy + 0.5) * res);
  float& mx = tile->hit_dx[i];
  float& my = tile->hit_dy[i];
  if (outcome == FuseOutcome::kInitialized || outcome == FuseOutcome::kRaised) {
    const float a = outcome == FuseOutcome::kRaised
                        ? static_cast<float>(params_.filter.increase_height_alpha)
                        : 0.f;
    mx = a * mx + (1.f - a) * px;
    my = a * my + (1.f - a) * py;
  } else if (outcome == FuseOutcome::kFused) {
    const double w = var_before / (var_before + var_z);  // the Kalman gain
    mx += static_cast<float>(w * (px - mx));
    my += static_cast<float>(w * (py - my));
  }
  tile->filter_height[i] = h;
  tile->variance[i] = var;
  tile->scan[i] = scan.scan_tag;
  tile->count[i] += 1.f;
  tile->last_seen[i] = scan.time_f;
  ++tile->base_version;
  CommitHeight(tile, i, cx, cy);
}

IntegrateStats TerrainMap::Integrate(const std::vector<common::LidarPoint>& points,
                                     const common::Pose3& sensor_pose, int64_t scan_id,
                                     double time_s) {
  IntegrateStats stats;
  stats.points = static_cast<int64_t>(points.size());
  if (!sensor_pose.position_m.allFinite() || !sensor_pose.orientation.coeffs().allFinite()) {
    stats.nonfinite = stats.points;
    return stats;
  }
  // Scans are told apart by the low 32 bits of their id (never 0, which marks "no scan yet").
  const ScanFrame scan{
      sensor_pose.orientation.normalized().toRotationMatrix(), sensor_pose.position_m,
      static_cast<float>(time_s),
      static_cast<uint32_t>(scan_id) | (static_cast<uint32_t>(scan_id) == 0 ? 0x80000000u : 0u)};
  const double res = params_.resolution_m;
  std::array<int64_t, 256> last_end;
  last_end.fill(std::numeric_limits<int64_t>::min());
  // Runs of points fall in one cell: the spread variance of the last slope is kept (a tangent
  // per point was a tenth of the fusion's time).
  SpreadCache spread{kNaN, 0.0};
  interpolates_tile_ = nullptr;
  limited_tile_ = nullptr;
  for (const auto& p : points) {
    common::Vector3 pw;
    double range;
    if (!PlacePoint(scan, p, &pw, &range, &stats)) continue;
    const int64_t cx = FloorToInt(pw.x() / res);
    const int64_t cy = FloorToInt(pw.y() / res);
    FusePoint(scan, pw, range, cx, cy, &spread, &stats);
    if (params_.ray_bound_length_m > 0 && pw.z() < scan.origin.z() &&
        range <= params_.ray_bound_max_range_m) {
      // Neighbouring rays of one ring end in the same cell many times over (a dozen per cell
      // at 5 m): the first of a run records the bound for all of them.
      const auto end_key = static_cast<int64_t>((static_cast<uint64_t>(cx) << 32) ^
                                                (static_cast<uint64_t>(cy) & 0xffffffffu));
      const size_t ring = static_cast<size_t>(p.ring) & 0xff;
      if (last_end[ring] != end_key) {
        last_end[ring] = end_key;
        if (range > params_.ray_bound_margin_m) {
          RecordBound(
              scan.origin,
              scan.origin + (pw - scan.origin) * ((range - params_.ray_bound_margin_m) / range), cx,
              cy);
        }
      }
    }
  }
  return stats;
}

bool TerrainMap::NormalInterpolates(const Tile& tile, size_t i, int64_t cx, int64_t cy) const {
  const int n = params_.tile_size_cells;
  const int lx = static_cast<int>(i % n), ly = static_cast<int>(i / n);
  const bool inner = lx >= 1 && ly >= 1 && lx <= n - 2 && ly <= n - 2;
  auto known = [&](int dx, int dy) {
    if (inner) return !std::isnan(tile.elevation[i + dx + static_cast<int64_t>(dy) * n]);
    const int64_t x = cx + dx, y = cy + dy;
    const Tile* t = FindTile(static_cast<int>(FloorDiv(x, n)), static_cast<int>(FloorDiv(y, n)));
    if (t == nullptr) return false;
    const int64_t j = (x - FloorDiv(x, n) * n) + (y - FloorDiv(y, n) * n) * n;
    return !std::isnan(t->elevation[j]);
  };
  // A known neighbour on both sides along each axis, and at most two unknown in all.
  bool west = false, east = false, south = false, north = false;
  int unknown = 0;
  for (int dy = -1; dy <= 1; ++dy) {
    for (int dx = -1; dx <= 1; ++dx) {
      if (dx == 0 && dy == 0) continue;
      if (!known(dx, dy)) {
        ++unknown;
        continue;
      }
      west |= dx < 0;
      east |= dx > 0;
      south |= dy < 0;
      north |= dy > 0;
    }
  }
  return west && east && south && north && unknown <= 2;
}

bool TerrainMap::CachedNormalInterpolates(const Tile& tile, size_t i, int64_t cx, int64_t cy) {
  if (interpolates_tile_ != &tile || interpolates_i_ != i || interpolates_epoch_ != known_epoch_) {
    interpolates_tile_ = &tile;
    interpolates_i_ = i;
    interpolates_epoch_ = known_epoch_;
    interpolates_ = NormalInterpolates(tile, i, cx, cy);
  }
  return interpolates_;
}

namespace {

// Minmod of the fitted gradient and twice each one-sided difference (the MC limiter of MUSCL
// schemes): all three agree on an even ramp, and the fit stands; at a step one side is flat and
// the result is zero.
// Rises to either side of a cell (over two cells) that differ by less than this are one surface
// with noise, not a step's break: the fitted gradient stands. Under the 3 cm step-up of the
// Pioneer 3-AT and the rover, over the range noise (1.8 cm).
constexpr double kCarryBreak_m = 0.03;

// An unknown side (NaN) does not limit: the cell interpolates through its diagonals.
inline double McLimited(double fit, double back, double ahead) {
  double m = std::fabs(fit);
  for (const double d : {back, ahead}) {
    if (std::isnan(d)) continue;
    if (!(fit * d > 0.0)) return 0.0;
    m = std::min(m, 2.0 * std::fabs(d));
  }
  return fit > 0.0 ? m : -m;
}

}  // namespace

float TerrainMap::CommittedAt(const Tile& tile, size_t i, int64_t cx, int64_t cy, int dx,
                              int dy) const {
  const int n = params_.tile_size_cells;
  const int lx = static_cast<int>(i % n) + dx, ly = static_cast<int>(i / n) + dy;
  if (lx >= 0 && ly >= 0 && lx < n && ly < n) {
    return tile.elevation[lx + static_cast<int64_t>(ly) * n];
  }
  const int64_t x = cx + dx, y = cy + dy;
  const Tile* t = FindTile(static_cast<int>(FloorDiv(x, n)), static_cast<int>(FloorDiv(y, n)));
  if (t == nullptr) return kNaN;
  return t->elevation[(x - FloorDiv(x, n) * n) + (y - FloorDiv(y, n) * n) * n];
}

void TerrainMap::LimitGradient(const Tile& tile, size_t i, int64_t cx, int64_t cy, double* gx,
                               double* gy) const {
  const double h = tile.elevation[i];
  const double res = params_.resolution_m;
  // The gradient to the side over two cells (one where the second is unknown): a lone cell
  // that a ring line barely reached holds a point or two, whose noise alone would cut the carry.
  auto side = [&](int dx, int dy) {
    const float far = CommittedAt(tile, i, cx, cy, 2 * dx, 2 * dy);
    if (!std::isnan(far)) return (far - h) / (2.0 * res);
    return (CommittedAt(tile, i, cx, cy, dx, dy) - h) / res;
  };
  // Where both sides are known the limiter acts only at a break in the rise: on natural ground
  // seen from afar a few noisy cells would otherwise cut the carry and crease a hillside.
  auto limit = [&](double fit, double back, double ahead) {
    if (!std::isnan(back) && !std::isnan(ahead) &&
        std::fabs(ahead - back) * 2.0 * res < kCarryBreak_m) {
      return fit;
    }
    return McLimited(fit, back, ahead);
  };
  *gx = limit(*gx, -side(-1, 0), side(1, 0));
  *gy = limit(*gy, -side(0, -1), side(0, 1));
}

// The published height follows the filter in steps larger than commit_epsilon, except where a
// ray passed slightly beneath it: such a cell mixes a surface with a gap next to it (range
// noise spills the rim of a trench into its first cell, a wall's foot into the wall cell) and
// is published unknown, so the gap keeps its true width. Larger conflicts are thin structures
// the ray passed beside; they stay.
void TerrainMap::CommitHeight(Tile* tile, size_t i, int64_t cx, int64_t cy, bool only_to_carry) {
  float h = tile->filter_height[i];
  // The filter's height belongs where its points lay; on a plane of moderate slope (the last
  // derived for the cell) it is carried to the cell's centre, so an even ramp sampled along a
  // few ring lines reads even (cell to cell differences of one cell's rise, not up to twice).
  // Only a normal that interpolates is trusted: at the rim of unseen ground (the blind ring
  // around a standing robot) the fit extrapolates from one side, is steep from noise alone and
  // leans further with the cell's own height, so its carry would grow into a false step.
  // `settled`: the commit had the last word a trusted normal gives (a carry, or none needed).
  // `only_to_carry` (RecommitUnsettled): nothing changes unless the height is carried now.
  bool settled = std::isnan(h);
  bool carried_now = false;
  if (tile->normal_x != nullptr && tile->normal_y != nullptr && !std::isnan(h)) {
    const double nx = tile->normal_x[i], ny = tile->normal_y[i];
    const double nz2 = 1.0 - nx * nx - ny * ny;
    // A slope in (0, max_spread_slope_rad], as SlopeSpreadVariance > 0 asks, without an acos.
    const bool carries =
        std::isfinite(nx) && std::isfinite(ny) && nz2 < 1.0 && nz2 >= min_spread_nz2_;
    settled = std::isfinite(nx) && std::isfinite(ny) && !carries;
    if (carries && CachedNormalInterpolates(*tile, i, cx, cy)) {
      settled = true;
      carried_now = true;
      // Runs of points fall in one cell: its limited gradient is kept for the run (the
      // neighbours' heights barely move meanwhile).
      if (limited_tile_ != tile || limited_i_ != i) {
        const double nz = std::sqrt(nz2);
        limited_tile_ = tile;
        limited_i_ = i;
        limited_gx_ = -nx / nz;
        limited_gy_ = -ny / nz;
        LimitGradient(*tile, i, cx, cy, &limited_gx_, &limited_gy_);
      }
      h = static_cast<float>(h - (limited_gx_ * tile->hit_dx[i] + limited_gy_ * tile->hit_dy[i]));
    }
  }
  tile->carried[i] = settled ? 1 : 0;
  // A recommit that carries nothing would only re-read the visibility bounds recorded since the
  // cell's points came, which a commit applies to new points only.
  if (only_to_carry && !carried_now) return;
  const float bound = tile->conflict_bound[i];
  if (!std::isnan(h) && bound < h - params_.visibility_tolerance_m &&
      h - bound < params_.max_visibility_conflict_m) {
    h = kNaN;
  }
  float& committed = tile->elevation[i];
  if (std::isnan(h) != std::isnan(committed) ||
      (!std::isnan(h) && std::fabs(double(h) - committed) > params_.commit_epsilon_m)) {
    if (std::isnan(h) != std::isnan(committed)) ++known_epoch_;
    committed = h;
    ++tile->base_version;
    MarkDirty(cx, cy);
  }
}

// The last stretch of a downward ray: every cell it crosses before the one of its return gets
// the ray's height where it leaves that cell as an upper bound of the ground there (under the
// 2.5-D assumption that a cell's surface is one height).
void TerrainMap::RecordBound(const common::Vector3& from, const common::Vector3& to,
                             int64_t return_x, int64_t return_y) {
  const common::Vector3 d = to - from;
  const double length = d.norm();
  if (!(length > 0)) return;
  const double start_t = std::max(0.0, 1.0 - params_.ray_bound_length_m / length);
  const common::Vector3 a = from + start_t * d;
  const double res = params_.resolution_m;
  const double x0 = a.x() / res, y0 = a.y() / res, x1 = to.x() / res, y1 = to.y() / res;
  const double dz = to.z() - a.z();
  const double eps = params_.commit_epsilon_m;
  // Exact traversal of the cells from the start to the return (Amanatides & Woo, as
  // TraverseCells), keeping the parameter at which the segment leaves each cell.
  int64_t ix = static_cast<int64_t>(std::floor(x0)), iy = static_cast<int64_t>(std::floor(y0));
  const int64_t end_x = static_cast<int64_t>(std::floor(x1));
  const int64_t end_y = static_cast<int64_t>(std::floor(y1));
  const double dx = x1 - x0, dy = y1 - y0;
  const int step_x = end_x > ix ? 1 : (end_x < ix ? -1 : 0);
  const int step_y = end_y > iy ? 1 : (end_y < iy ? -1 : 0);
  constexpr double kInf = std::numeric_limits<double>::infinity();
  double t_max_x = kInf, t_delta_x = kInf, t_max_y = kInf, t_delta_y = kInf;
  if (step_x != 0) {
    t_delta_x = 1.0 / std::fabs(dx);
    t_max_x = (step_x > 0 ? (ix + 1 - x0) : (x0 - ix)) * t_delta_x;
  }
  if (step_y != 0) {
    t_delta_y = 1.0 / std::fabs(dy);
    t_max_y = (step_y > 0 ? (iy + 1 - y0) : (y0 - iy)) * t_delta_y;
  }
  int64_t remaining_x = std::abs(end_x - ix), remaining_y = std::abs(end_y - iy);
  // `cells_left`: cells the ray crosses after this one before its return's.
  auto record = [&](int64_t cx, int64_t cy, float z_exit, int64_t cells_left) {
    int lx, ly;
    Tile* tile = TileForCell(cx, cy, &lx, &ly);
    const size_t i = lx + static_cast<size_t>(ly) * params_.tile_size_cells;
    float& raw = tile->raw_bound[i];
    if (!(raw <= z_exit)) {
      raw = z_exit;
      float& committed = tile->bound[i];
      if (std::isnan(committed) || raw < committed - eps) {
        committed = raw;
        ++tile->base_version;
        MarkDirty(cx, cy);
      }
    }
    // Only a ray that goes on for more than the next cell can say a surface is not there: one
    // that ends right after this cell may have hit a face standing in it.
    float& conflict = tile->conflict_bound[i];
    if (cells_left >= 1 && !(conflict <= z_exit)) {
      conflict = z_exit;
      if (!std::isnan(tile->filter_height[i])) CommitHeight(tile, i, cx, cy);
    }
  };
  // The segment ends short of the return (ray_bound_margin_m): its last cell is the return's
  // own (never visited: the surface stands in it) or the one before, left at the segment's end.
  const bool end_is_return = end_x == return_x && end_y == return_y;
  while (remaining_x > 0 || remaining_y > 0) {
    // This cell is left at the next border crossing.
    const bool step_in_x = remaining_y == 0 || (remaining_x > 0 && t_max_x <= t_max_y);
    const double t_exit = std::min(1.0, step_in_x ? t_max_x : t_max_y);
    const float z_exit = static_cast<float>(a.z() + std::max(0.0, t_exit) * dz);
    record(ix, iy, z_exit, remaining_x + remaining_y - 1 + (end_is_return ? 0 : 1));
    if (step_in_x) {
      ix += step_x;
      t_max_x += t_delta_x;
      --remaining_x;
    } else {
      iy += step_y;
      t_max_y += t_delta_y;
      --remaining_y;
    }
  }
  if (!end_is_return) record(end_x, end_y, static_cast<float>(to.z()), 0);
}

common::GridGeometry TerrainMap::Bounds() const {
  common::GridGeometry g = AllocatedBounds();
  if (tiles_.empty()) return g;
  const double tile_m = params_.tile_size_cells * params_.resolution_m;
  g.size_x += 2 * params_.tile_size_cells;
  g.size_y += 2 * params_.tile_size_cells;
  g.origin.x_m -= tile_m;
  g.origin.y_m -= tile_m;
  return g;
}

common::GridGeometry TerrainMap::AllocatedBounds() const {
  common::GridGeometry g;
  g.resolution_m = params_.resolution_m;
  if (tiles_.empty()) return g;
  int tx0 = std::numeric_limits<int>::max(), ty0 = tx0;
  int tx1 = std::numeric_limits<int>::min(), ty1 = tx1;
  for (const auto& [key, tile] : tiles_) {
    tx0 = std::min(tx0, key.first);
    ty0 = std::min(ty0, key.second);
    tx1 = std::max(tx1, key.first);
    ty1 = std::max(ty1, key.second);
  }
  const int T = params_.tile_size_cells;
  g.size_x = (tx1 - tx0 + 1) * T;
  g.size_y = (ty1 - ty0 + 1) * T;
  g.origin = {tx0 * T * params_.resolution_m, ty0 * T * params_.resolution_m, 0.0};
  return g;
}

std::vector<std::pair<int, int>> TerrainMap::Tiles() const {
  std::vector<std::pair<int, int>> keys;
  for (const auto& [key, tile] : tiles_) keys.push_back(key);
  std::sort(keys.begin(), keys.end(), [](const Key& a, const Key& b) {
    return std::make_pair(a.second, a.first) < std::make_pair(b.second, b.first);
  });
  return keys;
}

const common::GridMap* TerrainMap::TileLayers(int tx, int ty) const {
  const Tile* t = FindTile(tx, ty);
  return t ? &t->layers : nullptr;
}

int64_t TerrainMap::TileBaseVersion(int tx, int ty) const {
  const Tile* t = FindTile(tx, ty);
  return t ? t->base_version : -1;
}

int64_t TerrainMap::TileDerivedVersion(int tx, int ty) const {
  const Tile* t = FindTile(tx, ty);
  return t ? t->derived_version : -1;
}

void TerrainMap::Clear() {
  tiles_.clear();
  last_tile_ = nullptr;
  dirty_blocks_.clear();
  has_last_dirty_ = false;
  last_region_.clear();
}

int64_t TerrainMap::known_cells() const {
  int64_t n = 0;
  for (const auto& [key, tile] : tiles_) {
    const common::Layer& h = tile->layers.at(layers::kElevation);
    for (int64_t i = 0; i < h.size(); ++i) n += !std::isnan(h.data()[i]);
  }
  return n;
}

size_t TerrainMap::memory_bytes() const {
  size_t bytes = 0;
  for (const auto& [key, tile] : tiles_) {
    bytes += tile->layers.layer_names().size() * sizeof(float) * tile->filter_height.size();
    bytes += tile->filter_height.size() * (5 * sizeof(float) + sizeof(uint32_t) + 1);
  }
  return bytes;
}

TerrainMapParams LoadTerrainMapParams(common::YamlMap& m) {
  TerrainMapParams p;
  m.Get("resolution_m", &p.resolution_m);
  m.Get("tile_size_cells", &p.tile_size_cells);
  m.Get("min_range_m", &p.min_range_m);
  m.Get("max_range_m", &p.max_range_m);
  m.Get("self_filter_radius_m", &p.self_filter_radius_m);
  m.Get("max_height_above_sensor_m", &p.max_height_above_sensor_m);
  m.Get("ray_bound_length_m", &p.ray_bound_length_m);
  m.Get("ray_bound_max_range_m", &p.ray_bound_max_range_m);
  m.Get("ray_bound_margin_m", &p.ray_bound_margin_m);
  m.Get("commit_epsilon_m", &p.commit_epsilon_m);
  m.Get("visibility_tolerance_m", &p.visibility_tolerance_m);
  m.Get("max_visibility_conflict_m", &p.max_visibility_conflict_m);
  if (m.Has("filter")) {
    common::YamlMap filter = m.Child("filter");
    p.filter = LoadElevationFilterParams(filter);
  }
  if (m.Has("traversability")) {
    common::YamlMap traversability = m.Child("traversability");
    p.traversability = LoadTraversabilityParams(traversability);
  }
  if (m.Has("obstacles")) {
    common::YamlMap obstacles = m.Child("obstacles");
    p.obstacles = LoadObstacleParams(obstacles);
  }
  m.Finish();
  return p;
}

}  // namespace cairn::mapping
