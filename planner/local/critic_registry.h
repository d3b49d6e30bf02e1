#pragma once

#include <functional>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "planner/local/critics.h"
#include "planner/local/trajectory_generator.h"

/// @file
/// The DWA's critic seam. The local planner scores trajectories with a list of critics built
/// from configuration (DwaParams::critics, `local_planner.critics` in the navigator's YAML) in
/// the listed order, each made by name through a CriticRegistry. BuiltinCritics() holds the
/// shipped ones; a new critic is one TrajectoryCritic subclass and one CriticRegistry::Add in
/// BuiltinCritics() (see planner/README.md, "Adding a critic").

namespace cairn::planner {

/// A critic's own parameters by key: numbers, and booleans as 1 or 0. Keys carry units in their
/// names like every param (`inflation_m`). A critic reads them with a CriticParamReader, so a
/// key it does not know is an error.
using CriticParams = std::map<std::string, double>;

/// One entry of the DWA's critic list.
struct CriticConfig {
  std::string name;     ///< a registered critic ("clearance", "path_align", ...)
  double scale{1.0};    ///< weight of its value in the DWA's sum, finite and >= 0
  CriticParams params;  ///< its own keys; an absent key keeps the critic's default

  bool operator==(const CriticConfig& o) const {
    return name == o.name && scale == o.scale && params == o.params;
  }
};

/// What a critic may know besides its own params: the robot's velocity and acceleration limits
/// and the trajectory generator's settings (horizon, step, control period).
struct CriticSetup {
  VelocityLimits limits;
  TrajectoryGeneratorParams generator;
};

/// Reads one critic's params: Get every key the critic knows, then Finish(), which throws on
/// any key that was not read (the strictness of common::YamlMap, for a critic's keys).
class CriticParamReader {
 public:
  explicit CriticParamReader(const CriticConfig& config) : config_(config) {}

  /// Reads `key` into *value when present (a finite number); returns whether it was.
  /// @throws std::invalid_argument for a value that is not finite.
  bool Get(const std::string& key, double* value);
  /// A boolean: 1 or 0. @throws std::invalid_argument for another value.
  bool Get(const std::string& key, bool* value);
  /// @throws std::invalid_argument naming the critic and the first key no Get asked for.
  void Finish() const;

 private:
  const CriticConfig& config_;
  std::set<std::string> used_;
};

/// Makes a critic from its configuration entry. It reads `config.params` with a
/// CriticParamReader (and calls Finish), passes `config.scale` on, and returns a critic whose
/// name() is `config.name`. @throws std::invalid_argument for a bad param.
using CriticFactory = std::function<std::unique_ptr<TrajectoryCritic>(const CriticConfig& config,
                                                                      const CriticSetup& setup)>;

/// Critic factories by name. Copyable: a test copies BuiltinCritics() and adds its own.
class CriticRegistry {
 public:
  /// @throws std::invalid_argument for an empty name or one already taken.
  void Add(const std::string& name, CriticFactory factory);
  bool Has(const std::string& name) const { return factories_.count(name) > 0; }
  /// Registered names, sorted.
  std::vector<std::string> names() const;

  /// The critic of one list entry.
  /// @throws std::invalid_argument naming an unknown critic (and the known ones), a bad scale or
  /// a bad or unknown param.
  std::unique_ptr<TrajectoryCritic> Make(const CriticConfig& config,
                                         const CriticSetup& setup) const;
  /// Make() with default limits, for a configuration loader to report a bad entry early.
  void Check(const CriticConfig& config) const;

 private:
  std::map<std::string, CriticFactory> factories_;
};

/// The shipped critics: "speed", "oscillation", "goal_dist", "path_align" and "clearance"
/// (critics.h; their keys in critic_registry.cc and config/navigator/navigator.yaml).
const CriticRegistry& BuiltinCritics();

/// The default list, in scoring order (cheap critics first, the clearance critic, which
/// rasterises the footprint, last) with Nav2 DWB-like weights.
std::vector<CriticConfig> DefaultCritics();

}  // namespace cairn::planner
