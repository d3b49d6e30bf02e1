#pragma once

#include <cstdint>
#include <optional>
#include <vector>

/// @file
/// Seed 003's reactive five-sector explorer ("ExploradorAutonomo", seed 003 §3.4–§3.5) and the
/// stateless baseline it replaced (Práctica 1's "fuzzy" controller style).
///
/// Scan. One planar scan, beam 0 at the robot's right (angle_min, −120° on seed 003's 240°
/// laser) to beam N − 1 at its left. Readings are cleaned first: below clean_min_range_m or
/// above clean_max_range_m (±inf included) they become clean_replacement_m, and so does NaN
/// unless legacy_nan is set.
///
/// Sectors. chunk = N / 5 (integer division): right [0, chunk), front-right [chunk, 2·chunk),
/// front [2·chunk, 3·chunk), front-left [3·chunk, 4·chunk), left [4·chunk, N) (the remainder
/// goes to the left sector). Each sector is reduced to its minimum range.
///
/// Decision, once per scan (ReactiveExplorer):
///   obstacle = front < safety or front-left < safety/divisor or front-right < safety/divisor.
///   obstacle: the block timer starts at the first such scan; if the global minimum over all
///     beams is below critical_distance_m, or the time blocked exceeds block_time_limit_s
///     (strictly), reverse straight (reverse_speed_mps, 0). Otherwise stop and turn in place at
///     ±turn_rate_radps toward the side whose (side + front-side) minima sum is larger, left if
///     strictly larger, else right (ties turn right); the side is chosen once and kept until
///     the front clears.
///   clear: the timer and the turn memory are reset; left < side_distance_m → (centring speed,
///     −centring turn rate) (veer right); else right < side_distance_m → (centring speed,
///     +centring turn rate) (veer left); else (cruise speed, 0). The left rule wins when both
///     walls are close.
/// As in the source, the panic reverse lives only in the obstacle branch (a side wall closer
/// than critical_distance_m with a clear front leads to centring), and the timer is not reset
/// while reversing, so once blocked too long the robot reverses on every scan until the front
/// test clears.
///
/// Time is simulation time passed in by the caller (the source used the wall clock).

namespace cairn::explore {

/// A planar velocity command: forward speed and yaw rate (counter-clockwise positive).
struct VelocityCommand {
  double v_mps{0.0};
  double omega_radps{0.0};
};

/// What the explorer decided on a scan.
enum class ReactiveMode {
  kCruise,       ///< front and both sides clear: straight at cruise speed
  kCentreLeft,   ///< too close to the right wall: slower, small turn to the left (ω > 0)
  kCentreRight,  ///< too close to the left wall: slower, small turn to the right (ω < 0)
  kTurnInPlace,  ///< obstacle ahead: stop and rotate toward the freer side
  kReverse,      ///< obstacle ahead and critical clearance or blocked too long: back up straight
};

/// "CRUISE", "CENTRE_LEFT", "CENTRE_RIGHT", "TURN_IN_PLACE", "REVERSE".
const char* ReactiveModeName(ReactiveMode mode);

/// Every constant of seed 003's final explorer ("EXPLORADOR MEJORADO (ANTI-OSCILACIÓN)").
struct ReactiveParams {
  double safety_distance_m{0.65};     ///< front sector threshold
  double front_lateral_divisor{1.5};  ///< front-left / front-right threshold = safety / this
  double critical_distance_m{0.25};   ///< panic threshold on the global minimum
  double block_time_limit_s{2.0};     ///< reverse once blocked strictly longer than this
  double cruise_speed_mps{0.35};
  double centring_speed_mps{0.28};       ///< 0.8 × cruise in the source
  double centring_turn_rate_radps{0.4};  ///< magnitude; the sign picks the side
  double side_distance_m{0.45};          ///< left / right sector threshold for centring
  double turn_rate_radps{0.6};           ///< turn in place, magnitude
  double reverse_speed_mps{-0.15};       ///< negative: backwards
  /// Longest reverse, then a turn in place toward the remembered (or freer) side with a new
  /// block timer; 0: reverse until the front clears (the seed's rule). A robot backed against a
  /// wall with something ahead otherwise pushes backwards for ever, pitched, its laser finding
  /// the floor ahead.
  double max_reverse_s{0.0};
  double clean_min_range_m{0.05};        ///< readings strictly below are replaced
  double clean_max_range_m{10.0};        ///< readings strictly above are replaced
  double clean_replacement_m{10.0};      ///< the "reasonable maximum distance"
  /// true: keep the source's NaN bug. NaN readings are not cleaned, a sector holding one has a
  /// NaN minimum (NumPy's min), and every comparison with it is false: NaN in the front sector
  /// hides an obstacle there and the robot cruises. false (default): NaN becomes
  /// clean_replacement_m like any other invalid reading.
  bool legacy_nan{false};

