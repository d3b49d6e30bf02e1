#include "services/explore/scan_features.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "services/explore/field_checks.h"
#include <Eigen/Geometry>

namespace cairn::explore {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();
// d_xy below this is clamped in H (a point straight above or below the scanner centre).
constexpr double kMinHorizontalDistanceM = 1e-3;
// Largest local-ground grid side (cells): 60 m at 0.5 m is 240.
constexpr double kMaxGroundGridSide = 8192;

using internal::Fail;
using internal::Require;

bool FiniteNonNegative(double v) { return std::isfinite(v) && v >= 0.0; }
bool FinitePositive(double v) { return std::isfinite(v) && v > 0.0; }
bool ValidAngle(double theta_rad) {
  return std::isfinite(theta_rad) && theta_rad > 0.0 && theta_rad < 0.5 * M_PI;
}

float Clamp01(float v) { return std::min(1.f, std::max(0.f, v)); }

// The hot-loop forms of the public formulas, without argument checks.
struct Formulas {
  float cos_theta;
  float inv_one_minus_cos;  // 1 / (1 - cos θ)
  float k;
  float tan_theta;
  float tan_descent;  // below the base (dz < 0)
  float a_max;
  float w_a, w_n, inv_w_norm;

  float Slope(float n_z) const {
    return 1.f / (1.f + std::exp(-k * (n_z - cos_theta) * inv_one_minus_cos));
  }
  float Height(float dz, float d_xy) const {
    return std::exp(-std::fabs(dz) / (std::max(d_xy, static_cast<float>(kMinHorizontalDistanceM)) *
                                      (dz < 0.f ? tan_descent : tan_theta)));
  }
  float Quality(float par, float d_i) const {
    const float d_a = par <= a_max ? 1.f : a_max / par;
    const float x = w_a * d_a, y = w_n * d_i;
    return std::min(1.f, std::sqrt(x * x + y * y) * inv_w_norm);
  }
};

// Union-find over rejected triangles, union by the smaller index (deterministic roots).
int32_t Find(std::vector<int32_t>& parent, int32_t x) {
  while (parent[x] != x) {
    parent[x] = parent[parent[x]];
    x = parent[x];
  }
  return x;
}

void Unite(std::vector<int32_t>& parent, int32_t a, int32_t b) {
  a = Find(parent, a);
  b = Find(parent, b);
  if (a == b) return;
  if (a < b) {
    parent[b] = a;
  } else {
    parent[a] = b;
  }
}

void CheckMesh(const OrderedScan& scan, const ScanMesh& mesh) {
  const size_t n = static_cast<size_t>(scan.size());
  Require(mesh.area_per_point_m2.size() == n, "ScanMesh.area_per_point_m2",
          "must have one entry per scan point", mesh.area_per_point_m2.size());
  Require(mesh.normals.size() == n, "ScanMesh.normals", "must have one entry per scan point",
          mesh.normals.size());
  Require(mesh.neighbour_offsets.size() == n + 1, "ScanMesh.neighbour_offsets",
          "must have scan.size() + 1 entries", mesh.neighbour_offsets.size());
  Require(mesh.neighbour_offsets[0] == 0, "ScanMesh.neighbour_offsets", "must start at 0",
          mesh.neighbour_offsets[0]);
  for (size_t i = 0; i < n; ++i) {
    Require(mesh.neighbour_offsets[i + 1] >= mesh.neighbour_offsets[i],
            "ScanMesh.neighbour_offsets", "must not decrease", mesh.neighbour_offsets[i + 1]);
  }
  Require(static_cast<size_t>(mesh.neighbour_offsets[n]) == mesh.neighbours.size(),
          "ScanMesh.neighbour_offsets", "must end at neighbours.size()", mesh.neighbour_offsets[n]);
  for (int32_t q : mesh.neighbours) {
    Require(q >= 0 && static_cast<size_t>(q) < n, "ScanMesh.neighbours",
            "must be indices of scan points", q);
  }
}

}  // namespace

