#include "simulator/sonar_model.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "common/check.h"

namespace cairn::sim {

SonarEchoModel SonarEchoModelFromName(const std::string& name) {
  if (name == "faithful") return SonarEchoModel::kFaithful;
  if (name == "geometric") return SonarEchoModel::kGeometric;
  throw std::invalid_argument("unknown sonar echo model '" + name +
                              "' (known: faithful, geometric)");
}

const char* SonarEchoModelName(SonarEchoModel model) {
  return model == SonarEchoModel::kFaithful ? "faithful" : "geometric";
}

void SonarFanParams::Validate() const {
  CAIRN_THROW_UNLESS(rays >= 2 && rays <= 100000,
                     "sonar rays must be in [2, 100000], got " << rays);
  CAIRN_THROW_UNLESS(
      std::isfinite(half_aperture_rad) && half_aperture_rad > 0.0 && half_aperture_rad < M_PI / 2,
      "sonar half_aperture must be in (0, 90) deg");
  CAIRN_THROW_UNLESS(std::isfinite(range_min_m) && range_min_m >= 0.0,
                     "sonar range_min_m must be >= 0");
  CAIRN_THROW_UNLESS(std::isfinite(range_max_m) && range_max_m > range_min_m,
                     "sonar range_max_m must be > range_min_m");
  CAIRN_THROW_UNLESS(std::isfinite(bin_m) && bin_m > 0.0, "sonar bin_m must be > 0");
  CAIRN_THROW_UNLESS(NumBins() >= 2 && NumBins() <= 10000,
                     "sonar bins (range / bin_m) must be in [2, 10000], got " << NumBins());
}

int SonarFanParams::NumBins() const {
  return static_cast<int>((range_max_m - range_min_m) / bin_m);
}

double SonarFanParams::RayIncrementRad() const { return 2.0 * half_aperture_rad / (rays - 1); }

double SonarFanParams::RayElevationRad(int i) const {
  return -half_aperture_rad + i * RayIncrementRad();
}

namespace {

std::vector<uint8_t> Normalise(const std::vector<double>& sum, const std::vector<int>& count) {
  std::vector<uint8_t> out(sum.size(), 0);
  for (size_t k = 0; k < sum.size(); ++k) {
    if (sum[k] == 0.0 || count[k] == 0) continue;
    out[k] = static_cast<uint8_t>(std::clamp(static_cast<int>(sum[k] / count[k] * 255.0), 0, 255));
  }
  return out;
}

// Appendix A's Calculo_angulo_incidencia and Contador_beams.
std::vector<uint8_t> FaithfulProfile(std::vector<double> r, const SonarFanParams& p) {
  const int n = static_cast<int>(r.size());
  const int bins = p.NumBins();
  for (double& v : r) {
    if (!std::isfinite(v) || v >= p.range_max_m) v = p.range_max_m;  // UWSim's no return
  }
  std::sort(r.begin(), r.end());  // the thesis sorts before it assigns the angles
  const double inc = p.RayIncrementRad();
  std::vector<double> x(n), y(n);
  double phi = -p.half_aperture_rad;
  for (int i = 0; i < n; ++i) {
    phi += inc;  // the first ray gets angle_min + inc
    x[i] = r[i] * std::cos(phi);
    y[i] = r[i] * std::sin(phi);
  }
  std::vector<double> sin_theta(n, std::nan(""));
  for (int i = 0; i + 1 < n; ++i) {
    const double c = std::hypot(x[i] - x[i + 1], y[i] - y[i + 1]);
    if (c == 0.0) continue;  // guarded: the thesis divided by zero
    // sin(asin(a)) with a clamped to [-1, 1] (the thesis raised ValueError beyond).
    sin_theta[i] = std::clamp(std::sin(inc) * x[i + 1] / c, -1.0, 1.0);
  }
  std::vector<double> sum(bins, 0.0);
  std::vector<int> count(bins, 0);
  for (int i = 0; i < n; ++i) {
    const int k = static_cast<int>(r[i] / p.bin_m);  // range_min ignored, as in the thesis
    if (k >= bins - 1) continue;                     // "se omite la distancia máxima"
    if (std::isnan(sin_theta[i])) continue;          // guarded: the thesis's IndexError
    ++count[k];
    sum[k] += sin_theta[i];
  }
  return Normalise(sum, count);
}

std::vector<uint8_t> GeometricProfile(const std::vector<double>& r, const SonarFanParams& p) {
  const int n = static_cast<int>(r.size());
  const int bins = p.NumBins();
  const double inc = p.RayIncrementRad();
  auto hit = [&](int i) {
    return std::isfinite(r[i]) && r[i] >= p.range_min_m && r[i] < p.range_max_m;
  };
  std::vector<double> sum(bins, 0.0);
  std::vector<int> count(bins, 0);
  for (int i = 0; i < n; ++i) {
    if (!hit(i)) continue;
    // The neighbour above, or below for the top ray; the surface runs from this hit to it.
    const int j = (i + 1 < n && hit(i + 1)) ? i + 1 : (i > 0 && hit(i - 1)) ? i - 1 : -1;
    if (j < 0) continue;
    // |P_i P_j| by the law of cosines in the triangle sensor, P_i, P_j (angle inc at the sensor).
    const double c =
        std::sqrt(std::max(0.0, r[i] * r[i] + r[j] * r[j] - 2.0 * r[i] * r[j] * std::cos(inc)));
    if (c <= 1e-12) continue;
    const double sin_theta = std::clamp(std::sin(inc) * r[j] / c, 0.0, 1.0);
    const int k = static_cast<int>((r[i] - p.range_min_m) / p.bin_m);
    if (k < 0 || k >= bins) continue;
    ++count[k];
    sum[k] += sin_theta;
  }
  return Normalise(sum, count);
}

}  // namespace

std::vector<uint8_t> EchoProfile(const std::vector<double>& ranges_m,
                                 const SonarFanParams& params) {
  CAIRN_THROW_UNLESS(static_cast<int>(ranges_m.size()) == params.rays,
                     "a sonar fan of " << ranges_m.size() << " ranges, expected " << params.rays);
  return params.model == SonarEchoModel::kFaithful ? FaithfulProfile(ranges_m, params)
                                                   : GeometricProfile(ranges_m, params);
}

void SonarSweepParams::Validate() const {
  CAIRN_THROW_UNLESS(std::isfinite(step_rad) && step_rad > 0.0 && step_rad < M_PI,
                     "sonar step must be in (0, 180) deg");
  CAIRN_THROW_UNLESS(std::isfinite(limit_rad) && limit_rad > 0.0 && limit_rad <= M_PI,
                     "sonar sector limit must be in (0, 180] deg");
  CAIRN_THROW_UNLESS(std::isfinite(start_rad) && std::abs(start_rad) <= limit_rad,
                     "sonar start angle must lie within the sector");
}

SonarSweep::SonarSweep(const SonarSweepParams& params)
    : params_((params.Validate(), params)), angle_rad_(params.start_rad) {}

double SonarSweep::Advance() {
  if (params_.continuous) {
    angle_rad_ = std::remainder(angle_rad_ + params_.step_rad, 2.0 * M_PI);
    return angle_rad_;
  }
  if (up_) {
    angle_rad_ += params_.step_rad;
    if (angle_rad_ >= params_.limit_rad) {
      up_ = false;
      ++reversals_;
    }
  } else {
    angle_rad_ -= params_.step_rad;
    if (angle_rad_ <= -params_.limit_rad) {
      up_ = true;
      ++reversals_;
    }
  }
  return angle_rad_;
}

double PingTimeS(double range_m, double sound_speed_mps, bool round_trip) {
  return (round_trip ? 2.0 : 1.0) * range_m / sound_speed_mps;
}

double BinTimeS(double range_m, double sound_speed_mps, int bins, bool round_trip) {
  return PingTimeS(range_m, sound_speed_mps, round_trip) / bins;
}

}  // namespace cairn::sim
