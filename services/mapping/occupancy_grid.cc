#include "services/mapping/occupancy_grid.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "common/check.h"
#include "common/layers.h"
#include "common/yaml_reader.h"

namespace cairn::mapping {

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// Per-cell state of a scan in the one-update-per-scan mode.
constexpr uint8_t kUntouched = 0;
constexpr uint8_t kHitPending = 1;  // an obstacle return of this scan ends here
constexpr uint8_t kDone = 2;        // updated in this scan

// Above this many cells the scan's bounding box is not worth a state buffer (rays from far
// apart origins); such a scan is applied beam by beam.
constexpr int64_t kMaxScanBoxCells = int64_t{1} << 26;

}  // namespace

float LogOddsFromProbability(double probability) {
  return static_cast<float>(std::log(probability / (1.0 - probability)));
}

double ProbabilityFromLogOdds(float logodds) { return 1.0 / (1.0 + std::exp(-double{logodds})); }

float OccupancyPercent(float logodds) {
  if (std::isnan(logodds)) return kNaN;
  return static_cast<float>(100.0 * ProbabilityFromLogOdds(logodds));
}

// ---------------------------------------------------------------------------------------------
// Params

OccupancyParams OccupancyParams::Seed003() {
  OccupancyParams p;
  p.hit_logodds = 2.0f;
  p.miss_logodds = -0.7f;
  p.clamp_min_logodds = -10.0f;
  p.clamp_max_logodds = 10.0f;
  p.protect_occupied_logodds = 2.0f;
  p.one_update_per_scan = false;
  p.clamp_after_scan = true;
  p.min_range_m = 0.1;
  p.max_range_m = 4.95;
  p.no_return_range_m = 4.9;
  p.beam_step = 2;
  return p;
}

common::GridGeometry OccupancyParams::geometry() const {
  common::GridGeometry g;
  g.resolution_m = resolution_m;
  g.size_x = size_x_cells;
  g.size_y = size_y_cells;
  g.origin = common::Pose2{origin_x_m, origin_y_m, 0.0};
  return g;
}

void OccupancyParams::Validate() const {
  CAIRN_THROW_UNLESS(std::isfinite(hit_logodds) && hit_logodds > 0.f,
                     "occupancy hit_logodds must be positive, got " << hit_logodds);
  CAIRN_THROW_UNLESS(std::isfinite(miss_logodds) && miss_logodds < 0.f,
                     "occupancy miss_logodds must be negative, got " << miss_logodds);
  CAIRN_THROW_UNLESS(std::isfinite(clamp_min_logodds) && std::isfinite(clamp_max_logodds) &&
                         clamp_min_logodds < 0.f && clamp_max_logodds > 0.f,
                     "occupancy clamps must satisfy clamp_min_logodds < 0 < clamp_max_logodds");
  CAIRN_THROW_UNLESS(!std::isnan(protect_occupied_logodds),
                     "occupancy protect_occupied_logodds must not be NaN");
  CAIRN_THROW_UNLESS(std::isfinite(min_range_m) && min_range_m >= 0.0,
                     "occupancy min_range_m must be >= 0, got " << min_range_m);
  CAIRN_THROW_UNLESS(
      std::isfinite(max_range_m) && max_range_m > min_range_m,
      "occupancy max_range_m must be finite and above min_range_m, got " << max_range_m);
  CAIRN_THROW_UNLESS(
      std::isfinite(no_return_range_m) && no_return_range_m >= 0.0,
      "occupancy no_return_range_m must be finite and >= 0, got " << no_return_range_m);
  CAIRN_THROW_UNLESS(beam_step >= 1, "occupancy beam_step must be >= 1, got " << beam_step);
  CAIRN_THROW_UNLESS(max_scan_tilt_rad > 0.0, "occupancy max_scan_tilt_deg must be positive, got "
                                                  << max_scan_tilt_rad * 180.0 / M_PI);
  CAIRN_THROW_UNLESS(std::isfinite(resolution_m) && resolution_m > 0.0,
                     "occupancy resolution_m must be positive, got " << resolution_m);
  CAIRN_THROW_UNLESS(
      size_x_cells > 0 && size_y_cells > 0,
      "occupancy grid size must be positive, got " << size_x_cells << " x " << size_y_cells);
  CAIRN_THROW_UNLESS(std::isfinite(origin_x_m) && std::isfinite(origin_y_m),
                     "occupancy origin must be finite");
  CAIRN_THROW_UNLESS(
      tile_size_cells >= 8 && tile_size_cells <= 4096 &&
          (tile_size_cells & (tile_size_cells - 1)) == 0,
      "occupancy tile_size_cells must be a power of two in [8, 4096], got " << tile_size_cells);
}