void ScanAnalysisParams::Validate() const {
  Require(ValidAngle(max_slope_rad), "ScanAnalysisParams.max_slope_rad", "must be in (0, pi/2)",
          max_slope_rad);
  Require(max_descent_rad == 0.0 || ValidAngle(max_descent_rad),
          "ScanAnalysisParams.max_descent_rad", "must be 0 or in (0, pi/2)", max_descent_rad);
  Require(FinitePositive(slope_steepness), "ScanAnalysisParams.slope_steepness", "must be > 0",
          slope_steepness);
  Require(FiniteNonNegative(w_l), "ScanAnalysisParams.w_l", "must be >= 0", w_l);
  Require(FiniteNonNegative(w_g), "ScanAnalysisParams.w_g", "must be >= 0", w_g);
  Require(FiniteNonNegative(w_bl), "ScanAnalysisParams.w_bl", "must be >= 0", w_bl);
  Require(FiniteNonNegative(w_bg), "ScanAnalysisParams.w_bg", "must be >= 0", w_bg);
  Require(FinitePositive(obstacle_band_m), "ScanAnalysisParams.obstacle_band_m", "must be > 0",
          obstacle_band_m);
  Require(FinitePositive(ground_cell_m), "ScanAnalysisParams.ground_cell_m", "must be > 0",
          ground_cell_m);
  Require(FinitePositive(ground_grid_radius_m), "ScanAnalysisParams.ground_grid_radius_m",
          "must be > 0", ground_grid_radius_m);
  Require(2.0 * std::ceil(ground_grid_radius_m / ground_cell_m) <= kMaxGroundGridSide,
          "ScanAnalysisParams.ground_cell_m",
          "must be at least ground_grid_radius_m / 4096 (grid too large)", ground_cell_m);
  Require(FinitePositive(a_max_m2), "ScanAnalysisParams.a_max_m2", "must be > 0", a_max_m2);
  Require(FiniteNonNegative(w_a), "ScanAnalysisParams.w_a", "must be >= 0", w_a);
  Require(FiniteNonNegative(w_n), "ScanAnalysisParams.w_n", "must be >= 0", w_n);
  Require(w_a + w_n > 0.0, "ScanAnalysisParams.w_a", "and w_n must not both be 0", w_a);
  Require(FiniteNonNegative(min_zone_area_m2), "ScanAnalysisParams.min_zone_area_m2",
          "must be >= 0", min_zone_area_m2);
}

double SlopeTerm(double n_z, double theta_rad, double k) {
  Require(std::isfinite(n_z) && n_z >= -1.0 && n_z <= 1.0, "SlopeTerm n_z", "must be in [-1, 1]",
          n_z);
  Require(ValidAngle(theta_rad), "SlopeTerm theta_rad", "must be in (0, pi/2)", theta_rad);
  Require(FinitePositive(k), "SlopeTerm k", "must be > 0", k);
  const double c = std::cos(theta_rad);
  return 1.0 / (1.0 + std::exp(-k * (n_z - c) / (1.0 - c)));
}

double HeightTerm(double dz_m, double d_xy_m, double theta_rad) {
  Require(std::isfinite(dz_m), "HeightTerm dz_m", "must be finite", dz_m);
  Require(FiniteNonNegative(d_xy_m), "HeightTerm d_xy_m", "must be >= 0", d_xy_m);
  Require(ValidAngle(theta_rad), "HeightTerm theta_rad", "must be in (0, pi/2)", theta_rad);
  return std::exp(-std::fabs(dz_m) /
                  (std::max(d_xy_m, kMinHorizontalDistanceM) * std::tan(theta_rad)));
}

double AreaQuality(double par_m2, double a_max_m2) {
  Require(FiniteNonNegative(par_m2), "AreaQuality par_m2", "must be >= 0", par_m2);
  Require(FinitePositive(a_max_m2), "AreaQuality a_max_m2", "must be > 0", a_max_m2);
  return par_m2 <= a_max_m2 ? 1.0 : a_max_m2 / par_m2;
}

double CombinedQuality(double d_a, double d_i, double w_a, double w_n) {
  Require(std::isfinite(d_a) && d_a >= 0.0 && d_a <= 1.0, "CombinedQuality d_a",
          "must be in [0, 1]", d_a);
  Require(std::isfinite(d_i) && d_i >= 0.0 && d_i <= 1.0, "CombinedQuality d_i",
          "must be in [0, 1]", d_i);
  Require(FiniteNonNegative(w_a), "CombinedQuality w_a", "must be >= 0", w_a);
  Require(FiniteNonNegative(w_n), "CombinedQuality w_n", "must be >= 0", w_n);
  Require(w_a + w_n > 0.0, "CombinedQuality w_a", "and w_n must not both be 0", w_a);
  return std::min(1.0, std::hypot(w_a * d_a, w_n * d_i) / std::hypot(w_a, w_n));
}

