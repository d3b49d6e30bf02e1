#include "planner/cost_map.h"

#include <algorithm>
#include <cmath>
#include <deque>
#include <limits>

#include "common/check.h"
#include "common/layers.h"

namespace cairn::planner {

using common::CellIndex;
using common::Pose2;
using common::Vector2;

namespace {

constexpr double kHalfDiagonal = 0.70710678118654752;  // cells
// A point at distance d from a cell centre is at most d - 0.5 from the cell's square (the
// square holds the disc of radius 0.5 around its centre). For a point anywhere in a cell whose
// centre is d_cc from a blocking cell's centre, the distance to that square is therefore at
// most d_cc + kHalfDiagonal - 0.5 = d_cc + kInnerSlack.
constexpr double kInnerSlack = kHalfDiagonal - 0.5;
constexpr double kEps = 1e-6;

}  // namespace

void CostMapParams::Validate() const {
  CAIRN_THROW_UNLESS(std::isfinite(lethal_cost) && lethal_cost > 0.0f,
                     "lethal_cost must be positive, got " << lethal_cost);
  CAIRN_THROW_UNLESS(std::isfinite(planning_padding_m) && planning_padding_m >= 0.0,
                     "planning_padding_m must not be negative, got " << planning_padding_m);
  CAIRN_THROW_UNLESS(std::isfinite(footprint_padding_m) && footprint_padding_m >= 0.0 &&
                         footprint_padding_m <= 10.0,
                     "footprint_padding_m must lie in [0, 10], got " << footprint_padding_m);
  CAIRN_THROW_UNLESS(
      std::isfinite(unknown_cost) && unknown_cost >= 0.0f && unknown_cost < lethal_cost,
      "unknown_cost must lie in [0, lethal_cost), got " << unknown_cost);
  CAIRN_THROW_UNLESS(std::isfinite(one_way_cost) && one_way_cost >= 0.0f,
                     "one_way_cost must be finite and >= 0, got " << one_way_cost);
}

int HeadingClass(double heading_grid_rad) {
  constexpr double kQuarter = M_PI / 2;
  constexpr double kAxisTolerance = 1e-6;  // rad
  double h = std::fmod(heading_grid_rad, 2.0 * M_PI);
  if (h < 0.0) h += 2.0 * M_PI;
  const double axes = h / kQuarter;
  const double nearest = std::round(axes);
  if (std::abs(axes - nearest) * kQuarter <= kAxisTolerance) {
    return (2 * static_cast<int>(nearest)) % 8;
  }
  return (2 * static_cast<int>(std::floor(axes)) + 1) % 8;
}

uint8_t HeadingClassBits(int heading_class) {
  CAIRN_DEMAND(heading_class >= 0 && heading_class < 8);
  if (heading_class % 2 == 0) return static_cast<uint8_t>(1u << heading_class);
  return static_cast<uint8_t>((1u << ((heading_class + 7) % 8)) | (1u << heading_class) |
                              (1u << ((heading_class + 1) % 8)));
}

CellIndex HeadingStep(int bin) {
  static const int kDx[8] = {1, 1, 0, -1, -1, -1, 0, 1};
  static const int kDy[8] = {0, 1, 1, 1, 0, -1, -1, -1};
  CAIRN_DEMAND(bin >= 0 && bin < 8);
  return {kDx[bin], kDy[bin]};
}

CostMap::CostMap(const common::GridGeometry& geometry, common::Layer cost,
                 const std::vector<Vector2>& footprint_m, const CostMapParams& params)
    : CostMap(geometry, std::move(cost), std::nullopt, footprint_m, params) {}

CostMap::CostMap(const common::GridGeometry& geometry, common::Layer cost,
                 std::optional<common::Layer> directed, const std::vector<Vector2>& footprint_m,
                 const CostMapParams& params)
    : geometry_(geometry), cost_(std::move(cost)), params_(params) {
  geometry_.Validate();
  params_.Validate();
  CAIRN_THROW_UNLESS(cost_.rows() == geometry_.size_x && cost_.cols() == geometry_.size_y,
                     "cost layer is " << cost_.rows() << " x " << cost_.cols()
                                      << " cells but the grid is " << geometry_.size_x << " x "
                                      << geometry_.size_y);
  if (directed) {
    CAIRN_THROW_UNLESS(directed->rows() == geometry_.size_x && directed->cols() == geometry_.size_y,
                       "directed layer is " << directed->rows() << " x " << directed->cols()
                                            << " cells but the grid is " << geometry_.size_x
                                            << " x " << geometry_.size_y);
    ReadDirected(*directed);
  }
  cos_origin_ = std::cos(geometry_.origin.yaw_rad);
  sin_origin_ = std::sin(geometry_.origin.yaw_rad);
  // The robot's footprint and the padded one the global planner checks its states with.
  FootprintRasterizer own(footprint_m);
  FootprintRasterizer robot =
      params_.footprint_padding_m > 0.0
          ? FootprintRasterizer(GrowConvexPolygon(own.hull_m(), params_.footprint_padding_m))
          : own;
  FootprintRasterizer padded(GrowConvexPolygon(robot.hull_m(), params_.planning_padding_m));
  for (const FootprintRasterizer* r : {&robot, &padded}) {
    shapes_.push_back({*r, r->circumscribed_radius_m() / geometry_.resolution_m,
                       r->inscribed_radius_m() / geometry_.resolution_m});
  }

  // Blocking and non-free masks, then their distance fields.
  GridMask blocked(geometry_.size_x, geometry_.size_y);
  GridMask nonfree(geometry_.size_x, geometry_.size_y);
  const float* c = cost_.data();
  uint8_t* b = blocked.data();
  uint8_t* nf = nonfree.data();
  const int64_t n = geometry_.num_cells();
  int min_x = geometry_.size_x, min_y = geometry_.size_y, max_x = -1, max_y = -1;
  for (int64_t i = 0; i < n; ++i) {
    const float v = c[i];
    const bool unknown = std::isnan(v);
    b[i] = (unknown ? !params_.unknown_is_traversable : v >= params_.lethal_cost) ? 1 : 0;
    nf[i] = (unknown || v > 0.0f) ? 1 : 0;
    if (!unknown) {
      const int ix = static_cast<int>(i % geometry_.size_x);
      const int iy = static_cast<int>(i / geometry_.size_x);
      min_x = std::min(min_x, ix);
      max_x = std::max(max_x, ix);
      min_y = std::min(min_y, iy);
      max_y = std::max(max_y, iy);
    }
  }
  if (max_x >= 0) known_cells_ = std::make_pair(CellIndex{min_x, min_y}, CellIndex{max_x, max_y});
  blocked_distance_ = DistanceTransform(blocked);
  nonfree_distance_ = DistanceTransform(nonfree);
}

// The directed masks into the cost layer (255: lethal; 1..254: one-way, not blocking; unseen
// drops: lethal or unknown) and the one-way masks.
void CostMap::ReadDirected(const common::Layer& directed) {
  has_directed_ = true;
  // Graded: never as high as the lethal cost.
  const float one_way = std::min(params_.one_way_cost, std::nextafter(params_.lethal_cost, 0.0f));
  const int64_t n = geometry_.num_cells();
  const float* d = directed.data();
  float* c = cost_.data();
  for (int64_t i = 0; i < n; ++i) {
    const float v = d[i];
    if (std::isnan(v) || v == 0.0f) continue;
    int mask = 0;
    if (v == layers::kUnseenDrop) {
      ++unseen_drop_cells_;
      if (!params_.unseen_drop_is_unknown) {
        c[i] = params_.lethal_cost;
        continue;
      }
      // The rim may be driven over towards the ground out of sight, to look, never climbed
      // from there: out of the rim, the headings away from each unknown 4-neighbour are refused.
      mask = ClimbFromUnknownMask(i, d);
      if (mask == 0) {
        c[i] = std::numeric_limits<float>::quiet_NaN();
        continue;
      }
    } else {
      const bool whole = v >= 0.0f && v <= layers::kAllHeadingsBlocked && v == std::floor(v);
      mask = whole ? static_cast<int>(v) : static_cast<int>(layers::kAllHeadingsBlocked);
    }
    if (mask == static_cast<int>(layers::kAllHeadingsBlocked)) {
      c[i] = params_.lethal_cost;
      continue;
    }
    if (one_way_mask_.empty()) one_way_mask_.assign(static_cast<size_t>(n), 0);
    one_way_mask_[i] = static_cast<uint8_t>(mask);
    ++one_way_cells_;
    if (!std::isnan(c[i])) {
      c[i] = c[i] >= params_.lethal_cost ? one_way : std::max(c[i], one_way);
    }
  }
}

int CostMap::ClimbFromUnknownMask(int64_t i, const float* directed) const {
  const int sx = geometry_.size_x;
  const int ix = static_cast<int>(i % sx), iy = static_cast<int>(i / sx);
  const float* c = cost_.data();
  // The 4-neighbours +x, -x, +y, -y, and the heading bit from each into the cell.
  constexpr int kDx[4] = {1, -1, 0, 0}, kDy[4] = {0, 0, 1, -1}, kInto[4] = {4, 0, 6, 2};
  int mask = 0;
  for (int k = 0; k < 4; ++k) {
    const int x = ix + kDx[k], y = iy + kDy[k];
    if (x < 0 || y < 0 || x >= sx || y >= geometry_.size_y) continue;
    // Another rim read as unknown ground is not ground out of sight.
    const int64_t j = x + static_cast<int64_t>(y) * sx;
    if (std::isnan(c[j]) && directed[j] != layers::kUnseenDrop) mask |= 1 << kInto[k];
  }
  return mask;
}

uint8_t CostMap::OneWayMask(const CellIndex& cell) const {
  if (one_way_mask_.empty() || !geometry_.Contains(cell)) return 0;
  return one_way_mask_[geometry_.LinearIndex(cell)];
}

const Eigen::MatrixXf& CostMap::heading_block_distance_cells(int heading_class) const {
  CAIRN_DEMAND(heading_class >= 0 && heading_class < 8);
  std::call_once(class_once_[heading_class], [this, heading_class] {
    class_distance_[heading_class] = RefusalDistance(HeadingClassBits(heading_class));
  });
  return class_distance_[heading_class];
}

const Eigen::MatrixXf& CostMap::one_way_distance_cells() const {
  std::call_once(one_way_once_, [this] { one_way_distance_ = RefusalDistance(0xFF); });
  return one_way_distance_;
}

Eigen::MatrixXf CostMap::RefusalDistance(uint8_t bits) const {
  // The transform runs over the refusing cells' bounding box grown by a margin; farther out
  // the field holds the margin, a lower bound of the distance.
  const int sx = geometry_.size_x, sy = geometry_.size_y;
  int x0 = sx, y0 = sy, x1 = -1, y1 = -1;
  for (size_t i = 0; i < one_way_mask_.size(); ++i) {
    if (!(one_way_mask_[i] & bits)) continue;
    const int ix = static_cast<int>(i % sx), iy = static_cast<int>(i / sx);
    x0 = std::min(x0, ix);
    x1 = std::max(x1, ix);
    y0 = std::min(y0, iy);
    y1 = std::max(y1, iy);
  }
  Eigen::MatrixXf field;
  if (x1 < 0) {
    field.setConstant(sx, sy, std::numeric_limits<float>::infinity());
    return field;
  }
  const int margin = ClassFieldMarginCells();
  x0 = std::max(0, x0 - margin);
  y0 = std::max(0, y0 - margin);
  x1 = std::min(sx - 1, x1 + margin);
  y1 = std::min(sy - 1, y1 + margin);
  GridMask refusing(x1 - x0 + 1, y1 - y0 + 1);
  for (int iy = y0; iy <= y1; ++iy) {
    for (int ix = x0; ix <= x1; ++ix) {
      refusing(ix - x0, iy - y0) =
          (one_way_mask_[ix + static_cast<int64_t>(iy) * sx] & bits) ? 1 : 0;
    }
  }
  field.setConstant(sx, sy, static_cast<float>(margin));
  field.block(x0, y0, x1 - x0 + 1, y1 - y0 + 1) = DistanceTransform(refusing);
  return field;
}

int CostMap::ClassFieldMarginCells() const {
  // Beyond every distance the fields are compared with: the padded footprint's reach (twice
  // over, for the skipping along a motion) and any grid planner's clearance disc.
  return std::max(64, static_cast<int>(std::ceil(4.0 * shapes_[1].circumscribed_cells)) + 8);
}

// True when a cell under the footprint at the pose has one of `bits`.
bool CostMap::FootprintCrosses(double x_cells, double y_cells, double yaw_grid_rad,
                               const Shape& shape, uint8_t bits,
                               const std::vector<StraddledBits>* straddled) const {
  thread_local std::vector<RowSpan> spans;
  shape.rasterizer.Rasterize(x_cells, y_cells, yaw_grid_rad, geometry_.resolution_m, &spans);
  const int sx = geometry_.size_x;
  for (const RowSpan& span : spans) {
    if (span.iy < 0 || span.iy >= geometry_.size_y) continue;
    const int64_t row_start = static_cast<int64_t>(span.iy) * sx;
    const uint8_t* row = one_way_mask_.data() + row_start;
    for (int ix = std::max(0, span.ix_min); ix <= std::min(span.ix_max, sx - 1); ++ix) {
      if (!(row[ix] & bits)) continue;
      if (straddled == nullptr || straddled->empty()) return true;
      const int64_t cell = row_start + ix;
      const auto it =
          std::lower_bound(straddled->begin(), straddled->end(), cell,
                           [](const StraddledBits& s, int64_t c) { return s.cell < c; });
      const uint8_t exempt = it != straddled->end() && it->cell == cell ? it->bits : 0;
      if (row[ix] & bits & static_cast<uint8_t>(~exempt)) return true;
    }
  }
  return false;
}

std::vector<CostMap::StraddledBits> CostMap::StraddledOneWayBits(const Pose2& pose_world) const {
  std::vector<StraddledBits> out;
  if (one_way_cells_ == 0) return out;
  std::vector<RowSpan> spans;
  const Vector2 g = ToGridCells(pose_world.position());
  shapes_[0].rasterizer.Rasterize(g.x(), g.y(), ToGridYaw(pose_world.yaw_rad),
                                  geometry_.resolution_m, &spans);
  const auto covered = [&spans](int ix, int iy) {
    for (const RowSpan& span : spans) {
      if (span.iy == iy && ix >= span.ix_min && ix <= span.ix_max) return true;
    }
    return false;
  };
  const int sx = geometry_.size_x;
  for (const RowSpan& span : spans) {
    if (span.iy < 0 || span.iy >= geometry_.size_y) continue;
    for (int ix = std::max(0, span.ix_min); ix <= std::min(span.ix_max, sx - 1); ++ix) {
      const int64_t cell = ix + static_cast<int64_t>(span.iy) * sx;
      const uint8_t mask = one_way_mask_[cell];
      if (mask == 0) continue;
      uint8_t bits = 0;
      for (int k = 0; k < 8; ++k) {
        const CellIndex step = HeadingStep(k);
        if ((mask & (1u << k)) && covered(ix + step.ix, span.iy + step.iy)) bits |= 1u << k;
      }
      if (bits != 0) out.push_back({cell, bits});
    }
  }
  std::sort(out.begin(), out.end(),
            [](const StraddledBits& a, const StraddledBits& b) { return a.cell < b.cell; });
  return out;
}

bool CostMap::MotionAllowed(const Pose2& from, const Pose2& to, FootprintKind kind) const {
  static const std::vector<StraddledBits> kNone;
  return MotionAllowed(from, to, kind, kNone);
}

bool CostMap::MotionAllowed(const Pose2& from, const Pose2& to, FootprintKind kind,
                            const std::vector<StraddledBits>& straddled) const {
  if (one_way_cells_ == 0) return true;
  const Vector2 a = ToGridCells(from.position());
  const Vector2 d = ToGridCells(to.position()) - a;
  const double length = d.norm();
  if (length < 1e-9) return true;  // a pure rotation crosses nothing
  const int heading_class = HeadingClass(std::atan2(d.y(), d.x()));
  const uint8_t bits = HeadingClassBits(heading_class);
  const Eigen::MatrixXf& field = heading_block_distance_cells(heading_class);
  const Shape& shape = shapes_[static_cast<int>(kind)];
  const double yaw0 = ToGridYaw(from.yaw_rad);
  const double turn = common::WrapAngle(to.yaw_rad - from.yaw_rad);
  // Poses at most half a cell apart for every point of the footprint.
  const double sweep = length + shape.circumscribed_cells * std::abs(turn);
  const int n = std::max(1, static_cast<int>(std::ceil(sweep / 0.5)));
  const double sample_cells = length / n;
  // A cell the footprint touches at a position p has its centre within `reach` of the centre
  // of p's cell; at a position s cells further on, within reach + s.
  const double reach = shape.circumscribed_cells + 2.0 * kHalfDiagonal + kEps;
  for (int k = 0; k <= n;) {
    const double t = static_cast<double>(k) / n;
    const Vector2 p = a + d * t;
    double free_cells = -1.0;
    if (p.x() >= 0.0 && p.y() >= 0.0 && p.x() < geometry_.size_x && p.y() < geometry_.size_y) {
      free_cells = field(static_cast<int>(p.x()), static_cast<int>(p.y())) - reach;
    }
    if (free_cells > 0.0) {
      if (std::isinf(free_cells)) return true;
      k += std::max(1, static_cast<int>(std::ceil(free_cells / sample_cells)) - 1);
      continue;
    }
    if (FootprintCrosses(p.x(), p.y(), yaw0 + t * turn, shape, bits, &straddled)) return false;
    ++k;
  }
  return true;
}

Vector2 CostMap::ToGridCells(const Vector2& world_m) const {
  const double dx = world_m.x() - geometry_.origin.x_m;
  const double dy = world_m.y() - geometry_.origin.y_m;
  const double inv = 1.0 / geometry_.resolution_m;
  return {(cos_origin_ * dx + sin_origin_ * dy) * inv,
          (-sin_origin_ * dx + cos_origin_ * dy) * inv};
}

bool CostMap::Contains(const Vector2& world_m) const {
  const Vector2 g = ToGridCells(world_m);
  return g.x() >= 0.0 && g.y() >= 0.0 && g.x() < geometry_.size_x && g.y() < geometry_.size_y;
}

float CostMap::CostAt(const Vector2& world_m) const {
  const Vector2 g = ToGridCells(world_m);
  if (!(g.x() >= 0.0 && g.y() >= 0.0 && g.x() < geometry_.size_x && g.y() < geometry_.size_y)) {
    return std::numeric_limits<float>::quiet_NaN();
  }
  return cost_(static_cast<int>(g.x()), static_cast<int>(g.y()));
}

float CostMap::TraversalCostAt(const Vector2& world_m) const {
  const float v = CostAt(world_m);
  if (std::isnan(v)) return params_.unknown_cost;
  return std::min(std::max(v, 0.0f), params_.lethal_cost);
}

bool CostMap::IsBlockedCell(const CellIndex& cell) const {
  if (!geometry_.Contains(cell)) return !params_.unknown_is_traversable;
  const float v = cost_(cell.ix, cell.iy);
  return std::isnan(v) ? !params_.unknown_is_traversable : v >= params_.lethal_cost;
}

double CostMap::ClearanceAt(const Vector2& world_m) const {
  const Vector2 g = ToGridCells(world_m);
  if (!(g.x() >= 0.0 && g.y() >= 0.0 && g.x() < geometry_.size_x && g.y() < geometry_.size_y)) {
    return 0.0;
  }
  return blocked_distance_(static_cast<int>(g.x()), static_cast<int>(g.y())) *
         geometry_.resolution_m;
}

double CostMap::SmoothClearanceAt(const Vector2& world_m) const {
  return SmoothDistance(blocked_distance_, world_m);
}

double CostMap::SmoothOneWayClearanceAt(const Vector2& world_m) const {
  if (one_way_cells_ == 0) return std::numeric_limits<double>::infinity();
  return SmoothDistance(one_way_distance_cells(), world_m);
}

double CostMap::SmoothDistance(const Eigen::MatrixXf& d, const Vector2& world_m) const {
  const Vector2 g = ToGridCells(world_m);
  if (!(g.x() >= 0.0 && g.y() >= 0.0 && g.x() < geometry_.size_x && g.y() < geometry_.size_y)) {
    return 0.0;
  }
  // Cell centres sit at half-integer coordinates; clamp at the border.
  const double fx = std::clamp(g.x() - 0.5, 0.0, geometry_.size_x - 1.0);
  const double fy = std::clamp(g.y() - 0.5, 0.0, geometry_.size_y - 1.0);
  const int x0 = std::min(static_cast<int>(fx), geometry_.size_x - 1);
  const int y0 = std::min(static_cast<int>(fy), geometry_.size_y - 1);
  const int x1 = std::min(x0 + 1, geometry_.size_x - 1);
  const int y1 = std::min(y0 + 1, geometry_.size_y - 1);
  const double tx = fx - x0, ty = fy - y0;
  if (std::isinf(d(x0, y0))) return std::numeric_limits<double>::infinity();
  const double v = (1 - tx) * (1 - ty) * d(x0, y0) + tx * (1 - ty) * d(x1, y0) +
                   (1 - tx) * ty * d(x0, y1) + tx * ty * d(x1, y1);
  return v * geometry_.resolution_m;
}

CostMap::Quick CostMap::QuickCheck(double x_cells, double y_cells, const Shape& shape) const {
  if (!(x_cells >= 0.0 && y_cells >= 0.0)) return Quick::kUnknown;
  const int ix = static_cast<int>(x_cells);
  const int iy = static_cast<int>(y_cells);
  // Every cell the footprint can touch must lie inside the grid for the distance fields to
  // speak for it (cells outside the grid are unknown).
  const int margin = static_cast<int>(std::ceil(shape.circumscribed_cells)) + 2;
  if (ix < margin || iy < margin || ix >= geometry_.size_x - margin ||
      iy >= geometry_.size_y - margin) {
    return Quick::kUnknown;
  }
  // A touched cell's centre lies within the circumscribed radius plus one cell diagonal of the
  // centre of the robot's cell.
  const double reach = shape.circumscribed_cells + 2.0 * kHalfDiagonal + kEps;
  if (nonfree_distance_(ix, iy) > reach) return Quick::kValidFree;
  const float blocked = blocked_distance_(ix, iy);
  if (blocked > reach) return Quick::kValid;
  // A blocking cell this close overlaps the inscribed disc wherever the robot is in its cell.
  if (blocked + kInnerSlack + kEps < shape.inscribed_cells) return Quick::kInvalid;
  return Quick::kUnknown;
}

FootprintCost CostMap::ExactAtGridPose(double x_cells, double y_cells, double yaw_grid_rad,
                                       const Shape& shape,
                                       const std::vector<int64_t>* ignored) const {
  thread_local std::vector<RowSpan> spans;
  shape.rasterizer.Rasterize(x_cells, y_cells, yaw_grid_rad, geometry_.resolution_m, &spans);
  FootprintCost out;
  const int sx = geometry_.size_x;
  const int sy = geometry_.size_y;
  const float* data = cost_.data();
  auto unknown = [&]() {
    out.touches_unknown = true;
    if (!params_.unknown_is_traversable) {
      out.valid = false;
      out.max_cost = params_.lethal_cost;
      return false;
    }
    out.max_cost = std::max(out.max_cost, params_.unknown_cost);
    return true;
  };
  for (const RowSpan& span : spans) {
    if (span.iy < 0 || span.iy >= sy) {
      if (!unknown()) return out;
      continue;
    }
    int lo = span.ix_min, hi = span.ix_max;
    if (lo < 0 || hi >= sx) {
      if (!unknown()) return out;
      lo = std::max(lo, 0);
      hi = std::min(hi, sx - 1);
    }
    const float* row = data + static_cast<int64_t>(span.iy) * sx;
    for (int ix = lo; ix <= hi; ++ix) {
      const float v = row[ix];
      if (ignored != nullptr && !ignored->empty() &&
          std::binary_search(ignored->begin(), ignored->end(),
                             ix + static_cast<int64_t>(span.iy) * sx)) {
        continue;
      }
      if (std::isnan(v)) {
        if (!unknown()) return out;
      } else if (v >= params_.lethal_cost) {
        out.valid = false;
        out.max_cost = params_.lethal_cost;
        return out;
      } else if (v > out.max_cost) {
        out.max_cost = v;
      }
    }
  }
  return out;
}

FootprintCost CostMap::CheckFootprintExact(const Pose2& pose_world, FootprintKind kind) const {
  const Vector2 g = ToGridCells(pose_world.position());
  return ExactAtGridPose(g.x(), g.y(), ToGridYaw(pose_world.yaw_rad),
                         shapes_[static_cast<int>(kind)]);
}

std::vector<int64_t> CostMap::BlockingCellsUnder(const Pose2& pose_world) const {
  std::vector<RowSpan> spans;
  const Vector2 g = ToGridCells(pose_world.position());
  shapes_[0].rasterizer.Rasterize(g.x(), g.y(), ToGridYaw(pose_world.yaw_rad),
                                  geometry_.resolution_m, &spans);
  std::vector<int64_t> cells;
  for (const RowSpan& span : spans) {
    if (span.iy < 0 || span.iy >= geometry_.size_y) continue;
    for (int ix = std::max(0, span.ix_min); ix <= std::min(span.ix_max, geometry_.size_x - 1);
         ++ix) {
      if (IsBlockedCell({ix, span.iy}))
        cells.push_back(ix + static_cast<int64_t>(span.iy) * geometry_.size_x);
    }
  }
  std::sort(cells.begin(), cells.end());
  return cells;
}

FootprintCost CostMap::CheckFootprintIgnoring(const Pose2& pose_world,
                                              const std::vector<int64_t>& ignored_cells) const {
  const Vector2 g = ToGridCells(pose_world.position());
  // Far from every blocking cell the ignored ones cannot matter; near one, read the cells.
  if (QuickCheck(g.x(), g.y(), shapes_[0]) == Quick::kValidFree) return FootprintCost{};
  return ExactAtGridPose(g.x(), g.y(), ToGridYaw(pose_world.yaw_rad), shapes_[0], &ignored_cells);
}

FootprintCost CostMap::CheckFootprint(const Pose2& pose_world, FootprintKind kind) const {
  const Shape& shape = shapes_[static_cast<int>(kind)];
  const Vector2 g = ToGridCells(pose_world.position());
  switch (QuickCheck(g.x(), g.y(), shape)) {
    case Quick::kValidFree:
      return FootprintCost{};
    case Quick::kInvalid:
      return FootprintCost{false, params_.lethal_cost, false};
    case Quick::kValid:
    case Quick::kUnknown:
      break;
  }
  return ExactAtGridPose(g.x(), g.y(), ToGridYaw(pose_world.yaw_rad), shape);
}

bool CostMap::IsValid(const Pose2& pose_world, FootprintKind kind) const {
  const Shape& shape = shapes_[static_cast<int>(kind)];
  const Vector2 g = ToGridCells(pose_world.position());
  switch (QuickCheck(g.x(), g.y(), shape)) {
    case Quick::kValidFree:
    case Quick::kValid:
      return true;
    case Quick::kInvalid:
      return false;
    case Quick::kUnknown:
      break;
  }
  return ExactAtGridPose(g.x(), g.y(), ToGridYaw(pose_world.yaw_rad), shape).valid;
}

bool CostMap::FitsAtSomeHeading(int64_t cell, FootprintKind kind) const {
  const int k_kind = static_cast<int>(kind);
  std::call_once(fits_once_[k_kind], [this, k_kind] {
    fits_[k_kind].reset(new std::atomic<uint8_t>[static_cast<size_t>(geometry_.num_cells())]());
  });
  std::atomic<uint8_t>& known = fits_[k_kind][static_cast<size_t>(cell)];
  const uint8_t answer = known.load(std::memory_order_relaxed);
  if (answer != 0) return answer == 1;
  const Vector2 c = geometry_.CenterOf(
      {static_cast<int>(cell % geometry_.size_x), static_cast<int>(cell / geometry_.size_x)});
  constexpr int kHeadings = 16;
  bool fits = false;
  for (int k = 0; k < kHeadings && !fits; ++k) {
    fits = IsValid({c.x(), c.y(), 2.0 * M_PI * k / kHeadings}, kind);
  }
  known.store(fits ? 1 : 2, std::memory_order_relaxed);
  return fits;
}

void CostMap::ComputeComponents() const {
  const int sx = geometry_.size_x;
  const int sy = geometry_.size_y;
  const int64_t n = geometry_.num_cells();
  components_.assign(static_cast<size_t>(n), -1);
  // A cell is passable when some position inside it keeps the inscribed disc off every
  // blocking cell. With the origin outside the footprint nothing can be ruled out.
  const double inscribed = shapes_[0].inscribed_cells;
  const bool prune = inscribed > 0.0;
  const double threshold = std::max(0.0, inscribed - kInnerSlack - 1e-3);
  std::vector<uint8_t> passable(static_cast<size_t>(n), 1);
  if (prune) {
    const float* d = blocked_distance_.data();
    for (int64_t i = 0; i < n; ++i) passable[i] = (d[i] > 0.0f && d[i] >= threshold) ? 1 : 0;
  }
  int32_t label = 0;
  std::vector<int64_t> stack;
  for (int64_t seed = 0; seed < n; ++seed) {
    if (!passable[seed] || components_[seed] >= 0) continue;
    components_[seed] = label;
    stack.push_back(seed);
    while (!stack.empty()) {
      const int64_t i = stack.back();
      stack.pop_back();
      const int ix = static_cast<int>(i % sx);
      const int iy = static_cast<int>(i / sx);
      for (int dy = -1; dy <= 1; ++dy) {
        const int ny = iy + dy;
        if (ny < 0 || ny >= sy) continue;
        for (int dx = -1; dx <= 1; ++dx) {
          const int nx = ix + dx;
          if ((dx == 0 && dy == 0) || nx < 0 || nx >= sx) continue;
          const int64_t j = nx + static_cast<int64_t>(ny) * sx;
          if (passable[j] && components_[j] < 0) {
            components_[j] = label;
            stack.push_back(j);
          }
        }
      }
    }
    ++label;
  }
}

const std::vector<int32_t>& CostMap::RidgeCells() const {
  std::call_once(ridges_once_, [this] {
    const int sx = geometry_.size_x;
    const int sy = geometry_.size_y;
    const float* d = blocked_distance_.data();
    const double passable = std::max(0.0, shapes_[0].inscribed_cells - kInnerSlack - 1e-3);
    const float far = static_cast<float>(10.0 / geometry_.resolution_m);
    static const int kDx[4] = {1, 0, 1, 1};
    static const int kDy[4] = {0, 1, 1, -1};
    for (int iy = 1; iy + 1 < sy; ++iy) {
      for (int ix = 1; ix + 1 < sx; ++ix) {
        const int64_t i = ix + static_cast<int64_t>(iy) * sx;
        const float v = d[i];
        if (!(v > 0.0f) || v < passable || v >= far) continue;
        for (int k = 0; k < 4; ++k) {
          const float a = d[i + kDx[k] + static_cast<int64_t>(kDy[k]) * sx];
          const float b = d[i - kDx[k] - static_cast<int64_t>(kDy[k]) * sx];
          if (v >= a && v >= b && (v > a || v > b)) {
            ridges_.push_back(static_cast<int32_t>(i));
            break;
          }
        }
      }
    }
  });
  return ridges_;
}

bool CostMap::ConnectedWithinHorizon(const Vector2& a_world_m, const Vector2& b_world_m,
                                     double horizon_m, double goal_radius_m) const {
  const auto a = geometry_.IndexOf(a_world_m);
  const auto b = geometry_.IndexOf(b_world_m);
  if (!a || !b) return false;
  const int sx = geometry_.size_x;
  const int sy = geometry_.size_y;
  const double res = geometry_.resolution_m;
  const double inscribed = shapes_[0].inscribed_cells;
  const double threshold = std::max(0.0, inscribed - kInnerSlack - 1e-3);
  const float* d = blocked_distance_.data();
  const float* c = cost_.data();
  const double h2 = (horizon_m / res) * (horizon_m / res);
  const double g2 = (goal_radius_m / res) * (goal_radius_m / res);
  auto allowed = [&](int ix, int iy) {
    const int64_t i = ix + static_cast<int64_t>(iy) * sx;
    if (inscribed > 0.0 && !(d[i] > 0.0f && d[i] >= threshold)) return false;
    if (!std::isnan(c[i])) return true;
    const double da = double(ix - a->ix) * (ix - a->ix) + double(iy - a->iy) * (iy - a->iy);
    const double db = double(ix - b->ix) * (ix - b->ix) + double(iy - b->iy) * (iy - b->iy);
    return da <= h2 || db <= g2;
  };
  if (!allowed(a->ix, a->iy) || !allowed(b->ix, b->iy)) return false;
  // On a map with one-way cells, the steps DirectedReachable refuses are refused here too.
  const bool directed = one_way_cells_ > 0 && inscribed > 0.0;
  std::array<const float*, 8> refused{};
  if (directed) {
    for (int k = 0; k < 8; ++k) refused[k] = heading_block_distance_cells(k).data();
  }
  const auto f_threshold = static_cast<float>(threshold);
  std::vector<uint8_t> seen(static_cast<size_t>(geometry_.num_cells()), 0);
  std::vector<int64_t> stack = {a->ix + static_cast<int64_t>(a->iy) * sx};
  seen[stack.back()] = 1;
  const int64_t target = b->ix + static_cast<int64_t>(b->iy) * sx;
  while (!stack.empty()) {
    const int64_t i = stack.back();
    stack.pop_back();
    if (i == target) return true;
    const int ix = static_cast<int>(i % sx);
    const int iy = static_cast<int>(i / sx);
    for (int k = 0; k < 8; ++k) {
      const CellIndex step = HeadingStep(k);
      const int nx = ix + step.ix, ny = iy + step.iy;
      if (nx < 0 || ny < 0 || nx >= sx || ny >= sy) continue;
      const int64_t j = nx + static_cast<int64_t>(ny) * sx;
      if (seen[j] || !allowed(nx, ny)) continue;
      if (directed && (refused[k][i] <= f_threshold || refused[k][j] <= f_threshold)) continue;
      seen[j] = 1;
      stack.push_back(j);
    }
  }
  return false;
}

int CostMap::ComponentOf(const Vector2& world_m) const {
  std::call_once(components_once_, [this] { ComputeComponents(); });
  const Vector2 g = ToGridCells(world_m);
  if (!(g.x() >= 0.0 && g.y() >= 0.0 && g.x() < geometry_.size_x && g.y() < geometry_.size_y)) {
    return -1;
  }
  return components_[static_cast<int>(g.x()) + static_cast<int64_t>(g.y()) * geometry_.size_x];
}

bool CostMap::MaybeConnected(const Vector2& a_world_m, const Vector2& b_world_m) const {
  const int a = ComponentOf(a_world_m);
  if (a < 0 || a != ComponentOf(b_world_m)) return false;
  return one_way_cells_ == 0 || DirectedReachable(a_world_m, b_world_m);
}

// Breadth-first search from a's cell over the passable cells (those of the components) by the
// steps the one-way cells allow. A step towards heading bin k is refused when a one-way cell
// refusing heading class k lies within the passability threshold (the inscribed radius less
// kInnerSlack) of either cell's centre: such a cell lies under the inscribed disc wherever the
// robot is in that cell, and a robot crossing from one cell into the other moves with a
// displacement of that class or of a neighbouring open quadrant, which that cell's bits refuse
// too. So a drivable path makes a route, and "unreachable" proves that none exists.
bool CostMap::DirectedReachable(const Vector2& a_world_m, const Vector2& b_world_m) const {
  const double inscribed = shapes_[0].inscribed_cells;
  if (inscribed <= 0.0) return true;  // with the origin outside the footprint: no proof
  const auto a = geometry_.IndexOf(a_world_m);
  const auto b = geometry_.IndexOf(b_world_m);
  if (!a || !b) return false;
  const int sx = geometry_.size_x;
  const int sy = geometry_.size_y;
  const float threshold = static_cast<float>(std::max(0.0, inscribed - kInnerSlack - 1e-3));
  std::array<const float*, 8> refused;
  for (int k = 0; k < 8; ++k) refused[k] = heading_block_distance_cells(k).data();
  const int64_t target = geometry_.LinearIndex(*b);
  std::vector<uint8_t> seen(static_cast<size_t>(geometry_.num_cells()), 0);
  std::vector<int64_t> stack = {geometry_.LinearIndex(*a)};
  seen[stack.back()] = 1;
  while (!stack.empty()) {
    const int64_t i = stack.back();
    stack.pop_back();
    if (i == target) return true;
    const int ix = static_cast<int>(i % sx);
    const int iy = static_cast<int>(i / sx);
    for (int k = 0; k < 8; ++k) {
      const CellIndex step = HeadingStep(k);
      const int nx = ix + step.ix, ny = iy + step.iy;
      if (nx < 0 || ny < 0 || nx >= sx || ny >= sy) continue;
      const int64_t j = nx + static_cast<int64_t>(ny) * sx;
      if (seen[j] || components_[j] < 0) continue;
      if (refused[k][i] <= threshold || refused[k][j] <= threshold) continue;
      seen[j] = 1;
      stack.push_back(j);
    }
  }
  return false;
}

}  // namespace cairn::planner
