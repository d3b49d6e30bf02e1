#include "services/mapping/elevation_filter.h"

#include <cmath>
#include <limits>

#include "common/check.h"

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
}

double PointHeightVariance(const common::Vector3& sensor_m, const common::Vector3& point_m,
                           const ElevationFilterParams& params) {
  const common::Vector3 beam = point_m - sensor_m;
  const double range = beam.norm();
  if (!(range > 1e-9)) return params.range_noise_m * params.range_noise_m;
  const double bz2 = (beam.z() / range) * (beam.z() / range);
  const double lateral = params.beam_constant_m + params.beam_angle_rad * range;
  return params.range_noise_m * params.range_noise_m * bz2 + lateral * lateral * (1.0 - bz2);
}

FuseOutcome FuseHeight(float* height_m, float* variance_m2, double z, double var_z,
                       bool same_scan, const ElevationFilterParams& p) {
  FuseOutcome outcome;
  double h = *height_m, var = *variance_m2;
  if (std::isnan(h) || !std::isfinite(var)) {
    h = z;
    var = var_z;
    outcome = FuseOutcome::kInitialized;
  } else {
    // Distance of the measurement from the estimate in units of the standard deviation of
    // their difference. elevation_mapping divides by the cell's sigma alone: once a cell has
    // converged (3 mm at the variance clamp) nearly every point of a centimetre-noise lidar
    // falls outside the gate, so the height freezes across scans and, within a scan, climbs to
    // the highest noisy point. Gating on var + var_z keeps noise in the fusion and still
    // separates true second surfaces (a wall face, an object) that lie many sigmas away.
    const double mahalanobis = std::fabs(z - h) / std::sqrt(var + var_z);
    if (mahalanobis >= p.mahalanobis_threshold) {
      if (same_scan && z < h) {
        return FuseOutcome::kIgnoredLower;  // nothing changes, no clamp needed
      } else if (same_scan) {
        const double a = p.increase_height_alpha;
        h = a * h + (1.0 - a) * z;
        var = a * var + (1.0 - a) * var_z;
        outcome = FuseOutcome::kRaised;
      } else {
        var += p.multi_height_noise_m2;
        outcome = FuseOutcome::kMultiHeight;
      }
    } else {
      h = (var * z + var_z * h) / (var + var_z);
      var = (var * var_z) / (var + var_z);
      outcome = FuseOutcome::kFused;
    }
  }
  if (var < p.min_variance_m2) var = p.min_variance_m2;
  if (var > p.max_variance_m2) {
    *height_m = std::numeric_limits<float>::quiet_NaN();
    *variance_m2 = std::numeric_limits<float>::quiet_NaN();
    return outcome;
  }
  *height_m = static_cast<float>(h);
  *variance_m2 = static_cast<float>(var);
  return outcome;
}

}  // namespace cairn::mapping
