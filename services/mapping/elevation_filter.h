#pragma once

#include <cmath>
#include <cstdint>
#include <limits>

#include "common/types.h"

/// @file
/// The per-cell height filter of the elevation layer (seed 000 section 3.2, after ANYbotics
/// elevation_mapping): each cell holds a Gaussian height estimate (height, variance) fused from
/// point measurements with a 1-D Kalman update, Mahalanobis gating and variance limits.

namespace cairn::common {
class YamlMap;
}  // namespace cairn::common

namespace cairn::mapping {

/// Parameters of the height filter and of the laser noise model.
struct ElevationFilterParams {
  // Laser noise model (Pomerleau et al. 2012, elevation_mapping's LaserSensorProcessor).
  double range_noise_m{0.018};     ///< sigma along the beam ("min_radius")
  double beam_constant_m{0.0015};  ///< lateral sigma at zero range
  double beam_angle_rad{0.0006};   ///< lateral sigma growth per metre of range (beam divergence)

  /// |z - h| / sqrt(var + var_z) at or above this is another height (another surface).
  double mahalanobis_threshold{2.5};
  double multi_height_noise_m2{9e-7};  ///< added to a cell's variance per conflicting point
  double min_variance_m2{9e-6};        ///< (3 mm)^2: variances below are clamped up
  double max_variance_m2{0.01};        ///< (10 cm)^2: variances above make the cell unknown
  /// Blend toward a higher point of the same scan: 0 takes the higher point (upstream default).
  double increase_height_alpha{0.0};
  /// A cell on a slope holds points of different true heights: across a 0.2 m cell a 10 deg
  /// ramp rises 3.5 cm, several times a grazing ray's height noise. Up to this slope (the last
  /// one derived for the cell) the rise's variance across the cell, (res tan(slope))^2 / 12, is
  /// added to each point's. Without it the gate takes the upper part of the cell for another
  /// surface, the same-scan rule lifts the cell toward its highest points, and neighbouring
  /// cells on an even ramp differ by up to twice its rise (false step edges). Steeper cells
  /// (walls, step faces) keep the plain rule. 0 turns it off (upstream behaviour).
  double max_spread_slope_rad{0.44};

  /// @throws std::invalid_argument naming a bad field.
  void Validate() const;
};

/// Reads a `filter` section (every key optional; max_spread_slope_deg in degrees) over the
/// defaults. @throws common::ConfigError naming the file and line of a bad or unknown key.
ElevationFilterParams LoadElevationFilterParams(common::YamlMap& map);

/// Height variance (m²) of a point measured from `sensor_m` at `point_m` (world frame):
/// sigma_r² along the beam and sigma_lat² = (beam_constant + beam_angle·range)² across it,
/// projected on the vertical. elevation_mapping put the "normal" sigma on the sensor's z axis
/// whatever the beam direction, so for a level sensor every point got (1.8 cm)² at any range;
/// here the noise axes follow the beam, as in the cited model: grazing rays on the ground get
/// the small lateral sigma, steep ones the range sigma.
double PointHeightVariance(const common::Vector3& sensor_m, const common::Vector3& point_m,
                           const ElevationFilterParams& params);
/// The same from the range and the vertical component of the unit beam direction.
inline double PointHeightVariance(double range_m, double beam_z,
                                  const ElevationFilterParams& params) {
  const double bz2 = beam_z * beam_z;
  const double lateral = params.beam_constant_m + params.beam_angle_rad * range_m;
  return params.range_noise_m * params.range_noise_m * bz2 + lateral * lateral * (1.0 - bz2);
}

/// Variance of the true height across a cell of size res_m on a plane of `slope_rad` (0 for an
/// unknown slope or one steeper than max_spread_slope_rad).
inline double SlopeSpreadVariance(double slope_rad, double res_m,
                                  const ElevationFilterParams& params) {
  if (!(slope_rad > 0.0) || !(slope_rad <= params.max_spread_slope_rad)) return 0.0;
  const double rise = res_m * std::tan(slope_rad);
  return rise * rise / 12.0;
}

/// What one measurement did to a cell.
enum class FuseOutcome : int8_t {
  kInitialized,   ///< the cell was unknown: it takes the measurement
  kFused,         ///< within the gate: Kalman update
  kIgnoredLower,  ///< outside the gate, same scan, lower: ignored
  kRaised,        ///< outside the gate, same scan, higher: height raised toward it
  kMultiHeight,   ///< outside the gate, earlier scan: variance += multi_height_noise
};

/// Applies one measurement (z, var_z) to a cell (height, variance). `same_scan` says whether
/// the cell was last updated by the scan this point belongs to. After the update the variance is
/// clamped to min_variance; above max_variance the cell becomes unknown (both NaN).
/// Returns what happened (before the clamp).
inline FuseOutcome FuseHeight(float* height_m, float* variance_m2, double z, double var_z,
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
    // Compared squared: no square root and division per point.
    const double d = z - h;
    if (d * d >= p.mahalanobis_threshold * p.mahalanobis_threshold * (var + var_z)) {
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