// ---------------------------------------------------------------------------------------------
// Storage

OccupancyGrid::OccupancyGrid(const OccupancyParams& params) : params_(params) {
  params_.Validate();
  geometry_ = params_.geometry();
  tile_shift_ = 0;
  while ((1 << tile_shift_) < params_.tile_size_cells) ++tile_shift_;
  tile_mask_ = params_.tile_size_cells - 1;
  tiles_x_ = (geometry_.size_x + tile_mask_) >> tile_shift_;
  tiles_y_ = (geometry_.size_y + tile_mask_) >> tile_shift_;
  tiles_.resize(static_cast<size_t>(tiles_x_) * tiles_y_);
}

OccupancyGrid::OccupancyGrid(const OccupancyGrid& other)
    : params_(other.params_),
      geometry_(other.geometry_),
      tile_shift_(other.tile_shift_),
      tile_mask_(other.tile_mask_),
      tiles_x_(other.tiles_x_),
      tiles_y_(other.tiles_y_),
      tiles_(other.tiles_.size()),
      num_tiles_(other.num_tiles_),
      version_(other.version_) {
  const size_t tile_cells = size_t{1} << (2 * tile_shift_);
  for (size_t i = 0; i < tiles_.size(); ++i) {
    if (!other.tiles_[i]) continue;
    tiles_[i].reset(new float[tile_cells]);
    std::memcpy(tiles_[i].get(), other.tiles_[i].get(), tile_cells * sizeof(float));
  }
}

OccupancyGrid& OccupancyGrid::operator=(const OccupancyGrid& other) {
  if (this != &other) *this = OccupancyGrid(other);
  return *this;
}

OccupancyGrid::~OccupancyGrid() = default;

float* OccupancyGrid::MutableCell(int ix, int iy) {
  const size_t tile = static_cast<size_t>(iy >> tile_shift_) * tiles_x_ + (ix >> tile_shift_);
  std::unique_ptr<float[]>& t = tiles_[tile];
  if (!t) {
    const size_t tile_cells = size_t{1} << (2 * tile_shift_);
    t.reset(new float[tile_cells]);
    std::fill(t.get(), t.get() + tile_cells, kNaN);
    ++num_tiles_;
  }
  return t.get() + (((iy & tile_mask_) << tile_shift_) | (ix & tile_mask_));
}

const float* OccupancyGrid::FindCell(int ix, int iy) const {
  if (!Inside(ix, iy)) return nullptr;
  const size_t tile = static_cast<size_t>(iy >> tile_shift_) * tiles_x_ + (ix >> tile_shift_);
  const float* t = tiles_[tile].get();
  if (!t) return nullptr;
  return t + (((iy & tile_mask_) << tile_shift_) | (ix & tile_mask_));
}

float OccupancyGrid::LogOdds(const common::CellIndex& cell) const {
  const float* c = FindCell(cell.ix, cell.iy);
  return c ? *c : kNaN;
}

float OccupancyGrid::LogOddsAt(const common::Vector2& world_m) const {
  const auto cell = CellAt(world_m);
  return cell ? LogOdds(*cell) : kNaN;
}

void OccupancyGrid::SetLogOdds(const common::CellIndex& cell, float logodds) {
  CAIRN_THROW_UNLESS(Inside(cell.ix, cell.iy),
                     "cell (" << cell.ix << ", " << cell.iy << ") is outside the occupancy grid");
  *MutableCell(cell.ix, cell.iy) = logodds;
  ++version_;
}

size_t OccupancyGrid::memory_bytes() const {
  return num_tiles_ * (size_t{1} << (2 * tile_shift_)) * sizeof(float) +
         tiles_.size() * sizeof(tiles_[0]);
}

void OccupancyGrid::Clear() {
  for (auto& t : tiles_) t.reset();
  num_tiles_ = 0;
  ++version_;
}

