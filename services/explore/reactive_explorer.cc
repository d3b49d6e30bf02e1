#include "services/explore/reactive_explorer.h"

#include <cmath>
#include <limits>

#include "common/check.h"

namespace cairn::explore {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// The cleaned value of one reading.
double Clean(float range_m, const ReactiveParams& params) {
  const double r = range_m;
  if (std::isnan(r)) return params.legacy_nan ? kNaN : params.clean_replacement_m;
  if (r < params.clean_min_range_m || r > params.clean_max_range_m) {
    return params.clean_replacement_m;
  }
  return r;
}

// Minimum of the cleaned readings [begin, end); NaN as soon as one is NaN (NumPy's min).
double SectorMin(const std::vector<float>& ranges_m, size_t begin, size_t end,
                 const ReactiveParams& params) {
  double best = std::numeric_limits<double>::infinity();
  for (size_t i = begin; i < end; ++i) {
    const double r = Clean(ranges_m[i], params);
    if (std::isnan(r)) return kNaN;
    if (r < best) best = r;
  }
  return best;
}

// The front test (every comparison with NaN is false, as in the source).
bool FrontObstacle(const SectorMinima& s, const ReactiveParams& params) {
  const double lateral_m = params.front_lateral_distance_m();
  return s.front_m < params.safety_distance_m || s.front_left_m < lateral_m ||
         s.front_right_m < lateral_m;
}

// +1 (left) when the left side is strictly freer, else -1 (right; ties and NaN go right).
int FreerSide(const SectorMinima& s) {
  return (s.left_m + s.front_left_m) > (s.right_m + s.front_right_m) ? +1 : -1;
}

// Centring or cruise with a clear front.
void ClearFrontDecision(const SectorMinima& s, const ReactiveParams& params, ReactiveMode* mode,
                        VelocityCommand* command) {
  if (s.left_m < params.side_distance_m) {
    *mode = ReactiveMode::kCentreRight;
    *command = {params.centring_speed_mps, -params.centring_turn_rate_radps};
  } else if (s.right_m < params.side_distance_m) {
    *mode = ReactiveMode::kCentreLeft;
    *command = {params.centring_speed_mps, +params.centring_turn_rate_radps};
  } else {
    *mode = ReactiveMode::kCruise;
    *command = {params.cruise_speed_mps, 0.0};
  }
}

VelocityCommand TurnCommand(int direction, const ReactiveParams& params) {
  return {0.0, direction > 0 ? params.turn_rate_radps : -params.turn_rate_radps};
}

void CheckPositive(double value, const char* field) {
  CAIRN_THROW_UNLESS(std::isfinite(value) && value > 0.0,
                     "ReactiveParams." << field << " must be positive and finite, got " << value);
}

}  // namespace

const char* ReactiveModeName(ReactiveMode mode) {
  switch (mode) {
    case ReactiveMode::kCruise:
      return "CRUISE";
    case ReactiveMode::kCentreLeft:
      return "CENTRE_LEFT";
    case ReactiveMode::kCentreRight:
      return "CENTRE_RIGHT";
    case ReactiveMode::kTurnInPlace:
      return "TURN_IN_PLACE";
    case ReactiveMode::kReverse:
      return "REVERSE";
  }
  return "UNKNOWN";
}

void ReactiveParams::Validate() const {
  CheckPositive(safety_distance_m, "safety_distance_m");
  CheckPositive(front_lateral_divisor, "front_lateral_divisor");
  CheckPositive(critical_distance_m, "critical_distance_m");
  CAIRN_THROW_UNLESS(
      std::isfinite(block_time_limit_s) && block_time_limit_s >= 0.0,
      "ReactiveParams.block_time_limit_s must be >= 0 and finite, got " << block_time_limit_s);
  CheckPositive(cruise_speed_mps, "cruise_speed_mps");
  CheckPositive(centring_speed_mps, "centring_speed_mps");
  CheckPositive(centring_turn_rate_radps, "centring_turn_rate_radps");
  CheckPositive(side_distance_m, "side_distance_m");
  CheckPositive(turn_rate_radps, "turn_rate_radps");
  CAIRN_THROW_UNLESS(
      std::isfinite(reverse_speed_mps) && reverse_speed_mps < 0.0,
      "ReactiveParams.reverse_speed_mps must be negative (backwards), got " << reverse_speed_mps);
  CAIRN_THROW_UNLESS(
      std::isfinite(clean_min_range_m) && clean_min_range_m >= 0.0,
      "ReactiveParams.clean_min_range_m must be >= 0 and finite, got " << clean_min_range_m);
  CAIRN_THROW_UNLESS(std::isfinite(clean_max_range_m) && clean_max_range_m > clean_min_range_m,
                     "ReactiveParams.clean_max_range_m must be finite and above "
                     "clean_min_range_m, got "
                         << clean_max_range_m);
  CheckPositive(clean_replacement_m, "clean_replacement_m");
  CAIRN_THROW_UNLESS(std::isfinite(max_reverse_s) && max_reverse_s >= 0.0,
                     "ReactiveParams.max_reverse_s must be >= 0 and finite (0: no limit), got "
                         << max_reverse_s);
}

