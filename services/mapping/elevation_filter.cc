#include "services/mapping/elevation_filter.h"

#include <cmath>
#include <limits>

#include "common/check.h"
#include "common/yaml_reader.h"

namespace cairn::mapping {

void ElevationFilterParams::Validate() const {
  CAIRN_THROW_UNLESS(std::isfinite(range_noise_m) && range_noise_m >= 0,
                     "range_noise_m must be >= 0, got " << range_noise_m);
  CAIRN_THROW_UNLESS(std::isfinite(beam_constant_m) && beam_constant_m >= 0,
                     "beam_constant_m must be >= 0, got " << beam_constant_m);
  CAIRN_THROW_UNLESS(std::isfinite(beam_angle_rad) && beam_angle_rad >= 0,
                     "beam_angle_rad must be >= 0, got " << beam_angle_rad);
  CAIRN_THROW_UNLESS(mahalanobis_threshold > 0,
                     "mahalanobis_threshold must be positive, got " << mahalanobis_threshold);
  CAIRN_THROW_UNLESS(multi_height_noise_m2 >= 0, "multi_height_noise_m2 must be >= 0");
  CAIRN_THROW_UNLESS(min_variance_m2 > 0 && max_variance_m2 > min_variance_m2,
                     "need 0 < min_variance_m2 < max_variance_m2, got " << min_variance_m2 << ", "
                                                                        << max_variance_m2);
  CAIRN_THROW_UNLESS(increase_height_alpha >= 0 && increase_height_alpha < 1,
                     "increase_height_alpha must be in [0, 1), got " << increase_height_alpha);
  CAIRN_THROW_UNLESS(max_spread_slope_rad >= 0 && max_spread_slope_rad < M_PI / 2,
                     "max_spread_slope_rad must be in [0, pi/2), got " << max_spread_slope_rad);
}

double PointHeightVariance(const common::Vector3& sensor_m, const common::Vector3& point_m,
                           const ElevationFilterParams& params) {
  const common::Vector3 beam = point_m - sensor_m;
  const double range = beam.norm();
  if (!(range > 1e-9)) return params.range_noise_m * params.range_noise_m;
  return PointHeightVariance(range, beam.z() / range, params);
}

ElevationFilterParams LoadElevationFilterParams(common::YamlMap& m) {
  ElevationFilterParams p;
  m.Get("range_noise_m", &p.range_noise_m);
  m.Get("beam_constant_m", &p.beam_constant_m);
  m.Get("beam_angle_rad", &p.beam_angle_rad);
  m.Get("mahalanobis_threshold", &p.mahalanobis_threshold);
  m.Get("multi_height_noise_m2", &p.multi_height_noise_m2);
  m.Get("min_variance_m2", &p.min_variance_m2);
  m.Get("max_variance_m2", &p.max_variance_m2);
  m.Get("increase_height_alpha", &p.increase_height_alpha);
  double spread_deg = p.max_spread_slope_rad * 180.0 / M_PI;
  if (m.Get("max_spread_slope_deg", &spread_deg))
    p.max_spread_slope_rad = spread_deg * M_PI / 180.0;
  m.Finish();
  return p;
}

}  // namespace cairn::mapping