// ---------------------------------------------------------------------------------------------
// Insertion

void OccupancyGrid::AddBeam(const common::Vector2& origin_m, const common::Vector2& direction,
                            double range_m, bool hit, std::vector<Segment>* segments,
                            OccupancyInsertStats* stats) const {
  if (!origin_m.allFinite() || !direction.allFinite() || std::isnan(range_m) || range_m < 0.0) {
    ++stats->beams_invalid;
    return;
  }
  // Range rules act on the measured range; the planar ray follows `direction` that far.
  // Readings travel as float32, so the thresholds are compared at float precision: a 4.95 m
  // reading (4.9499998f) reaches a 4.95 m maximum.
  double keep = range_m;
  const float range_f = static_cast<float>(range_m);
  if (hit) {
    if (range_f < static_cast<float>(params_.min_range_m)) {
      ++stats->beams_skipped;
      return;
    }
    if (range_f >= static_cast<float>(params_.max_range_m)) {
      hit = false;
      keep = std::min(range_m, params_.no_return_range_m);
    }
  } else {
    keep = std::min(range_m, params_.no_return_range_m);
  }
  const common::Vector2 a = geometry_.ContinuousIndexOf(origin_m);
  const common::Vector2 b = geometry_.ContinuousIndexOf(origin_m + direction * keep);
  segments->push_back({a.x(), a.y(), b.x(), b.y(), hit});
  ++stats->beams_used;
}

OccupancyInsertStats OccupancyGrid::InsertScan(const common::LaserScan& scan) {
  const common::Pose3& pose = scan.sensor_pose;
  CAIRN_THROW_UNLESS(pose.position_m.allFinite() && pose.orientation.coeffs().allFinite(),
                     "laser scan has a non-finite sensor pose");
  CAIRN_THROW_UNLESS(std::isfinite(scan.angle_min_rad) && std::isfinite(scan.angle_increment_rad),
                     "laser scan has a non-finite angle_min or angle_increment");
  OccupancyInsertStats stats;
  segments_.clear();
  const Eigen::Matrix3d rotation = pose.orientation.normalized().toRotationMatrix();
  // The sensor's z axis against the vertical, without an acos: cos(tilt) = R(2, 2). A limit of
  // pi or more (+inf by default) skips nothing.
  if (rotation(2, 2) < std::cos(std::min(params_.max_scan_tilt_rad, M_PI))) {
    stats.scans_tilted = 1;
    return stats;
  }
  const common::Vector2 origin = pose.position_m.head<2>();
  // A reading at or beyond the scan's own range_max is a no-return.
  const double scan_max =
      scan.range_max_m > 0.0 && std::isfinite(scan.range_max_m) ? scan.range_max_m : INFINITY;
  const int n = static_cast<int>(scan.ranges_m.size());
  for (int i = 0; i < n; ++i) {
    if (i % params_.beam_step != 0) {
      ++stats.beams_skipped;
      continue;
    }
    const double r = scan.ranges_m[i];
    if (std::isnan(r) || r < 0.0) {
      ++stats.beams_invalid;
      continue;
    }
    const double angle = scan.angle_min_rad + i * scan.angle_increment_rad;
    const Eigen::Vector3d dir = rotation * Eigen::Vector3d(std::cos(angle), std::sin(angle), 0.0);
    const double horizontal = dir.head<2>().norm();
    if (horizontal < 1e-6) {  // a beam pointing straight up or down has no planar extent
      ++stats.beams_skipped;
      continue;
    }
    const bool no_return = !std::isfinite(r) || r >= scan_max;
    // The planar ray is the beam's projection on the ground plane. A no-return clears no
    // farther than the laser reaches.
    AddBeam(origin, dir.head<2>(), no_return ? std::min(r, scan_max) : r, /*hit=*/!no_return,
            &segments_, &stats);
  }
  return Integrate(segments_, stats);
}

OccupancyInsertStats OccupancyGrid::InsertRays(const std::vector<PlanarRay>& rays) {
  OccupancyInsertStats stats;
  segments_.clear();
  for (const PlanarRay& ray : rays) {
    const common::Vector2 delta = ray.end_m - ray.origin_m;
    const double length = delta.norm();
    const common::Vector2 direction =
        length > 0.0 ? common::Vector2(delta / length) : common::Vector2::Zero();
    AddBeam(ray.origin_m, direction, length, ray.hit, &segments_, &stats);
  }
  return Integrate(segments_, stats);
}