ScanFeatures AnalyseScan(const OrderedScan& scan, const ScanMesh& mesh,
                         const ScanAnalysisParams& params) {
  scan.Validate();
  params.Validate();
  CheckMesh(scan, mesh);
  const int n = scan.size();
  const int beams = scan.beams_per_line;
  const Eigen::Vector3f* pts = scan.points_m.data();
  const Eigen::Vector3f* normals = mesh.normals.data();
  const float* par = mesh.area_per_point_m2.data();
  const int32_t* offsets = mesh.neighbour_offsets.data();
  const int32_t* nbrs = mesh.neighbours.data();
  const Eigen::Vector3f origin = scan.sensor_origin_m;
  const float base_z = scan.robot_base_z_m;

  const double c = std::cos(params.max_slope_rad);
  Formulas f;
  f.cos_theta = static_cast<float>(c);
  f.inv_one_minus_cos = static_cast<float>(1.0 / (1.0 - c));
  f.k = static_cast<float>(params.slope_steepness);
  f.tan_theta = static_cast<float>(std::tan(params.max_slope_rad));
  f.tan_descent = params.max_descent_rad > 0.0
                      ? static_cast<float>(std::tan(params.max_descent_rad))
                      : f.tan_theta;
  f.a_max = static_cast<float>(params.a_max_m2);
  f.w_a = static_cast<float>(params.w_a);
  f.w_n = static_cast<float>(params.w_n);
  f.inv_w_norm = static_cast<float>(1.0 / std::hypot(params.w_a, params.w_n));
  const float w_l = static_cast<float>(params.w_l), w_g = static_cast<float>(params.w_g);
  const float w_bl = static_cast<float>(params.w_bl), w_bg = static_cast<float>(params.w_bg);
  const float band = static_cast<float>(params.obstacle_band_m);

  // Local-ground grid centred on the scanner: side cells of ground_cell_m, +inf = no ground.
  const int half = static_cast<int>(std::ceil(params.ground_grid_radius_m / params.ground_cell_m));
  const int side = 2 * half;
  const float cell = static_cast<float>(params.ground_cell_m);
  const float inv_cell = 1.f / cell;
  const float grid_min = -static_cast<float>(half) * cell;
  std::vector<float> ground(static_cast<size_t>(side) * side, kInf);
  auto cell_of = [&](float dx, float dy, int* cx, int* cy) {
    *cx = static_cast<int>(std::floor((dx - grid_min) * inv_cell));
    *cy = static_cast<int>(std::floor((dy - grid_min) * inv_cell));
    return *cx >= 0 && *cy >= 0 && *cx < side && *cy < side;
  };

  ScanFeatures out;
  out.navigability.assign(n, kNaN);
  out.obstacle.assign(n, kNaN);
  out.quality.assign(n, kNaN);
  std::vector<float> fpl(n, 0.f);    // F_pl; 0 for invalid points
  std::vector<float> bl(n, 0.f);     // pass 1: |N_xy| |r̂ · N|; pass 2: B_l
  std::vector<float> dxy(n, 0.f);    // d_xy
  std::vector<uint8_t> state(n, 0);  // 0 invalid, 1 valid, 2 valid and in the obstacle band

  // Pass 1: local terms, quality and the ground grid.
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3f& p = pts[i];
    const Eigen::Vector3f& nrm = normals[i];
    if (!(std::isfinite(p.x()) && std::isfinite(p.y()) && std::isfinite(p.z()) &&
          std::isfinite(nrm.x()) && std::isfinite(nrm.y()) && std::isfinite(nrm.z()))) {
      continue;
    }
    state[i] = 1;
    const Eigen::Vector3f ray = p - origin;
    const float d_xy = std::sqrt(ray.x() * ray.x() + ray.y() * ray.y());
    const float range = ray.norm();
    const float pz = p.z() - base_z;
    const bool reachable = pz <= d_xy * f.tan_theta;
    const float n_z = std::min(1.f, std::max(-1.f, nrm.z()));
    const float s = f.Slope(n_z);
    fpl[i] = reachable ? s * f.Height(pz, d_xy) : 0.f;
    const float incidence = range > 0.f ? std::min(1.f, std::fabs(ray.dot(nrm)) / range) : 0.f;
    const float n_xy = std::sqrt(nrm.x() * nrm.x() + nrm.y() * nrm.y());
    bl[i] = n_xy * incidence;
    dxy[i] = d_xy;
    const float a = std::isfinite(par[i]) ? par[i] : 0.f;
    out.quality[i] = f.Quality(a, incidence);
    int cx = 0, cy = 0;
    if (reachable && n_z >= f.cos_theta && cell_of(ray.x(), ray.y(), &cx, &cy)) {
      float& g = ground[static_cast<size_t>(cy) * side + cx];
      g = std::min(g, p.z());
    }
  }

  // Pass 2: F, the local ground, the band and B_l.
  for (int i = 0; i < n; ++i) {
    if (state[i] == 0) continue;
    const int32_t b = offsets[i], e = offsets[i + 1];
    float fsum = 0.f;
    for (int32_t j = b; j < e; ++j) fsum += fpl[nbrs[j]];
    const float fpg = e > b ? fsum / static_cast<float>(e - b) : fpl[i];
    out.navigability[i] = Clamp01(w_l * fpl[i] + w_g * fpg);

    const Eigen::Vector3f& p = pts[i];
    float g = kInf;
    int cx = 0, cy = 0;
    cell_of(p.x() - origin.x(), p.y() - origin.y(), &cx, &cy);
    for (int y = std::max(0, cy - 1); y <= std::min(side - 1, cy + 1); ++y) {
      for (int x = std::max(0, cx - 1); x <= std::min(side - 1, cx + 1); ++x) {
        g = std::min(g, ground[static_cast<size_t>(y) * side + x]);
      }
    }
    if (!(g < kInf)) g = base_z;
    const float above = p.z() - g;
    const float foot = g - base_z;
    if (above >= 0.f && above <= band && foot <= dxy[i] * f.tan_theta) {
      state[i] = 2;
      bl[i] = Clamp01(bl[i] * f.Height(foot, dxy[i]));
    } else {
      bl[i] = 0.f;
    }
  }

  // Pass 3: B.
  for (int i = 0; i < n; ++i) {
    if (state[i] == 0) continue;
    if (state[i] == 1) {
      out.obstacle[i] = 0.f;
      continue;
    }
    const int32_t b = offsets[i], e = offsets[i + 1];
    float bsum = 0.f;
    for (int32_t j = b; j < e; ++j) bsum += bl[nbrs[j]];
    const float bg = e > b ? bsum / static_cast<float>(e - b) : bl[i];
    out.obstacle[i] = Clamp01(w_bl * bl[i] + w_bg * bg);
  }

  // Interest zones: rejected triangles joined through shared grid edges. An edge (u, v), u < v,
  // of a grid triangle goes from u to one of 4 forward neighbours; slot 4 u + kind holds the
  // first rejected triangle seen on it.
  const int32_t num_rejected = static_cast<int32_t>(mesh.rejected_triangles.size());
  if (num_rejected == 0) return out;
  std::vector<int32_t> parent(num_rejected);
  for (int32_t t = 0; t < num_rejected; ++t) parent[t] = t;
  std::vector<int32_t> slot(static_cast<size_t>(n) * 4, -1);
  for (int32_t t = 0; t < num_rejected; ++t) {
    const Eigen::Vector3i& tri = mesh.rejected_triangles[t];
    for (int k = 0; k < 3; ++k) {
      Require(tri[k] >= 0 && tri[k] < n, "ScanMesh.rejected_triangles",
              "must hold indices of scan points", tri[k]);
    }
    for (int k = 0; k < 3; ++k) {
      const int u = std::min(tri[k], tri[(k + 1) % 3]);
      const int v = std::max(tri[k], tri[(k + 1) % 3]);
      const int dl = v / beams - u / beams;
      const int db = v % beams - u % beams;
      int kind = -1;
      if (dl == 0 && db == 1) kind = 0;
      if (dl == 1 && db == 0) kind = 1;
      if (dl == 1 && db == 1) kind = 2;
      if (dl == 1 && db == -1) kind = 3;
      Require(kind >= 0, "ScanMesh.rejected_triangles",
              "must be triangles of the scan grid (neighbouring cells); bad edge from point", u);
      int32_t& s = slot[static_cast<size_t>(u) * 4 + kind];
      if (s < 0) {
        s = t;
      } else {
        Unite(parent, s, t);
      }
    }
  }

  // Per group (indexed by its root, the smallest triangle index in it): area, normal sum.
  std::vector<double> area(num_rejected, 0.0);
  std::vector<Eigen::Vector3d> normal_sum(num_rejected, Eigen::Vector3d::Zero());
  std::vector<int32_t> count(num_rejected, 0);
  const Eigen::Vector3d origin_d = origin.cast<double>();
  for (int32_t t = 0; t < num_rejected; ++t) {
    const int32_t r = Find(parent, t);
    const Eigen::Vector3i& tri = mesh.rejected_triangles[t];
    const Eigen::Vector3d a = pts[tri[0]].cast<double>();
    const Eigen::Vector3d b = pts[tri[1]].cast<double>();
    const Eigen::Vector3d c3 = pts[tri[2]].cast<double>();
    Eigen::Vector3d cross = (b - a).cross(c3 - a);
    if (cross.dot(3.0 * origin_d - a - b - c3) < 0.0) cross = -cross;
    area[r] += 0.5 * cross.norm();
    normal_sum[r] += 0.5 * cross;  // A_T n_T
    ++count[r];
  }

  // Kept groups, and their distinct vertices.
  std::vector<int32_t> zone_of(num_rejected, -1);
  std::vector<int32_t> roots;
  for (int32_t r = 0; r < num_rejected; ++r) {
    if (parent[r] == r && area[r] > params.min_zone_area_m2) {
      zone_of[r] = static_cast<int32_t>(roots.size());
      roots.push_back(r);
    }
  }
  if (roots.empty()) return out;
  const size_t num_zones = roots.size();
  // Triangles of each kept zone, contiguous (counting sort), so a vertex stamp per zone is exact.
  std::vector<int32_t> start(num_zones + 1, 0);
  for (size_t z = 0; z < num_zones; ++z) start[z + 1] = start[z] + count[roots[z]];
  std::vector<int32_t> order(start[num_zones]);
  std::vector<int32_t> fill(start.begin(), start.end() - 1);
  for (int32_t t = 0; t < num_rejected; ++t) {
    const int32_t z = zone_of[Find(parent, t)];
    if (z >= 0) order[fill[z]++] = t;
  }
  std::vector<int32_t> stamp(n, -1);
  out.zones.reserve(num_zones);
  for (size_t z = 0; z < num_zones; ++z) {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    int vertices = 0;
    for (int32_t j = start[z]; j < start[z + 1]; ++j) {
      const Eigen::Vector3i& tri = mesh.rejected_triangles[order[j]];
      for (int k = 0; k < 3; ++k) {
        if (stamp[tri[k]] == static_cast<int32_t>(z)) continue;
        stamp[tri[k]] = static_cast<int32_t>(z);
        sum += pts[tri[k]].cast<double>();
        ++vertices;
      }
    }
    const int32_t r = roots[z];
    InterestZone zone;
    const Eigen::Vector3d center = sum / vertices;
    Eigen::Vector3d dir = normal_sum[r];
    if (!(dir.norm() > 0.0)) dir = origin_d - center;  // cancelling normals: face the sensor
    if (dir.norm() > 0.0) dir.normalize();
    zone.center_m = center.cast<float>();
    zone.normal = (area[r] * dir).cast<float>();
    zone.area_m2 = static_cast<float>(area[r]);
    out.zones.push_back(zone);
  }
  // Decreasing area; ties keep the root order (the earlier rejected triangle first).
  std::vector<size_t> by_area(num_zones);
  for (size_t z = 0; z < num_zones; ++z) by_area[z] = z;
  std::stable_sort(by_area.begin(), by_area.end(),
                   [&](size_t a, size_t b) { return area[roots[a]] > area[roots[b]]; });
  std::vector<InterestZone> sorted;
  sorted.reserve(num_zones);
  for (size_t z : by_area) sorted.push_back(out.zones[z]);
  out.zones = std::move(sorted);
  return out;
}

}  // namespace cairn::explore