SectorMinima ComputeSectorMinima(const std::vector<float>& ranges_m, const ReactiveParams& params) {
  params.Validate();
  CAIRN_THROW_UNLESS(ranges_m.size() >= 5,
                     "reactive explorer needs a scan of at least 5 beams (one per sector), got "
                         << ranges_m.size());
  const size_t n = ranges_m.size();
  const size_t chunk = n / 5;
  SectorMinima s;
  s.right_m = SectorMin(ranges_m, 0, chunk, params);
  s.front_right_m = SectorMin(ranges_m, chunk, 2 * chunk, params);
  s.front_m = SectorMin(ranges_m, 2 * chunk, 3 * chunk, params);
  s.front_left_m = SectorMin(ranges_m, 3 * chunk, 4 * chunk, params);
  s.left_m = SectorMin(ranges_m, 4 * chunk, n, params);
  s.global_m = SectorMin(ranges_m, 0, n, params);
  return s;
}

ReactiveExplorer::ReactiveExplorer(const ReactiveParams& params) : params_(params) {
  params_.Validate();
}

void ReactiveExplorer::Reset() {
  const int64_t scans = state_.scans;
  state_ = ReactiveState{};
  state_.scans = scans;
}

VelocityCommand ReactiveExplorer::Step(const std::vector<float>& ranges_m, double sim_time_s) {
  CAIRN_THROW_UNLESS(std::isfinite(sim_time_s),
                     "ReactiveExplorer::Step: sim_time_s must be finite, got " << sim_time_s);
  CAIRN_THROW_UNLESS(!state_.last_time_s || sim_time_s >= *state_.last_time_s,
                     "ReactiveExplorer::Step: sim_time_s went backwards ("
                         << sim_time_s << " s after " << state_.last_time_s.value_or(0.0)
                         << " s); call Reset() after rewinding the simulation");
  const SectorMinima sectors = ComputeSectorMinima(ranges_m, params_);

  ReactiveState& st = state_;
  st.sectors = sectors;
  st.last_time_s = sim_time_s;
  ++st.scans;
  st.front_obstacle = FrontObstacle(sectors, params_);
  if (st.front_obstacle) {
    if (!st.block_start_s) st.block_start_s = sim_time_s;
    st.blocked_s = sim_time_s - *st.block_start_s;
    if (sectors.global_m < params_.critical_distance_m ||
        st.blocked_s > params_.block_time_limit_s) {
      if (!st.reverse_start_s) st.reverse_start_s = sim_time_s;
      const bool too_long = params_.max_reverse_s > 0.0 &&
                            sim_time_s - *st.reverse_start_s > params_.max_reverse_s;
      if (!too_long) {
        st.mode = ReactiveMode::kReverse;
        st.command = {params_.reverse_speed_mps, 0.0};
        return st.command;
      }
      // Reversed for too long without the front clearing: turn instead, on a new timer.
      st.reverse_start_s.reset();
      st.block_start_s = sim_time_s;
      st.blocked_s = 0.0;
    } else {
      st.reverse_start_s.reset();
    }
    if (st.turn_direction == 0) st.turn_direction = FreerSide(sectors);
    st.mode = ReactiveMode::kTurnInPlace;
    st.command = TurnCommand(st.turn_direction, params_);
    return st.command;
  }
  st.turn_direction = 0;
  st.block_start_s.reset();
  st.reverse_start_s.reset();
  st.blocked_s = 0.0;
  ClearFrontDecision(sectors, params_, &st.mode, &st.command);
  return st.command;
}

StatelessExplorer::StatelessExplorer(const ReactiveParams& params) : params_(params) {
  params_.Validate();
}

StatelessDecision StatelessExplorer::Decide(const std::vector<float>& ranges_m) const {
  StatelessDecision d;
  d.sectors = ComputeSectorMinima(ranges_m, params_);
  if (FrontObstacle(d.sectors, params_)) {
    d.mode = ReactiveMode::kTurnInPlace;
    d.command = TurnCommand(FreerSide(d.sectors), params_);
  } else {
    ClearFrontDecision(d.sectors, params_, &d.mode, &d.command);
  }
  return d;
}

VelocityCommand StatelessExplorer::Step(const std::vector<float>& ranges_m) const {
  return Decide(ranges_m).command;
}

}  // namespace cairn::explore