template <typename Visitor>
void OccupancyGrid::VisitRayCells(const Segment& s, Visitor&& visit) const {
  if (params_.traversal == OccupancyTraversal::kExact) {
    TraverseCells(s.x0, s.y0, s.x1, s.y1, visit);
  } else {
    const common::CellIndex from{static_cast<int>(std::floor(s.x0)),
                                 static_cast<int>(std::floor(s.y0))};
    const common::CellIndex to{static_cast<int>(std::floor(s.x1)),
                               static_cast<int>(std::floor(s.y1))};
    BresenhamCells(from, to, visit);
  }
}

void OccupancyGrid::ApplyMiss(float* cell, OccupancyInsertStats* stats) {
  const float l = std::isnan(*cell) ? 0.f : *cell;
  if (!(l < params_.protect_occupied_logodds)) return;  // protected occupied cell
  float updated = l + params_.miss_logodds;
  if (params_.clamp_after_scan) {
    touched_.push_back(cell);
  } else {
    updated = std::max(updated, params_.clamp_min_logodds);
  }
  *cell = updated;
  ++stats->misses;
}

void OccupancyGrid::ApplyHit(float* cell, OccupancyInsertStats* stats) {
  const float l = std::isnan(*cell) ? 0.f : *cell;
  float updated = l + params_.hit_logodds;
  if (params_.clamp_after_scan) {
    touched_.push_back(cell);
  } else {
    updated = std::min(updated, params_.clamp_max_logodds);
  }
  *cell = updated;
  ++stats->hits;
}

OccupancyInsertStats OccupancyGrid::Integrate(const std::vector<Segment>& segments,
                                              OccupancyInsertStats stats) {
  touched_.clear();
  if (!params_.one_update_per_scan || !IntegrateOncePerScan(segments, &stats)) {
    IntegratePerBeam(segments, &stats);
  }
  // Seed 003 clamps once, after the whole scan.
  for (float* cell : touched_) {
    *cell = std::clamp(*cell, params_.clamp_min_logodds, params_.clamp_max_logodds);
  }
  touched_.clear();
  if (stats.hits > 0 || stats.misses > 0) ++version_;
  return stats;
}

void OccupancyGrid::IntegratePerBeam(const std::vector<Segment>& segments,
                                     OccupancyInsertStats* stats) {
  // Every ray in turn: its crossed cells get a miss, then its end cell a hit.
  for (const Segment& s : segments) {
    const int end_ix = static_cast<int>(std::floor(s.x1));
    const int end_iy = static_cast<int>(std::floor(s.y1));
    VisitRayCells(s, [&](int ix, int iy) {
      const bool is_end = ix == end_ix && iy == end_iy;
      if (!Inside(ix, iy)) {
        if (is_end && s.hit) ++stats->hits_outside;
        return true;
      }
      if (is_end && s.hit) {
        ApplyHit(MutableCell(ix, iy), stats);
      } else {
        ApplyMiss(MutableCell(ix, iy), stats);
      }
      return true;
    });
  }
}

