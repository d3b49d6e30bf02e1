#pragma once

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include <mujoco/mujoco.h>

#include "common/status.h"
#include "common/types.h"
#include "simulator/noise.h"
#include "simulator/scene_rays.h"
#include "simulator/sim_outputs.h"

/// @file
/// The seam every simulated sensor goes through. A sensor kind is a class deriving from
/// SimSensor with
///   - `static constexpr char kName[]`: its name in scenario files, `--help` and SimOutputs;
///   - `static constexpr char kDescription[]`: one line for `cairn-sim --help`;
///   - `using Params = ...`: a plain struct with defaults and `void Validate() const`;
///   - `static constexpr auto kLoadParams = &Load<Name>Params`: reads the overrides of a
///     scenario's `sensors: {<name>: {...}}` entry, `Params (common::YamlMap&, const Params&)`;
///   - `using Reading = ...`: what it appends to SimOutputs under kName;
///   - a constructor `(const Params&, const SensorContext&)` that finds what it needs in the
///     model (sites, MuJoCo sensors) and throws std::invalid_argument when it is missing.
/// Optionally, a sensor that can take readings on request overrides `Trigger(now_s)` (the
/// default refuses with kInvalidArgument); MujocoSim::TriggerSensor and SIM.CONTROL's
/// OP_TRIGGER_SENSOR reach it by robot and kind name.
/// It is registered by name in sensor_registry.cc (BuiltinSensors) and, for cairn-sim to
/// publish it, in simulator/lcm/sensor_publishers.cc.

namespace cairn::sim {

/// What a sensor learns about its robot when it is built.
struct SensorContext {
  const mjModel* model{nullptr};
  std::string sensor;      ///< the kind's name ("hdl32e")
  std::string robot;       ///< the robot id
  int robot_index{0};      ///< its index in the scenario (ray casts skip its own geoms)
  std::string model_path;  ///< the robot's MJCF file (for messages)
  int qpos_adr{0};         ///< address of the base's free joint in qpos
  int qvel_adr{0};         ///< ... and in qvel
  double wheel_radius_m{0.1};
  double track_m{0.4};  ///< kinematic track
  uint64_t seed{0};     ///< the scenario's noise seed

  /// The sensor's own noise stream: (seed, "<robot>/<sensor>").
  NoiseSource Noise() const;
  /// "robot 'r' (path): " for messages.
  std::string Where() const;
  /// Id of the robot's site `site` ("lidar_mount", found as "<robot>/<site>").
  /// @throws std::invalid_argument saying the sensor needs it.
  int RequireSite(const std::string& site) const;
};

/// What a sensor reads when it produces: the physics state at sim time now_s (positions
/// brought up to date when any due sensor casts rays) and the scene's rays.
struct SensorFrame {
  const mjModel* model{nullptr};
  const mjData* data{nullptr};
  double now_s{0.0};
  int64_t utime{0};  ///< now_s in microseconds: the stamp of every reading
  int robot_index{0};
  SceneRays* rays{nullptr};

  /// Casts from a sensor of this robot (its own geoms unseen) into *hits.
  void Cast(const common::Pose3& sensor, const RayPattern& pattern, int group_begin, int group_end,
            double max_range_m, std::vector<RayHit>* hits) const {
    rays->Cast(data, robot_index, sensor, pattern, group_begin, group_end, max_range_m, hits);
  }
  /// The same into a buffer of just these rays: hits[ray index - first_ray].
  void Cast(const common::Pose3& sensor, const RayPattern& pattern, int group_begin, int group_end,
            double max_range_m, RayHit* hits, int first_ray) const {
    rays->Cast(data, robot_index, sensor, pattern, group_begin, group_end, max_range_m, hits,
               first_ray);
  }
  void CastAll(const common::Pose3& sensor, const RayPattern& pattern, double max_range_m,
               std::vector<RayHit>* hits) const {
    rays->CastAll(data, robot_index, sensor, pattern, max_range_m, hits);
  }
};

/// The robot's wheels over the physics step just taken (for sensors that integrate).
struct StepMotion {
  double dt_s{0.0};
  double left_wheel_delta_rad{0.0};  ///< mean rotation of the left wheels
  double right_wheel_delta_rad{0.0};
  /// Sideways travel over the step (m, body frame, left positive): a DVL measures the sway of a
  /// hull, which a wheel never has (0 for wheels).
  double lateral_m{0.0};
};

/// One simulated sensor of one robot.
class SimSensor {
 public:
  SimSensor() = default;
  virtual ~SimSensor() = default;
  SimSensor(const SimSensor&) = delete;
  SimSensor& operator=(const SimSensor&) = delete;

  /// True when a reading falls due at sim time now_s (asked after every physics step).
  virtual bool Due(double now_s) const = 0;
  /// True when Produce casts rays: the simulator then brings every pose up to now_s first.
  virtual bool CastsRays() const { return false; }
  /// Appends the readings due at frame.now_s to *out and moves its schedule past them.
  virtual void Produce(const SensorFrame& frame, SimOutputs* out) = 0;
  /// After every physics step, due or not (sensors that integrate motion).
  virtual void OnStep(const StepMotion& /*motion*/) {}
  /// The robot was put at (x, y, yaw) with its base at height z_m (spawn or reset).
  virtual void OnPlaced(const common::Pose2& /*pose*/, double /*z_m*/) {}
  /// Asks for readings now (sim time now_s, between physics steps): a sensor with an
  /// on-request mode arms it and says Due from the next reading time after now_s on. The
  /// default refuses: kInvalidArgument "no on-request mode" (MujocoSim::TriggerSensor names the
  /// robot and the kind in front of the message).
  virtual common::Status Trigger(double /*now_s*/) {
    return common::InvalidArgumentError("no on-request mode");
  }
};

/// Periodic timing: reading n falls due at n / rate_hz (n = 1, 2, ...), computed from integers
/// so long runs do not drift.
struct SensorSchedule {
  double rate_hz{1.0};
  int64_t count{0};  ///< readings produced so far

  bool Due(double now_s) const { return static_cast<double>(count + 1) / rate_hz <= now_s + 1e-9; }
  /// Counts every reading due by now_s (a slow step never makes a burst of readings).
  void Advance(double now_s) {
    while (Due(now_s)) ++count;
  }
  /// The same without a loop over the readings passed (after a long idle time): afterwards
  /// the next reading falls due at the first reading time after now_s. Never moves back.
  void SkipTo(double now_s) {
    const double due_by = now_s + 1e-9;
    int64_t n = static_cast<int64_t>(std::floor(due_by * rate_hz));
    // Settle rounding with the very comparison Due() makes.
    while (n > 0 && static_cast<double>(n) / rate_hz > due_by) --n;
    while (static_cast<double>(n + 1) / rate_hz <= due_by) ++n;
    if (n > count) count = n;
  }
};

/// For Params::Validate(): finite and > 0, finite and >= 0.
inline bool FinitePositive(double v) { return std::isfinite(v) && v > 0.0; }
inline bool FiniteNonNegative(double v) { return std::isfinite(v) && v >= 0.0; }

/// Pose of a site in the world (from the last kinematics pass).
common::Pose3 SitePose(const mjData* data, int site);

/// Converts sim time to microseconds.
int64_t ToUtime(double t_s);

}  // namespace cairn::sim
