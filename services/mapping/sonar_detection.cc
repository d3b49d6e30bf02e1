#include "services/mapping/sonar_detection.h"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace cairn::mapping {

std::vector<int> DetectPeaks(const std::vector<uint8_t>& x, int min_peak_height,
                             int min_peak_distance) {
  const int n = static_cast<int>(x.size());
  std::vector<int> candidates;
  for (int i = 1; i + 1 < n; ++i) {
    const int rise = static_cast<int>(x[i]) - x[i - 1];
    const int fall = static_cast<int>(x[i + 1]) - x[i];
    if (rise > 0 && fall <= 0 && x[i] >= min_peak_height) candidates.push_back(i);
  }
  if (candidates.size() < 2 || min_peak_distance <= 1) return candidates;
  // Tallest first; among equals the higher index first (detect_peaks reverses an ascending
  // argsort); each kept peak removes its neighbours within mpd.
  std::vector<size_t> order(candidates.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    if (x[candidates[a]] != x[candidates[b]]) return x[candidates[a]] > x[candidates[b]];
    return candidates[a] > candidates[b];
  });
  std::vector<bool> removed(candidates.size(), false);
  for (size_t o = 0; o < order.size(); ++o) {
    const size_t i = order[o];
    if (removed[i]) continue;
    for (size_t j = 0; j < candidates.size(); ++j) {
      if (j != i && std::abs(candidates[j] - candidates[i]) <= min_peak_distance) {
        removed[j] = true;
      }
    }
  }
  std::vector<int> out;
  for (size_t i = 0; i < candidates.size(); ++i) {
    if (!removed[i]) out.push_back(candidates[i]);
  }
  return out;
}

std::vector<std::pair<int, int>> ZeroRuns(const std::vector<uint8_t>& x) {
  std::vector<std::pair<int, int>> runs;
  const int n = static_cast<int>(x.size());
  for (int i = 0; i < n;) {
    if (x[i] != 0) {
      ++i;
      continue;
    }
    int j = i;
    while (j < n && x[j] == 0) ++j;
    runs.emplace_back(i, j);
    i = j;
  }
  return runs;
}

bool PeakBetweenShadows(const std::vector<std::pair<int, int>>& zero_runs, int index) {
  for (size_t j = 0; j + 1 < zero_runs.size(); ++j) {
    if (index >= zero_runs[j].second && index <= zero_runs[j + 1].first) return true;
  }
  return false;
}

std::vector<int> SonarObstacleBins(const std::vector<uint8_t>& profile,
                                   const SonarPeakParams& params) {
  std::vector<int> peaks = DetectPeaks(profile, params.min_peak_height, params.min_peak_distance);
  if (!params.verify_shadow) return peaks;
  const auto runs = ZeroRuns(profile);
  peaks.erase(std::remove_if(peaks.begin(), peaks.end(),
                             [&](int k) { return !PeakBetweenShadows(runs, k); }),
              peaks.end());
  return peaks;
}

common::Vector2 SonarBinToWorld(const common::Vector2& sensor_xy_m, double beam_yaw_rad, int bin,
                                double bin_m) {
  const double d = bin * bin_m;
  return sensor_xy_m + common::Vector2(d * std::cos(beam_yaw_rad), d * std::sin(beam_yaw_rad));
}

}  // namespace cairn::mapping