bool OccupancyGrid::IntegrateOncePerScan(const std::vector<Segment>& segments,
                                         OccupancyInsertStats* stats) {
  if (segments.empty()) return true;
  // Bounding box of the scan's cells, clipped to the grid.
  double min_x = INFINITY, min_y = INFINITY, max_x = -INFINITY, max_y = -INFINITY;
  for (const Segment& s : segments) {
    min_x = std::min({min_x, s.x0, s.x1});
    min_y = std::min({min_y, s.y0, s.y1});
    max_x = std::max({max_x, s.x0, s.x1});
    max_y = std::max({max_y, s.y0, s.y1});
  }
  const int bx0 = static_cast<int>(std::max(0.0, std::floor(min_x)));
  const int by0 = static_cast<int>(std::max(0.0, std::floor(min_y)));
  const int bx1 = static_cast<int>(std::min<double>(geometry_.size_x - 1, std::floor(max_x)));
  const int by1 = static_cast<int>(std::min<double>(geometry_.size_y - 1, std::floor(max_y)));
  if (bx1 < bx0 || by1 < by0) {
    // Entirely outside the grid: only count the returns that could not be marked.
    for (const Segment& s : segments) stats->hits_outside += s.hit ? 1 : 0;
    return true;
  }
  const int64_t width = int64_t{bx1} - bx0 + 1, height = int64_t{by1} - by0 + 1;
  if (width * height > kMaxScanBoxCells) return false;
  scan_state_.assign(static_cast<size_t>(width * height), kUntouched);
  auto state = [&](int ix, int iy) -> uint8_t& {
    return scan_state_[static_cast<size_t>((iy - by0) * width + (ix - bx0))];
  };

  // 1. Cells of obstacle returns: a hit wins over any miss of the same scan.
  for (const Segment& s : segments) {
    if (!s.hit) continue;
    const int ix = static_cast<int>(std::floor(s.x1)), iy = static_cast<int>(std::floor(s.y1));
    if (!Inside(ix, iy)) {
      ++stats->hits_outside;
      continue;
    }
    state(ix, iy) = kHitPending;
  }
  // 2. Crossed cells (and the end cell of a no-return ray): one miss each.
  for (const Segment& s : segments) {
    const int end_ix = static_cast<int>(std::floor(s.x1));
    const int end_iy = static_cast<int>(std::floor(s.y1));
    VisitRayCells(s, [&](int ix, int iy) {
      if (s.hit && ix == end_ix && iy == end_iy) return true;
      if (!Inside(ix, iy)) return true;
      uint8_t& st = state(ix, iy);
      if (st != kUntouched) return true;
      ApplyMiss(MutableCell(ix, iy), stats);
      st = kDone;
      return true;
    });
  }
  // 3. One hit per return cell.
  for (const Segment& s : segments) {
    if (!s.hit) continue;
    const int ix = static_cast<int>(std::floor(s.x1)), iy = static_cast<int>(std::floor(s.y1));
    if (!Inside(ix, iy)) continue;
    uint8_t& st = state(ix, iy);
    if (st != kHitPending) continue;
    ApplyHit(MutableCell(ix, iy), stats);
    st = kDone;
  }
  return true;
}

// ---------------------------------------------------------------------------------------------
// Export

common::GridGeometry OccupancyGrid::ObservedBounds() const {
  int tx0 = tiles_x_, ty0 = tiles_y_, tx1 = -1, ty1 = -1;
  for (int ty = 0; ty < tiles_y_; ++ty) {
    for (int tx = 0; tx < tiles_x_; ++tx) {
      if (!tiles_[static_cast<size_t>(ty) * tiles_x_ + tx]) continue;
      tx0 = std::min(tx0, tx);
      ty0 = std::min(ty0, ty);
      tx1 = std::max(tx1, tx);
      ty1 = std::max(ty1, ty);
    }
  }
  common::GridGeometry bounds;
  bounds.resolution_m = geometry_.resolution_m;
  if (tx1 < 0) {
    bounds.origin = geometry_.origin;
    return bounds;
  }
  const int x0 = tx0 << tile_shift_, y0 = ty0 << tile_shift_;
  const int x1 = std::min(geometry_.size_x, (tx1 + 1) << tile_shift_);
  const int y1 = std::min(geometry_.size_y, (ty1 + 1) << tile_shift_);
  bounds.size_x = x1 - x0;
  bounds.size_y = y1 - y0;
  bounds.origin = common::Pose2{geometry_.origin.x_m + x0 * geometry_.resolution_m,
                                geometry_.origin.y_m + y0 * geometry_.resolution_m, 0.0};
  return bounds;
}