  /// front_lateral threshold: safety_distance_m / front_lateral_divisor (0.4333 m).
  double front_lateral_distance_m() const { return safety_distance_m / front_lateral_divisor; }
  /// @throws std::invalid_argument naming the first bad field.
  void Validate() const;
};

/// Minimum cleaned range of each sector and of the whole scan (NaN only in legacy_nan mode).
struct SectorMinima {
  double right_m{0.0};
  double front_right_m{0.0};
  double front_m{0.0};
  double front_left_m{0.0};
  double left_m{0.0};
  double global_m{0.0};  ///< minimum over all beams
};

/// Cleans a scan and reduces it to its five sector minima (see the file comment).
/// @throws std::invalid_argument for fewer than 5 beams or invalid params.
SectorMinima ComputeSectorMinima(const std::vector<float>& ranges_m, const ReactiveParams& params);

/// The explorer's memory and its last decision.
struct ReactiveState {
  ReactiveMode mode{ReactiveMode::kCruise};  ///< of the last scan (kCruise before any)
  VelocityCommand command;                   ///< of the last scan
  SectorMinima sectors;                      ///< of the last scan
  bool front_obstacle{false};                ///< the front test of the last scan
  /// Remembered turn side: +1 left (ω > 0), −1 right, 0 none chosen (front clear, or only
  /// reverses since the obstacle appeared).
  int turn_direction{0};
  std::optional<double> block_start_s;  ///< sim time of the first scan of the current obstacle
  std::optional<double> reverse_start_s;  ///< sim time the current reverse began
  double blocked_s{0.0};                ///< time blocked at the last scan (0 when clear)
  std::optional<double> last_time_s;    ///< sim time of the last scan
  int64_t scans{0};                     ///< scans processed
};

/// Seed 003's stateful reactive explorer: direction memory, block timer, reverse recovery.
/// Not thread-safe.
class ReactiveExplorer {
 public:
  /// @throws std::invalid_argument if the params are invalid.
  explicit ReactiveExplorer(const ReactiveParams& params = {});

  /// Decides the command for one scan taken at simulation time `sim_time_s`.
  /// @throws std::invalid_argument for fewer than 5 beams, a non-finite time, or a time
  /// earlier than the previous scan's (call Reset() after rewinding the simulation). On a
  /// throw the state is unchanged.
  VelocityCommand Step(const std::vector<float>& ranges_m, double sim_time_s);

  /// Forgets the turn side, the block timer and the last scan's time.
  void Reset();

  const ReactiveState& state() const { return state_; }
  const ReactiveParams& params() const { return params_; }

 private:
  ReactiveParams params_;
  ReactiveState state_;
};

/// One decision of the stateless baseline.
struct StatelessDecision {
  ReactiveMode mode{ReactiveMode::kCruise};  ///< never kReverse
  VelocityCommand command;
  SectorMinima sectors;
};

/// The baseline for seed 003 test 38: the Práctica 1 "fuzzy"-style controller that the report
/// says got stuck in corners. Same cleaning, sectors, thresholds and speeds as
/// ReactiveExplorer, but no internal state: each scan with an obstacle ahead picks its turn
/// side afresh from that scan alone (which lets it oscillate between sides in a corner), there
/// is no block timer and it never reverses (the critical threshold and block_time_limit_s are
/// unused). A clear front gives the same centring / cruise as ReactiveExplorer.
class StatelessExplorer {
 public:
  /// @throws std::invalid_argument if the params are invalid.
  explicit StatelessExplorer(const ReactiveParams& params = {});

  /// @throws std::invalid_argument for fewer than 5 beams.
  StatelessDecision Decide(const std::vector<float>& ranges_m) const;
  /// Decide(ranges_m).command.
  VelocityCommand Step(const std::vector<float>& ranges_m) const;

  const ReactiveParams& params() const { return params_; }

 private:
  ReactiveParams params_;
};

}  // namespace cairn::explore
