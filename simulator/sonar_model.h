#pragma once

#include <cstdint>
#include <string>
#include <vector>

/// @file
/// Seed 004's mechanically scanned imaging sonar (a Tritech Miniking-like MSIS), the part that
/// needs no physics: the head's sweep, and how one ping's vertical fan of ray ranges becomes an
/// echo-intensity profile of 1 m bins (§3.2.2-3.2.4). The sonar sensor (sensors/sonar_sensor.h)
/// casts the fan in the scene and hands the ranges here.
///
/// Two echo models:
/// - kFaithful: the thesis's code (Appendix A) as it ran: the fan's ranges sorted ascending
///   before angles are given to them, angles from angle_min + increment, the incidence from
///   sin(increment) · x[i+1] / c[i], the bins of the sorted ranges, the last bin never used,
///   int(255 · mean sin θ). Only its crashes are guarded (the asin argument clamped, c = 0
///   skipped, the last ray's missing θ skipped, where the thesis raised IndexError).
/// - kGeometric (the default): the rays keep their angles; a ray's incidence is the angle at its
///   hit between the surface through its neighbour's hit and the line back to the sensor, by the
///   law of sines (sin θ = sin α · d_neighbour / c); only rays that hit take part; bins cover
///   [range_min, range_max).

namespace cairn::sim {

enum class SonarEchoModel { kFaithful, kGeometric };

/// "faithful" or "geometric". @throws std::invalid_argument for another name.
SonarEchoModel SonarEchoModelFromName(const std::string& name);
const char* SonarEchoModelName(SonarEchoModel model);

struct SonarFanParams {
  int rays{2001};                                           ///< the vertical fan (thesis: 2001)
  double half_aperture_rad{20.0 * 3.14159265358979 / 180};  ///< ±20°: γ 40°
  double range_min_m{0.0};
  double range_max_m{50.0};  ///< ρmax (Table 4.1)
  double bin_m{1.0};         ///< beam_footprint
  SonarEchoModel model{SonarEchoModel::kGeometric};

  /// @throws std::invalid_argument naming the bad field.
  void Validate() const;
  /// int((range_max - range_min) / bin): 50 for the thesis's 50 m and 1 m.
  int NumBins() const;
  /// The elevation of ray i (ray 0 at -half_aperture, the lowest).
  double RayElevationRad(int i) const;
  double RayIncrementRad() const;
};

/// One ping's echo profile from the fan's ranges, ray 0 the lowest (a range that is not finite,
/// or at or beyond range_max, is no return). Returns NumBins() intensities in 0..255.
/// @throws std::invalid_argument when ranges has not params.rays entries.
std::vector<uint8_t> EchoProfile(const std::vector<double>& ranges_m, const SonarFanParams& params);

struct SonarSweepParams {
  double limit_rad{60.0 * 3.14159265358979 / 180};  ///< the sector: ±limit
  double step_rad{0.005};                           ///< per ping
  double start_rad{35.0 * 3.14159265358979 / 180};  ///< the head's angle at the first ping
  bool continuous{false};  ///< 360° rotation (the datasheet's mode) instead of the sector

  /// @throws std::invalid_argument naming the bad field.
  void Validate() const;
};

/// The head's mechanical sweep (Algorithm 4 as the code runs it): after each ping the head steps
/// one step_rad in its direction and turns back once it reaches a limit (>= limit going up, <=
/// -limit going down), so the head overshoots a limit by up to one step.
class SonarSweep {
 public:
  /// @throws std::invalid_argument for invalid params.
  explicit SonarSweep(const SonarSweepParams& params);

  /// Where the next ping is taken (radians, positive to the left, counter-clockwise seen from
  /// above).
  double angle_rad() const { return angle_rad_; }
  /// After a ping: steps the head and returns its new angle (the angle the thesis published
  /// with the ping, one step after the one it was taken at).
  double Advance();
  /// Direction reversals so far.
  int64_t reversals() const { return reversals_; }
  int direction() const { return up_ ? 1 : -1; }

 private:
  SonarSweepParams params_;
  double angle_rad_;
  bool up_{true};
  int64_t reversals_{0};
};

/// Seed 004 eq. 2.1-2.2: the time for a ping's echo from `range_m`, e / v as the thesis writes it
/// (round_trip false) or 2e / v (round_trip true, the physics), and per bin t_f / bins.
double PingTimeS(double range_m, double sound_speed_mps, bool round_trip);
double BinTimeS(double range_m, double sound_speed_mps, int bins, bool round_trip);

}  // namespace cairn::sim
