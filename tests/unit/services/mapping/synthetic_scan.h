#pragma once

#include <cmath>
#include <functional>
#include <limits>

#include "common/point_cloud.h"
#include "common/types.h"

/// @file
/// A ray-marched lidar over an analytic height field, for unit tests that need real-looking
/// revolutions without the simulator. NaN heights are holes with no bottom (no return).

namespace cairn::mapping::testing {

struct SyntheticLidar {
  int rings{16};
  double min_elevation_rad{-30.67 * M_PI / 180};
  double max_elevation_rad{-1.0 * M_PI / 180};
  int azimuths{360};
  double max_range_m{15.0};
  double step_m{0.01};
};

/// One revolution as a single slice, points in the sensor frame.
inline common::LidarSlice SyntheticRevolution(const common::Pose3& sensor,
                                              const std::function<double(double, double)>& ground,
                                              const SyntheticLidar& lidar, int64_t revolution = 0) {
  common::LidarSlice slice;
  slice.revolution = revolution;
  slice.slice_index = 0;
  slice.slice_count = 1;
  slice.sensor_pose = sensor;
  slice.max_range_m = lidar.max_range_m;
  const Eigen::Matrix3d r = sensor.orientation.toRotationMatrix();
  for (int ring = 0; ring < lidar.rings; ++ring) {
    const double el =
        lidar.min_elevation_rad +
        (lidar.max_elevation_rad - lidar.min_elevation_rad) * ring / std::max(1, lidar.rings - 1);
    for (int a = 0; a < lidar.azimuths; ++a) {
      const double az = 2 * M_PI * a / lidar.azimuths;
      const common::Vector3 dir_s(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az),
                                  std::sin(el));
      const common::Vector3 dir_w = r * dir_s;
      for (double t = lidar.step_m; t <= lidar.max_range_m; t += lidar.step_m) {
        const common::Vector3 p = sensor.position_m + t * dir_w;
        const double g = ground(p.x(), p.y());
        if (!std::isnan(g) && p.z() <= g) {
          // Refine the crossing by bisection over the last step.
          double lo = t - lidar.step_m, hi = t;
          for (int it = 0; it < 20; ++it) {
            const double mid = 0.5 * (lo + hi);
            const common::Vector3 q = sensor.position_m + mid * dir_w;
            const double gq = ground(q.x(), q.y());
            if (!std::isnan(gq) && q.z() <= gq) {
              hi = mid;
            } else {
              lo = mid;
            }
          }
          t = hi;
          common::LidarPoint lp;
          lp.x_m = static_cast<float>(t * dir_s.x());
          lp.y_m = static_cast<float>(t * dir_s.y());
          lp.z_m = static_cast<float>(t * dir_s.z());
          lp.ring = static_cast<int16_t>(ring);
          slice.points.push_back(lp);
          break;
        }
      }
    }
  }
  return slice;
}

inline common::Pose3 SensorAt(double x, double y, double z, double yaw = 0.0) {
  common::Pose3 p;
  p.position_m = {x, y, z};
  p.orientation = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ());
  return p;
}

}  // namespace cairn::mapping::testing
