#include "services/mapping/traversability.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <vector>

#include "common/check.h"
#include "common/layers.h"
#include "common/yaml_reader.h"
#include "services/mapping/ditch_detection.h"
#include <Eigen/Eigenvalues>

namespace cairn::mapping {
namespace {

using common::GridMap;
using common::Layer;

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// How far past a known cell the cost layer looks through unknown cells for the lowest ray bound:
// the cell on an edge is often mixed (part rim, part gap) and published unknown, its bound
// barely below the rim, while the rays show the drop a cell further.
constexpr double kUnseenDropReachM = 0.4;
int UnseenDropReachCells(double resolution_m) {
  return std::max(1, static_cast<int>(std::ceil(kUnseenDropReachM / resolution_m - 1e-9)));
}

// A ray bound this far below the lower level beside an unseen foot cell proves a gap there
// (within it: range noise on a ray that grazed the floor).
constexpr double kFootBoundNoise_m = 0.02;

// 4-neighbourhood: +x, -x, +y, -y (the seed's RIGHT, LEFT, UP, DOWN).
constexpr std::array<std::array<int, 2>, 4> kNeighbours{{{1, 0}, {-1, 0}, {0, 1}, {0, -1}}};
// The directed layer's heading bit of each of them (k * 45 deg counter-clockwise from +x).
constexpr std::array<int, 4> kNeighbourBit{0, 4, 2, 6};
// Unit vectors of the directed layer's heading bins.
constexpr double kDiag = 0.70710678118654752;
constexpr std::array<double, 8> kHeadingX{1, kDiag, 0, -kDiag, -1, -kDiag, 0, kDiag};
constexpr std::array<double, 8> kHeadingY{0, kDiag, 1, kDiag, 0, -kDiag, -1, -kDiag};
constexpr float kAllBlocked = layers::kAllHeadingsBlocked;
constexpr float kUnseenDrop = layers::kUnseenDrop;

CellRect Clip(const CellRect& r, int sx, int sy) {
  return {std::max(0, r.x0), std::max(0, r.y0), std::min(sx, r.x1), std::min(sy, r.y1)};
}

// Surface normal and roughness by PCA over the cells within the normal radius (grid_map's
// NormalVectorsFilter "area" method): fewer than 3 points or a degenerate spread gives the
// vertical normal, and cells on one line the slope along it.
struct NormalResult {
  Eigen::Vector3d normal{0.0, 0.0, 1.0};
  double roughness_m{0.0};
  int cells{0};      // known cells in the window
  bool line{false};  // on one line of the grid: the slope along it only
  // Standard error of the fitted gradient in its least constrained direction, from the scatter
  // of the heights about the plane (0 for a line or fewer than 4 cells).
  double gradient_error{0.0};
  double noise_m{0.0};  // the heights' scatter about the plane (n - 3 degrees of freedom)
};

NormalResult FitNormal(const float* h, int sx, int sy, int x, int y,
                       const std::vector<std::array<int, 2>>& offsets, double res) {
  NormalResult r;
  const double h0 = h[x + static_cast<int64_t>(y) * sx];
  double n = 0, sxx = 0, syy = 0, szz = 0, sxy = 0, sxz = 0, syz = 0, mx = 0, my = 0, mz = 0;
  for (const auto& o : offsets) {
    const int cx = x + o[0], cy = y + o[1];
    if (cx < 0 || cy < 0 || cx >= sx || cy >= sy) continue;
    const int64_t j = cx + static_cast<int64_t>(cy) * sx;
    const float hc = h[j];
    if (std::isnan(hc)) continue;
    const double px = o[0] * res, py = o[1] * res, pz = hc - h0;
    n += 1;
    mx += px;
    my += py;
    mz += pz;
    sxx += px * px;
    syy += py * py;
    szz += pz * pz;
    sxy += px * py;
    sxz += px * pz;
    syz += py * pz;
  }
  r.cells = static_cast<int>(n);
  if (n < 3) return r;
  mx /= n;
  my /= n;
  mz /= n;
  Eigen::Matrix3d c;
  c(0, 0) = sxx / n - mx * mx;
  c(1, 1) = syy / n - my * my;
  c(2, 2) = szz / n - mz * mz;
  c(0, 1) = c(1, 0) = sxy / n - mx * my;
  c(0, 2) = c(2, 0) = sxz / n - mx * mz;
  c(1, 2) = c(2, 1) = syz / n - my * mz;
  // Cells on one line of the grid (a lidar ring seen from afar crosses a ramp as a one-cell-wide
  // strip between unknown cells) fix the tilt along the line only. The 3-D fit would pass the
  // plane through the line vertically, and read a strip across a 5 degree ramp as a 90 degree
  // wall. Such a fit keeps the slope along the line (a lower bound of the true slope) instead.
  const double cxx = c(0, 0), cyy = c(1, 1), cxy = c(0, 1);
  const double half_trace = 0.5 * (cxx + cyy);
  const double spread = std::sqrt(std::max(0.0, 0.25 * (cxx - cyy) * (cxx - cyy) + cxy * cxy));
  const double minor_xy = half_trace - spread, major_xy = half_trace + spread;
  const double line_spread = 0.05 * res;  // m, across the line
  if (major_xy > 0 && minor_xy < line_spread * line_spread) {
    r.line = true;
    // Direction of the line: the major axis of the cells' horizontal spread.
    const double angle = 0.5 * std::atan2(2.0 * cxy, cxx - cyy);
    const double ux = std::cos(angle), uy = std::sin(angle);
    const double var_s = ux * ux * cxx + 2 * ux * uy * cxy + uy * uy * cyy;
    const double cov_sz = ux * c(0, 2) + uy * c(1, 2);
    if (!(var_s > 0)) return r;
    const double gradient = cov_sz / var_s;  // dz per m along the line
    const Eigen::Vector3d normal(-gradient * ux, -gradient * uy, 1.0);
    if (!normal.allFinite()) return r;
    r.normal = normal.normalized();
    r.roughness_m = std::sqrt(std::max(0.0, c(2, 2) - cov_sz * gradient));
    return r;
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
  eig.computeDirect(c);
  const Eigen::Vector3d ev = eig.eigenvalues();  // ascending
  // Collinear cells span no plane: keep the vertical normal.
  if (!(ev(1) > 1e-9 * std::max(ev(2), 1e-30))) return r;
  Eigen::Vector3d normal = eig.eigenvectors().col(0);
  if (normal.z() < 0) normal = -normal;
  if (!normal.allFinite() || normal.norm() < 0.5) return r;
  r.normal = normal.normalized();
  r.roughness_m = std::sqrt(std::max(0.0, ev(0)));
  // var(gradient) = sigma² / (n · spread) along the least spread direction, sigma² estimated
  // from the residual (n - 3 degrees of freedom).
  if (n > 3 && minor_xy > 0) {
    const double noise2 = std::max(0.0, ev(0)) * n / (n - 3);
    r.noise_m = std::sqrt(noise2);
    r.gradient_error = std::sqrt(noise2 / (n * minor_xy));
  }
  return r;
}

Layer& EnsureLayer(GridMap* map, const char* name) {
  if (!map->HasLayer(name)) return map->AddLayer(name);
  return map->at(name);
}

// Offsets of the normal window: every cell centre within the radius.
std::vector<std::array<int, 2>> NormalOffsets(double radius_m, double res) {
  const int rc = static_cast<int>(std::floor(radius_m / res + 1e-9));
  std::vector<std::array<int, 2>> offsets;
  const double r2 = radius_m * radius_m + 1e-12;
  for (int dy = -rc; dy <= rc; ++dy) {
    for (int dx = -rc; dx <= rc; ++dx) {
      if ((dx * dx + dy * dy) * res * res <= r2) offsets.push_back({dx, dy});
    }
  }
  return offsets;
}

// The windows of the plane fits.
struct NormalWindows {
  std::vector<std::array<int, 2>> narrow;  // normal_radius_m
  std::vector<std::array<int, 2>> wide;    // wide_normal_radius_m
  int min_cells{6};
  double max_gradient_error{0.0};
  double max_fit_noise_m{0.0};
};

// The layers of the first stage of ComputeGeometricLayers.
struct NormalLayers {
  float* slope;
  float* step;
  float* roughness;
  float* normal_x;
  float* normal_y;
};

// Normals, slope, roughness and the step layer of the cells of `rect`.
// The fit over the normal window, or over the wide window where that one cannot support a
// slope: too few cells, cells on one line, or heights too uncertain for the window's span
// (far or grazing ground seen by a few noisy rays; a 3 x 3 plane through cells with 1 cm of
// noise is off by about 1.2 deg, and a slope limit of 8 deg is crossed by noise alone). The
// scatter about the plane measures the noise: the published elevation is all the derived layers
// read, so the live map and a re-derivation from the stored base layers agree.
NormalResult FitSupported(const internal::TerrainView& view, const NormalWindows& windows,
                          double res, int x, int y) {
  const NormalResult narrow = FitNormal(view.h, view.sx, view.sy, x, y, windows.narrow, res);
  // Scatter above the sensor's noise is structure (a step, a block, a wall's foot), which the
  // narrow window must keep sharp; scatter at the noise level over a narrow span is noise.
  const bool noisy = narrow.gradient_error > windows.max_gradient_error &&
                     narrow.noise_m <= windows.max_fit_noise_m;
  const bool supported = narrow.cells >= windows.min_cells && !narrow.line && !noisy;
  if (supported || windows.wide.size() <= windows.narrow.size()) return narrow;
  const NormalResult wide = FitNormal(view.h, view.sx, view.sy, x, y, windows.wide, res);
  if (wide.cells < windows.min_cells || wide.line || wide.cells <= narrow.cells) return narrow;
  return wide;
}

void ComputeNormalLayers(const internal::TerrainView& view, const NormalWindows& windows,
                         double res, const CellRect& rect, const NormalLayers& out) {
  const int sx = view.sx;
  for (int y = rect.y0; y < rect.y1; ++y) {
    for (int x = rect.x0; x < rect.x1; ++x) {
      const int64_t i = x + static_cast<int64_t>(y) * sx;
      const float hc = view.h[i];
      if (std::isnan(hc)) {
        out.slope[i] = out.step[i] = out.roughness[i] = kNaN;
        out.normal_x[i] = out.normal_y[i] = kNaN;
        continue;
      }
      const NormalResult nr = FitSupported(view, windows, res, x, y);
      out.slope[i] = static_cast<float>(std::acos(std::clamp(nr.normal.z(), -1.0, 1.0)));
      out.roughness[i] = static_cast<float>(nr.roughness_m);
      out.normal_x[i] = static_cast<float>(nr.normal.x());
      out.normal_y[i] = static_cast<float>(nr.normal.y());
      float max_step = 0.f;
      for (const auto& d : kNeighbours) {
        const int cx = x + d[0], cy = y + d[1];
        if (!view.Inside(cx, cy)) continue;
        const float hn = view.H(cx, cy);
        if (!std::isnan(hn)) max_step = std::max(max_step, std::fabs(hn - hc));
      }
      out.step[i] = max_step;
    }
  }
}

// Rows holding a ditch cell (in or next to the rectangle), offset by one: the per-neighbour
// ditch checks are needed only on them and the rows next to them.
std::vector<uint8_t> DitchRows(const float* ddepth, int sx, int sy, const CellRect& rect) {
  std::vector<uint8_t> ditch_row(static_cast<size_t>(sy) + 2, 0);
  for (int y = std::max(0, rect.y0 - 1); y < std::min(sy, rect.y1 + 1); ++y) {
    const float* row = ddepth + static_cast<int64_t>(y) * sx;
    for (int x = std::max(0, rect.x0 - 1); x < std::min(sx, rect.x1 + 1); ++x) {
      if (!std::isnan(row[x])) {
        ditch_row[y + 1] = 1;
        break;
      }
    }
  }
  return ditch_row;
}

// 1 / limit, 0 for "no limit" (a zero limit makes any positive value lethal first).
double Inverse(double limit) { return std::isinf(limit) ? 0.0 : (limit > 0 ? 1.0 / limit : 0.0); }

// Share of a limit used by a measurement (values above the limit are caught as lethal first).
double Share(double value, double limit) {
  if (!(value > 0)) return 0.0;
  if (!(limit > 0)) return std::numeric_limits<double>::infinity();
  return std::isinf(limit) ? 0.0 : value / limit;
}

// One profile's cost rules over one map (traversability.h), their constants computed once.
// The rules below stop at the first that makes a cell lethal; until then `ratio` keeps the
// largest share of a limit in use.
class CostRules {
 public:
  CostRules(const GridMap& map, const common::RobotProfile& profile,
            const TraversabilityParams& params, const RobotContext& robot);

  // The cost of cell (x, y) and its directed mask (common/layers.h); `near_ditch`: a ditch lies
  // in its row or a row next to it.
  struct Verdict {
    float cost;
    float mask;
  };
  Verdict Judge(int x, int y, bool near_ditch) const;

 private:
  // The mask of a cell whose cost is `cost` and that no rule below made one-way.
  static Verdict Plain(float cost) {
    return {cost, std::isnan(cost) ? kNaN : (cost >= layers::kCostLethal ? kAllBlocked : 0.f)};
  }
  // The headings a slope of `s` (>= the stricter slope limit) refuses: uphill ones when s is
  // over the uphill limit, downhill ones when over the downhill one; kAllBlocked when it is over
  // both, over max_one_way_slope_rad, or without a direction.
  float SlopeMask(int64_t i, double s) const;
  // A lethal step or drop towards neighbour k: its heading bit when the edge is crossable the
  // other way, else kAllBlocked.
  float StepMask(int k, double rise) const;

  // Terrain using the share r of its most used limit: free up to free_fraction, then a whole
  // number in [1, graded_cost_max] (see common/layers.h).
  float Graded(double r) const {
    if (r <= ff_) return layers::kCostFree;
    const double raw = params_.graded_cost_max * (std::min(1.0, r) - ff_) / (1.0 - ff_);
    return static_cast<float>(std::clamp(std::round(raw), 1.0, std::max(1.0, graded_top_)));
  }
  float UnknownCellCost(int x, int y, int64_t i) const;
  // The slope, compensated by the IMU pitch when asked.
  double Slope(int64_t i) const;
  // All four neighbours known, no ditch nearby, no tilt: only the highest and the lowest
  // neighbour matter. False when the per-neighbour rules must decide.
  bool FastSteps(int64_t i, float hc, double* ratio) const;
  // The rules towards neighbour k: 0 when they leave the cell alone, else StepMask's value, or
  // kUnseenDrop from UnseenDropMask.
  float NeighbourMask(int x, int y, int64_t i, int k, float hc, double* ratio) const;
  bool StepLethal(int64_t i, int64_t j, int k, double rise, double* ratio) const;
  // Towards an unknown neighbour the rays looked into: kUnseenDrop when the ground there lies
  // too far below (a lower bound), else 0.
  float UnseenDropMask(int x, int y, int64_t i, int k, int64_t j, float hc, double* ratio) const;
  // True when a slope within the stricter slope limit could join cell i to cell jj (two cells
  // towards k, over one unseen cell) and their `rise`, once the part that each side's own
  // slope towards k explains is taken away (UnseenDropMask's foot rule).
  bool RampMayJoin(int x, int y, int64_t i, int k, int64_t jj, double rise) const;
  // A rise to the neighbour `cells` steps towards k, in the robot-levelled frame.
  double Tilted(int k, double rise, int cells = 1) const {
    return forward_m_[k] * cells * sp_ + rise * cp_;
  }

  const TraversabilityParams& params_;
  const float* h_;
  const float* slope_;
  const float* rough_;
  const float* nx_;
  const float* ny_;
  const float* ddepth_;
  const float* dwidth_;
  const float* bound_;
  int sx_, sy_;
  double tol_, max_slope_, max_slope_both_, slope_up_, slope_down_, up_limit_, down_limit_,
      rough_limit_, ditch_limit_;
  float unknown_value_;
  double ff_, graded_top_;
  double inv_slope_, inv_rough_, inv_up_, inv_down_;
  bool blind_;
  Eigen::Vector2d robot_cells_{0, 0};
  double blind_cells_{0};
  bool compensate_, exact_tilt_;
  double pitch_rad_, cp_, sp_, cos_heading_, sin_heading_;
  int reach_cells_;
  int bridged_cells_;  // the longest unseen run the profile spans (max_ditch_width_m)
  double res_m_;
  std::array<int64_t, 4> neighbour_offset_{};
  std::array<double, 4> forward_m_{};
};

CostRules::CostRules(const GridMap& map, const common::RobotProfile& profile,
                     const TraversabilityParams& params, const RobotContext& robot)
    : params_(params),
      h_(map.at(layers::kElevation).data()),
      slope_(map.at(layers::kSlope).data()),
      rough_(map.at(layers::kRoughness).data()),
      nx_(map.at(kNormalXLayer).data()),
      ny_(map.at(kNormalYLayer).data()),
      ddepth_(map.at(layers::kDitchDepth).data()),
      dwidth_(map.at(layers::kDitchWidth).data()),
      bound_(map.HasLayer(layers::kGroundBound) ? map.at(layers::kGroundBound).data() : nullptr),
      sx_(map.size_x()),
      sy_(map.size_y()),
      tol_(params.height_tolerance_m),
      max_slope_(std::min(profile.max_slope_up_rad, profile.max_slope_down_rad)),
      max_slope_both_(std::max(profile.max_slope_up_rad, profile.max_slope_down_rad)),
      slope_up_(profile.max_slope_up_rad),
      slope_down_(profile.max_slope_down_rad),
      up_limit_(profile.max_step_up_m),
      down_limit_(profile.max_step_down_m),
      rough_limit_(profile.max_roughness_m),
      ditch_limit_(profile.max_ditch_width_m),
      unknown_value_(params.unknown_is_lethal ? layers::kCostLethal : kNaN),
      ff_(params.free_fraction),
      graded_top_(std::min(99.0, std::floor(params.graded_cost_max))),
      inv_slope_(Inverse(max_slope_)),
      inv_rough_(Inverse(rough_limit_)),
      inv_up_(Inverse(up_limit_)),
      inv_down_(Inverse(down_limit_)),
      // Blind zone: a square around the robot's current position, strict bounds (seed 000).
      blind_(robot.xy_m.has_value() && params.blind_zone_half_size_m > 0),
      // IMU compensation: the robot's heading in the grid frame.
      compensate_(params.imu_pitch_compensation && robot.pitch_rad != 0.0),
      exact_tilt_(compensate_ && robot.yaw_rad.has_value()),
      pitch_rad_(robot.pitch_rad),
      cp_(std::cos(robot.pitch_rad)),
      sp_(std::sin(robot.pitch_rad)),
      reach_cells_(UnseenDropReachCells(map.resolution_m())),
      bridged_cells_(static_cast<int>(std::floor((ditch_limit_ + tol_) / map.resolution_m()))),
      res_m_(map.resolution_m()) {
  if (blind_) {
    robot_cells_ = map.geometry().ContinuousIndexOf(*robot.xy_m);
    blind_cells_ = params.blind_zone_half_size_m / map.resolution_m();
  }
  const double heading = robot.yaw_rad ? *robot.yaw_rad - map.geometry().origin.yaw_rad : 0.0;
  cos_heading_ = std::cos(heading);
  sin_heading_ = std::sin(heading);
  const double res = map.resolution_m();
  for (int k = 0; k < 4; ++k) {
    neighbour_offset_[k] = kNeighbours[k][0] + static_cast<int64_t>(kNeighbours[k][1]) * sx_;
    forward_m_[k] = (kNeighbours[k][0] * cos_heading_ + kNeighbours[k][1] * sin_heading_) * res;
  }
}

float CostRules::UnknownCellCost(int x, int y, int64_t i) const {
  const bool in_ditch = !std::isnan(ddepth_[i]);
  if (in_ditch && dwidth_[i] > ditch_limit_ + tol_) return layers::kCostLethal;
  // A ditch the robot can bridge: graded by the width it uses.
  if (in_ditch) return Graded(Share(dwidth_[i], ditch_limit_));
  if (blind_ && std::fabs(x + 0.5 - robot_cells_.x()) < blind_cells_ &&
      std::fabs(y + 0.5 - robot_cells_.y()) < blind_cells_) {
    return layers::kCostFree;
  }
  return unknown_value_;
}

double CostRules::Slope(int64_t i) const {
  double s = slope_[i];
  if (!compensate_) return s;
  if (!exact_tilt_) return std::max(0.0, s + pitch_rad_);
  const double nzc =
      std::sqrt(std::max(0.0, 1.0 - double(nx_[i]) * nx_[i] - double(ny_[i]) * ny_[i]));
  const double nh = nx_[i] * cos_heading_ + ny_[i] * sin_heading_;
  const double nz_world = nh * sp_ + nzc * cp_;
  return std::acos(std::clamp(std::fabs(nz_world), 0.0, 1.0));
}

bool CostRules::FastSteps(int64_t i, float hc, double* ratio) const {
  const float a = h_[i + neighbour_offset_[0]], b = h_[i + neighbour_offset_[1]];
  const float c = h_[i + neighbour_offset_[2]], d = h_[i + neighbour_offset_[3]];
  if (std::isnan(a) || std::isnan(b) || std::isnan(c) || std::isnan(d)) return false;
  const double up = double(std::max(std::max(a, b), std::max(c, d))) - hc;
  const double down = hc - double(std::min(std::min(a, b), std::min(c, d)));
  // A limit exceeded: the per-neighbour rules decide (edge length).
  if (!(up <= up_limit_ + tol_ && down <= down_limit_ + tol_)) return false;
  *ratio = std::max({*ratio, up > 0 ? up * inv_up_ : 0.0, down > 0 ? down * inv_down_ : 0.0});
  return true;
}

bool CostRules::StepLethal(int64_t i, int64_t j, int k, double rise, double* ratio) const {
  if (!(rise > up_limit_ + tol_ || -rise > down_limit_ + tol_)) {
    *ratio = std::max(*ratio, rise > 0 ? rise * inv_up_ : -rise * inv_down_);
    return false;
  }
  // The same edge one cell to either side must exceed the limit too (see
  // min_step_edge_cells); otherwise the pair counts as a step at the limit.
  bool supported = params_.min_step_edge_cells <= 1;
  const int64_t side = kNeighbours[k][1] + static_cast<int64_t>(kNeighbours[k][0]) * sx_;
  for (const int64_t s : {side, -side}) {
    if (supported) break;
    const float hs = h_[i + s], hn_s = h_[j + s];
    if (std::isnan(hs) || std::isnan(hn_s)) continue;
    double rise_s = double(hn_s) - hs;
    if (exact_tilt_) rise_s = Tilted(k, rise_s);
    supported = rise > 0 ? rise_s > up_limit_ + tol_ : -rise_s > down_limit_ + tol_;
  }
  if (supported) return true;
  *ratio = std::max(*ratio, 1.0);
  return false;
}

bool CostRules::RampMayJoin(int x, int y, int64_t i, int k, int64_t jj, double rise) const {
  // What a slope at the stricter slope limit rises over one cell.
  const double per_cell = std::tan(std::min(max_slope_, 1.4)) * res_m_;
  // Each side's rise over its own outer neighbour (0 where that is unknown or outside the map),
  // at most per_cell: the sides carried towards the unseen cell explain that much of the rise.
  const auto side = [per_cell](double inner, double outer) {
    return std::isnan(outer) ? 0.0 : std::clamp(inner - outer, -per_cell, per_cell);
  };
  double explained = side(h_[i], h_[i - neighbour_offset_[k]]);
  const int ox = x + 3 * kNeighbours[k][0], oy = y + 3 * kNeighbours[k][1];
  if (ox >= 0 && oy >= 0 && ox < sx_ && oy < sy_) {
    explained += side(h_[jj + neighbour_offset_[k]], h_[jj]);
  }
  // Only a slope the same way explains part of the rise; what is left must fit a slope over
  // the two cells between the centres.
  const double left =
      rise > 0 ? std::clamp(rise - explained, 0.0, rise) : std::clamp(rise - explained, rise, 0.0);
  return std::fabs(left) <= 2.0 * per_cell;
}

float CostRules::UnseenDropMask(int x, int y, int64_t i, int k, int64_t j, float hc,
                                double* ratio) const {
  // The sensor looked into this neighbour and found nothing down to bound[j], nor in the
  // unknown cells beyond it down to theirs.
  float lowest = bound_[j];
  for (int s = 2; s <= reach_cells_; ++s) {
    const int nx = x + s * kNeighbours[k][0], ny = y + s * kNeighbours[k][1];
    if (nx < 0 || ny < 0 || nx >= sx_ || ny >= sy_) break;
    const int64_t jj = nx + static_cast<int64_t>(ny) * sx_;
    if (!std::isnan(h_[jj])) {
      // Known ground past an unseen run the profile bridges (the ditch rule: its wheels span
      // the run whatever lies below): the crossing is a step from here to that ground. The
      // foot of a step face seen from below is such a run: its cell mixes face and floor
      // returns and is published unknown.
      if (s - 1 <= bridged_cells_) {
        double rise = double(h_[jj]) - hc;
        if (exact_tilt_) rise = Tilted(k, rise, s);
        return StepLethal(i, jj, k, rise, ratio) ? StepMask(k, rise) : 0.f;
      }
      // One unseen cell between two levels, and no ray passed below the lower one: the foot
      // of a face, hidden by its rim from above and mixed with the face from below. Unless a
      // slope the profile drives could join the two levels there (a ramp whose cell the rings
      // skipped rises as much over two cells), the crossing is the step between the two
      // levels (one-way when it is within one limit). A drop beyond both limits is left to
      // the rule below: the rays may prove it deeper.
      if (s == 2) {
        double rise = double(h_[jj]) - hc;
        const double lower = std::min<double>(hc, h_[jj]);
        if (!(bound_[j] < lower - kFootBoundNoise_m) &&
            (rise > 0 || -rise <= std::max(up_limit_, down_limit_) + tol_) &&
            !RampMayJoin(x, y, i, k, jj, rise)) {
          if (exact_tilt_) rise = Tilted(k, rise, s);
          return StepLethal(i, jj, k, rise, ratio) ? StepMask(k, rise) : 0.f;
        }
      }
      break;
    }
    if (std::isfinite(bound_[jj])) lowest = std::min(lowest, bound_[jj]);
  }
  double drop = double(hc) - lowest;
  if (exact_tilt_) drop = drop * cp_ - forward_m_[k] * sp_;
  // Deeper than the step-down limit already: blocked whatever lies below.
  if (drop > down_limit_ + tol_) return kAllBlocked;
  // Its depth is only a lower bound: blocked until seen, but worth a closer look.
  if (params_.unseen_drop_m > 0 && drop >= params_.unseen_drop_m - tol_) return kUnseenDrop;
  if (drop > 0) *ratio = std::max(*ratio, drop * inv_down_);
  return 0.f;
}

float CostRules::NeighbourMask(int x, int y, int64_t i, int k, float hc, double* ratio) const {
  const int64_t j = i + neighbour_offset_[k];
  // A bridged ditch is no step: the robot spans it.
  if (!std::isnan(ddepth_[j]) && !(dwidth_[j] > ditch_limit_ + tol_)) return 0.f;
  const float hn = h_[j];
  if (!std::isnan(hn)) {
    double rise = double(hn) - hc;
    // In a robot-levelled map the neighbour offset is tilted by the pitch as well.
    if (exact_tilt_) rise = Tilted(k, rise);
    return StepLethal(i, j, k, rise, ratio) ? StepMask(k, rise) : 0.f;
  }
  if (bound_ != nullptr && std::isfinite(bound_[j])) {
    return UnseenDropMask(x, y, i, k, j, hc, ratio);
  }
  return 0.f;
}

float CostRules::SlopeMask(int64_t i, double s) const {
  if (compensate_ || s >= max_slope_both_ || s >= params_.max_one_way_slope_rad) {
    return kAllBlocked;
  }
  // Uphill is against the normal's horizontal component.
  const double gx = -nx_[i], gy = -ny_[i];
  const double g = std::hypot(gx, gy);
  if (!(g > 1e-9)) return kAllBlocked;
  unsigned mask = 0;
  for (int b = 0; b < layers::kHeadingBins; ++b) {
    const double along = (kHeadingX[b] * gx + kHeadingY[b] * gy) / g;
    if ((along > 1e-6 && s >= slope_up_) || (along < -1e-6 && s >= slope_down_)) mask |= 1u << b;
  }
  return mask == 0 ? kAllBlocked : static_cast<float>(mask);
}

float CostRules::StepMask(int k, double rise) const {
  // Crossable the other way: up it when it is a drop within the step-up limit, down it when it
  // is a rise within the step-down limit.
  const bool other_way = rise > 0 ? rise <= down_limit_ + tol_ : -rise <= up_limit_ + tol_;
  return other_way ? static_cast<float>(1u << kNeighbourBit[k]) : kAllBlocked;
}

CostRules::Verdict CostRules::Judge(int x, int y, bool near_ditch) const {
  const int64_t i = x + static_cast<int64_t>(y) * sx_;
  const float hc = h_[i];
  if (std::isnan(hc)) return Plain(UnknownCellCost(x, y, i));
  // A known cell at the map border cannot be judged against all its neighbours.
  if (x == 0 || y == 0 || x == sx_ - 1 || y == sy_ - 1) return Plain(unknown_value_);
  if (!std::isnan(ddepth_[i])) {
    // A ditch's bottom: lethal when too wide, else the robot bridges it (its wheels never
    // touch it).
    if (dwidth_[i] > ditch_limit_ + tol_) return Plain(layers::kCostLethal);
    return Plain(Graded(Share(dwidth_[i], ditch_limit_)));
  }
  if (rough_[i] > rough_limit_ + tol_) return Plain(layers::kCostLethal);
  const double s = Slope(i);
  unsigned mask = 0;
  if (s >= max_slope_) {
    const float m = SlopeMask(i, s);
    if (m == kAllBlocked) return Plain(layers::kCostLethal);
    mask = static_cast<unsigned>(m);
  }
  double ratio = std::max(s * inv_slope_, rough_[i] > 0 ? rough_[i] * inv_rough_ : 0.0);
  // Steps to the 4-neighbours, inclusive bounds.
  if (!near_ditch && !exact_tilt_ && FastSteps(i, hc, &ratio)) {
    if (mask != 0) return {layers::kCostLethal, static_cast<float>(mask)};
    return Plain(Graded(ratio));
  }
  bool unseen_drop = false;
  for (int k = 0; k < 4; ++k) {
    const float m = NeighbourMask(x, y, i, k, hc, &ratio);
    if (m == 0.f) continue;
    if (m == kAllBlocked) return Plain(layers::kCostLethal);
    if (m == kUnseenDrop) {
      unseen_drop = true;
      continue;
    }
    mask |= static_cast<unsigned>(m);
  }
  // Blocked every way until the ground beyond is seen; a planner may look (common/layers.h).
  if (unseen_drop) return {layers::kCostLethal, kUnseenDrop};
  if (mask != 0) return {layers::kCostLethal, static_cast<float>(mask)};
  return Plain(Graded(ratio));
}

}  // namespace

void TraversabilityParams::Validate() const {
  CAIRN_THROW_UNLESS(std::isfinite(normal_radius_m) && normal_radius_m > 0,
                     "normal_radius_m must be positive, got " << normal_radius_m);
  CAIRN_THROW_UNLESS(std::isfinite(wide_normal_radius_m) && wide_normal_radius_m >= 0,
                     "wide_normal_radius_m must be >= 0, got " << wide_normal_radius_m);
  CAIRN_THROW_UNLESS(min_normal_cells >= 3,
                     "min_normal_cells must be at least 3, got " << min_normal_cells);
  CAIRN_THROW_UNLESS(std::isfinite(max_fit_noise_m) && max_fit_noise_m >= 0,
                     "max_fit_noise_m must be >= 0, got " << max_fit_noise_m);
  CAIRN_THROW_UNLESS(max_slope_error_rad > 0 && max_slope_error_rad < 0.5,
                     "max_slope_error_rad must be in (0, 0.5), got " << max_slope_error_rad);
  CAIRN_THROW_UNLESS(std::isfinite(blind_zone_half_size_m) && blind_zone_half_size_m >= 0,
                     "blind_zone_half_size_m must be >= 0, got " << blind_zone_half_size_m);
  CAIRN_THROW_UNLESS(graded_cost_max > 0 && graded_cost_max < 100,
                     "graded_cost_max must be in (0, 100), got " << graded_cost_max);
  CAIRN_THROW_UNLESS(free_fraction >= 0 && free_fraction < 1,
                     "free_fraction must be in [0, 1), got " << free_fraction);
  CAIRN_THROW_UNLESS(std::isfinite(min_ditch_depth_m) && min_ditch_depth_m > 0,
                     "min_ditch_depth_m must be positive, got " << min_ditch_depth_m);
  CAIRN_THROW_UNLESS(
      min_ditch_wall_slope_rad >= 0 && min_ditch_wall_slope_rad < 1.5,
      "min_ditch_wall_slope_rad must be in [0, 1.5), got " << min_ditch_wall_slope_rad);
  CAIRN_THROW_UNLESS(std::isfinite(max_ditch_search_m) && max_ditch_search_m > 0,
                     "max_ditch_search_m must be positive, got " << max_ditch_search_m);
  CAIRN_THROW_UNLESS(max_one_way_slope_rad >= 0 && max_one_way_slope_rad <= 1.5708,
                     "max_one_way_slope_rad must be in [0, pi/2], got " << max_one_way_slope_rad);
  CAIRN_THROW_UNLESS(std::isfinite(unseen_drop_m) && unseen_drop_m >= 0,
                     "unseen_drop_m must be >= 0, got " << unseen_drop_m);
  CAIRN_THROW_UNLESS(height_tolerance_m >= 0 && height_tolerance_m < 0.01,
                     "height_tolerance_m must be in [0, 0.01), got " << height_tolerance_m);
  CAIRN_THROW_UNLESS(min_step_edge_cells == 1 || min_step_edge_cells == 2,
                     "min_step_edge_cells must be 1 or 2, got " << min_step_edge_cells);
}

int DependencyRadiusCells(const TraversabilityParams& params, double resolution_m) {
  const int normal = static_cast<int>(
      std::ceil(std::max(params.normal_radius_m, params.wide_normal_radius_m) / resolution_m));
  // Known ditch bottoms look up to K cells for an unseen ditch cell, which looks K further for
  // its rims and two beyond them; the cost layer reads the 4-neighbours of each cell and the
  // unknown cells beyond them (CostRadiusCells).
  return std::max(normal, 2 * internal::DitchSearchCells(params, resolution_m) + 2) +
         CostRadiusCells(resolution_m);
}

// The unknown cells within UnseenDropReachCells, and the known cell past the far side of an
// unseen foot (CostRules::RampMayJoin).
int CostRadiusCells(double resolution_m) { return UnseenDropReachCells(resolution_m) + 1; }

void ComputeGeometricLayers(GridMap* map, const TraversabilityParams& params) {
  CAIRN_THROW_UNLESS(map != nullptr, "no map");
  ComputeGeometricLayers(map, params, CellRect::All(*map));
}

void ComputeGeometricLayers(GridMap* map, const TraversabilityParams& params,
                            const CellRect& rect_in) {
  CAIRN_THROW_UNLESS(map != nullptr, "no map");
  CAIRN_THROW_UNLESS(map->HasLayer(layers::kElevation),
                     "the map has no '" << layers::kElevation << "' layer");
  params.Validate();
  const int sx = map->size_x(), sy = map->size_y();
  const double res = map->resolution_m();
  const CellRect rect = Clip(rect_in, sx, sy);
  NormalLayers out;
  out.slope = EnsureLayer(map, layers::kSlope).data();
  out.step = EnsureLayer(map, layers::kStepMax).data();
  out.roughness = EnsureLayer(map, layers::kRoughness).data();
  out.normal_x = EnsureLayer(map, kNormalXLayer).data();
  out.normal_y = EnsureLayer(map, kNormalYLayer).data();
  float* ditch_depth = EnsureLayer(map, layers::kDitchDepth).data();
  float* ditch_width = EnsureLayer(map, layers::kDitchWidth).data();
  if (rect.empty()) return;
  const float* bound =
      map->HasLayer(layers::kGroundBound) ? map->at(layers::kGroundBound).data() : nullptr;
  const internal::TerrainView view{map->at(layers::kElevation).data(), bound, sx, sy};
  NormalWindows windows;
  windows.narrow = NormalOffsets(params.normal_radius_m, res);
  windows.wide = NormalOffsets(std::max(params.normal_radius_m, params.wide_normal_radius_m), res);
  windows.min_cells = std::min(params.min_normal_cells, static_cast<int>(windows.narrow.size()));
  windows.max_gradient_error = std::tan(params.max_slope_error_rad);
  windows.max_fit_noise_m = params.max_fit_noise_m;
  ComputeNormalLayers(view, windows, res, rect, out);
  internal::ComputeDitchLayers(view, params, res, rect, ditch_depth, ditch_width);
}

void ComputeCostLayer(GridMap* map, const common::RobotProfile& profile,
                      const TraversabilityParams& params, std::optional<common::Vector2> robot_xy_m,
                      double robot_pitch_rad) {
  CAIRN_THROW_UNLESS(map != nullptr, "no map");
  if (!map->HasLayer(layers::kSlope) || !map->HasLayer(layers::kDitchDepth) ||
      !map->HasLayer(kNormalXLayer)) {
    ComputeGeometricLayers(map, params);
  }
  RobotContext robot;
  robot.xy_m = robot_xy_m;
  robot.pitch_rad = robot_pitch_rad;
  ComputeCostLayer(map, profile, params, robot, CellRect::All(*map));
}

void ComputeCostLayer(GridMap* map, const common::RobotProfile& profile,
                      const TraversabilityParams& params, const RobotContext& robot,
                      const CellRect& rect_in) {
  CAIRN_THROW_UNLESS(map != nullptr, "no map");
  profile.Validate();
  params.Validate();
  for (const char* name :
       {layers::kElevation, layers::kSlope, layers::kRoughness, layers::kDitchDepth,
        layers::kDitchWidth, kNormalXLayer, kNormalYLayer}) {
    CAIRN_THROW_UNLESS(map->HasLayer(name), "the map has no '" << name << "' layer");
  }
  const int sx = map->size_x(), sy = map->size_y();
  const CellRect rect = Clip(rect_in, sx, sy);
  const std::string cost_name = layers::CostLayer(profile.name);
  const std::string directed_name = layers::DirectedLayer(profile.name);
  if (!map->HasLayer(cost_name)) map->AddLayer(cost_name);
  if (!map->HasLayer(directed_name)) map->AddLayer(directed_name);
  float* cost = map->at(cost_name).data();
  float* directed = map->at(directed_name).data();
  if (rect.empty()) return;
  const CostRules rules(*map, profile, params, robot);
  const std::vector<uint8_t> ditch_row =
      DitchRows(map->at(layers::kDitchDepth).data(), sx, sy, rect);
  for (int y = rect.y0; y < rect.y1; ++y) {
    const bool near_ditch = ditch_row[y] || ditch_row[y + 1] || ditch_row[y + 2];
    for (int x = rect.x0; x < rect.x1; ++x) {
      const auto verdict = rules.Judge(x, y, near_ditch);
      cost[x + static_cast<int64_t>(y) * sx] = verdict.cost;
      directed[x + static_cast<int64_t>(y) * sx] = verdict.mask;
    }
  }
}

TraversabilityParams LoadTraversabilityParams(common::YamlMap& m) {
  TraversabilityParams p;
  m.Get("normal_radius_m", &p.normal_radius_m);
  m.Get("wide_normal_radius_m", &p.wide_normal_radius_m);
  m.Get("min_normal_cells", &p.min_normal_cells);
  m.Get("max_slope_error_rad", &p.max_slope_error_rad);
  m.Get("max_fit_noise_m", &p.max_fit_noise_m);
  m.Get("blind_zone_half_size_m", &p.blind_zone_half_size_m);
  m.Get("imu_pitch_compensation", &p.imu_pitch_compensation);
  m.Get("unknown_is_lethal", &p.unknown_is_lethal);
  m.Get("graded_cost_max", &p.graded_cost_max);
  m.Get("free_fraction", &p.free_fraction);
  m.Get("min_ditch_depth_m", &p.min_ditch_depth_m);
  m.Get("unseen_drop_m", &p.unseen_drop_m);
  m.Get("max_one_way_slope_rad", &p.max_one_way_slope_rad);
  m.Get("max_ditch_search_m", &p.max_ditch_search_m);
  m.Get("min_ditch_wall_slope_rad", &p.min_ditch_wall_slope_rad);
  m.Get("height_tolerance_m", &p.height_tolerance_m);
  m.Get("min_step_edge_cells", &p.min_step_edge_cells);
  m.Finish();
  return p;
}

}  // namespace cairn::mapping