common::GridMap OccupancyGrid::Export(const common::GridGeometry& window) const {
  common::GridMap map(window);
  common::Layer& percent = map.AddLayer(layers::kOccupancy);
  common::Layer& logodds = map.AddLayer(layers::kOccupancyLogOdds);
  const double res = geometry_.resolution_m;
  // Exact copy when the window's cells are this grid's cells.
  const double off_x = (window.origin.x_m - geometry_.origin.x_m) / res;
  const double off_y = (window.origin.y_m - geometry_.origin.y_m) / res;
  const bool aligned =
      window.origin.yaw_rad == 0.0 && std::abs(window.resolution_m - res) <= 1e-9 * res &&
      std::abs(off_x - std::round(off_x)) < 1e-6 && std::abs(off_y - std::round(off_y)) < 1e-6;
  if (aligned) {
    const int dx = static_cast<int>(std::lround(off_x)), dy = static_cast<int>(std::lround(off_y));
    for (int iy = 0; iy < window.size_y; ++iy) {
      for (int ix = 0; ix < window.size_x; ++ix) {
        const float* c = FindCell(ix + dx, iy + dy);
        if (!c || std::isnan(*c)) continue;
        logodds(ix, iy) = *c;
        percent(ix, iy) = OccupancyPercent(*c);
      }
    }
    return map;
  }
  // Otherwise sample k x k points per window cell and keep the highest log-odds.
  const int k = std::max(1, static_cast<int>(std::ceil(window.resolution_m / res - 1e-9)));
  const double step = window.resolution_m / k;
  const double c = std::cos(window.origin.yaw_rad), s = std::sin(window.origin.yaw_rad);
  for (int iy = 0; iy < window.size_y; ++iy) {
    for (int ix = 0; ix < window.size_x; ++ix) {
      float best = kNaN;
      for (int sy = 0; sy < k; ++sy) {
        for (int sx = 0; sx < k; ++sx) {
          const double mx = ix * window.resolution_m + (sx + 0.5) * step;
          const double my = iy * window.resolution_m + (sy + 0.5) * step;
          const common::Vector2 world(window.origin.x_m + c * mx - s * my,
                                      window.origin.y_m + s * mx + c * my);
          const float v = LogOddsAt(world);
          if (!std::isnan(v) && (std::isnan(best) || v > best)) best = v;
        }
      }
      if (std::isnan(best)) continue;
      logodds(ix, iy) = best;
      percent(ix, iy) = OccupancyPercent(best);
    }
  }
  return map;
}

void OccupancyGrid::Import(const common::GridMap& map) {
  const common::Layer& layer = map.at(layers::kOccupancyLogOdds);
  for (int iy = 0; iy < map.size_y(); ++iy) {
    for (int ix = 0; ix < map.size_x(); ++ix) {
      const float v = layer(ix, iy);
      if (!std::isfinite(v)) continue;
      const auto cell = CellAt(map.CenterOf({ix, iy}));
      if (!cell) continue;
      *MutableCell(cell->ix, cell->iy) =
          std::clamp(v, params_.clamp_min_logodds, params_.clamp_max_logodds);
    }
  }
  ++version_;
}

OccupancyParams ReadOccupancyParams(common::YamlMap& m, const OccupancyParams& base) {
  std::string preset = "octomap";
  m.Get("preset", &preset);
  OccupancyParams p = base;
  if (preset == "seed003") {
    p = OccupancyParams::Seed003();
  } else if (preset != "octomap") {
    m.Fail(m.Raw("preset"), "occupancy.preset must be 'octomap' or 'seed003'");
  }
  m.Get("hit_logodds", &p.hit_logodds);
  m.Get("miss_logodds", &p.miss_logodds);
  m.Get("clamp_min_logodds", &p.clamp_min_logodds);
  m.Get("clamp_max_logodds", &p.clamp_max_logodds);
  m.Get("resolution_m", &p.resolution_m);
  m.Get("size_x_cells", &p.size_x_cells);
  m.Get("size_y_cells", &p.size_y_cells);
  m.Get("origin_x_m", &p.origin_x_m);
  m.Get("origin_y_m", &p.origin_y_m);
  m.Get("min_range_m", &p.min_range_m);
  m.Get("max_range_m", &p.max_range_m);
  m.Get("no_return_range_m", &p.no_return_range_m);
  double max_scan_tilt_deg = p.max_scan_tilt_rad * 180.0 / M_PI;
  m.Get("max_scan_tilt_deg", &max_scan_tilt_deg);
  p.max_scan_tilt_rad = max_scan_tilt_deg * M_PI / 180.0;
  // Seed 003 test 36's "improved" mode raises it above clamp_max_logodds (.inf: misses always
  // apply).
  m.Get("protect_occupied_logodds", &p.protect_occupied_logodds);
  return p;
}

}  // namespace cairn::mapping
