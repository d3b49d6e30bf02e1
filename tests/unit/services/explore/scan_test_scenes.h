#pragma once

#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "services/explore/scan_mesh.h"
#include <Eigen/Geometry>

/// @file
/// Synthetic turret scans for the scan analysis tests: analytic scenes (planar patches and
/// boxes) ray cast from a rotating vertical fan into an OrderedScan, with the surface each point
/// came from.

namespace cairn::explore::scan_testing {

inline constexpr double kDeg = M_PI / 180.0;
inline constexpr float kNaNf = std::numeric_limits<float>::quiet_NaN();

// A finite planar patch: points p with normal . p = offset inside the box [lo, hi].
struct Patch {
  Eigen::Vector3d normal;
  double offset;
  Eigen::Vector3d lo, hi;
};

// An axis-aligned solid box.
struct Box {
  Eigen::Vector3d lo, hi;
};

// Surfaces get ids in order: patches first, then boxes.
struct Scene {
  std::vector<Patch> patches;
  std::vector<Box> boxes;
  double max_range_m{40.0};
};

inline Patch Floor(double z, double x0 = -1e3, double x1 = 1e3, double y0 = -1e3, double y1 = 1e3) {
  return {{0, 0, 1}, z, {x0, y0, z - 1}, {x1, y1, z + 1}};
}

inline Patch WallX(double x, double y0 = -1e3, double y1 = 1e3, double z0 = -1e3, double z1 = 1e3) {
  return {{1, 0, 0}, x, {x - 1, y0, z0}, {x + 1, y1, z1}};
}

// Rises at `angle` along +x from (x0, ., 0) to x1, over y in [y0, y1].
inline Patch Ramp(double angle_rad, double x0, double x1, double y0, double y1) {
  const Eigen::Vector3d n(-std::sin(angle_rad), 0, std::cos(angle_rad));
  return {n, n.x() * x0, {x0, y0, -1}, {x1, y1, (x1 - x0) * std::tan(angle_rad) + 1}};
}

// Distance along the unit ray to the nearest surface, and its id (-1: none within range).
inline std::pair<double, int> Hit(const Scene& scene, const Eigen::Vector3d& o,
                                  const Eigen::Vector3d& d) {
  double best = scene.max_range_m;
  int id = -1;
  constexpr double kEps = 1e-9;
  for (size_t i = 0; i < scene.patches.size(); ++i) {
    const Patch& p = scene.patches[i];
    const double den = p.normal.dot(d);
    if (std::fabs(den) < 1e-12) continue;
    const double t = (p.offset - p.normal.dot(o)) / den;
    if (t <= 1e-6 || t >= best) continue;
    const Eigen::Vector3d q = o + t * d;
    if ((q.array() < p.lo.array() - kEps).any() || (q.array() > p.hi.array() + kEps).any()) {
      continue;
    }
    best = t;
    id = static_cast<int>(i);
  }
  for (size_t i = 0; i < scene.boxes.size(); ++i) {
    const Box& b = scene.boxes[i];
    double t0 = 0.0, t1 = best;
    bool miss = false;
    for (int k = 0; k < 3 && !miss; ++k) {
      if (std::fabs(d[k]) < 1e-12) {
        miss = o[k] < b.lo[k] || o[k] > b.hi[k];
        continue;
      }
      double a = (b.lo[k] - o[k]) / d[k], c = (b.hi[k] - o[k]) / d[k];
      if (a > c) std::swap(a, c);
      t0 = std::max(t0, a);
      t1 = std::min(t1, c);
      miss = t0 > t1;
    }
    if (miss || t0 <= 1e-6 || t0 >= best) continue;
    best = t0;
    id = static_cast<int>(scene.patches.size() + i);
  }
  return {best, id};
}

// Rotation from a turret line's scanning frame to the world at `pan_rad` (the simulator's
// convention: the line's x axis is the turret's up axis, its y axis the horizontal pan direction).
inline Eigen::Matrix3d TurretLineFrame(double pan_rad) {
  const double c = std::cos(pan_rad), s = std::sin(pan_rad);
  Eigen::Matrix3d r;
  r << 0.0, c, -s, 0.0, s, c, 1.0, 0.0, 0.0;
  return r;
}

// A rotating vertical fan: line = pan angle, beam = elevation, 0.5 deg steps by default.
struct Fan {
  double pan_min_deg{-10}, pan_max_deg{10};
  double elev_min_deg{-40}, elev_max_deg{0};
  double step_deg{0.5};
  double sensor_z_m{1.0};
};

struct CastScan {
  OrderedScan scan;
  std::vector<int> id;  // surface id per point, -1 for no return
  int Line(int i) const { return i / scan.beams_per_line; }
  int Beam(int i) const { return i % scan.beams_per_line; }
};

inline CastScan Cast(const Scene& scene, const Fan& fan) {
  CastScan out;
  OrderedScan& s = out.scan;
  s.num_lines =
      static_cast<int>(std::lround((fan.pan_max_deg - fan.pan_min_deg) / fan.step_deg)) + 1;
  s.beams_per_line =
      static_cast<int>(std::lround((fan.elev_max_deg - fan.elev_min_deg) / fan.step_deg)) + 1;
  s.sensor_origin_m = Eigen::Vector3f(0, 0, static_cast<float>(fan.sensor_z_m));
  s.robot_base_z_m = 0.f;
  s.pan_step_rad = fan.step_deg * kDeg;
  s.tilt_step_rad = fan.step_deg * kDeg;
  const Eigen::Vector3d o(0, 0, fan.sensor_z_m);
  for (int l = 0; l < s.num_lines; ++l) {
    const double pan = (fan.pan_min_deg + l * fan.step_deg) * kDeg;
    for (int b = 0; b < s.beams_per_line; ++b) {
      const double elev = (fan.elev_min_deg + b * fan.step_deg) * kDeg;
      const Eigen::Vector3d d(std::cos(elev) * std::cos(pan), std::cos(elev) * std::sin(pan),
                              std::sin(elev));
      const auto [t, id] = Hit(scene, o, d);
      out.id.push_back(id);
      s.points_m.push_back(id < 0 ? Eigen::Vector3f::Constant(kNaNf)
                                  : (o + t * d).cast<float>().eval());
    }
  }
  return out;
}

inline int Index(const OrderedScan& s, int line, int beam) {
  return line * s.beams_per_line + beam;
}

// Neighbours of point i in the mesh.
inline std::vector<int32_t> NeighboursOf(const ScanMesh& m, int i) {
  return {m.neighbours.begin() + m.neighbour_offsets[i],
          m.neighbours.begin() + m.neighbour_offsets[i + 1]};
}

template <typename Fn>
inline void ExpectThrowNaming(Fn fn, const std::string& field) {
  try {
    fn();
    ADD_FAILURE() << "no exception; expected one naming " << field;
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
  }
}

}  // namespace cairn::explore::scan_testing
