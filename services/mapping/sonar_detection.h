#pragma once

#include <cstdint>
#include <utility>
#include <vector>

#include "common/types.h"

/// @file
/// Seed 004's obstacle detection on one sonar ping (§3.3): the peaks of the echo profile
/// (detect_peaks with mph 110 and mpd 2, Duarte's semantics to the index), the zero runs (the
/// acoustic shadows) and the shadow verification the thesis describes (a peak counts only when
/// a shadow follows it), and where a peak lies in the world.

namespace cairn::mapping {

struct SonarPeakParams {
  int min_peak_height{110};  ///< mph
  int min_peak_distance{2};  ///< mpd, in bins
  /// The thesis's shadow verification (described, never wired in): a peak counts only when it
  /// lies between a zero run's end and the next zero run's start (that start included).
  bool verify_shadow{false};
};

/// detect_peaks(x, mph, mpd) with edge 'rising', threshold 0, kpsh false: indices i (neither end)
/// with x[i] - x[i-1] > 0 and x[i+1] - x[i] <= 0 and x[i] >= mph (a flat top at its rising
/// edge); then, tallest first, each kept peak removes the others within mpd bins (an equal
/// neighbour too); returned in index order.
std::vector<int> DetectPeaks(const std::vector<uint8_t>& x, int min_peak_height,
                             int min_peak_distance);

/// The runs of zeros as half-open [start, end) pairs (Calculo_rango_ceros).
std::vector<std::pair<int, int>> ZeroRuns(const std::vector<uint8_t>& x);

/// Whether the peak at `index` lies between two zero runs: in [run_j.end, run_{j+1}.start] for
/// some consecutive runs j, j+1 (verif_picos as the thesis meant it).
bool PeakBetweenShadows(const std::vector<std::pair<int, int>>& zero_runs, int index);

/// The detected obstacle bins of one profile: DetectPeaks, then the shadow verification when
/// params.verify_shadow.
std::vector<int> SonarObstacleBins(const std::vector<uint8_t>& profile,
                                   const SonarPeakParams& params);

/// Where the near edge of bin `bin` (bin · bin_m along the beam) lies in the world, the beam
/// leaving the sensor at `sensor_xy_m` with heading `beam_yaw_rad` (the robot's yaw plus the
/// head's pan, pan positive to the left).
common::Vector2 SonarBinToWorld(const common::Vector2& sensor_xy_m, double beam_yaw_rad, int bin,
                                double bin_m);

}  // namespace cairn::mapping
