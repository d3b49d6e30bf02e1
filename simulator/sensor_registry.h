#pragma once

#include <any>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "common/yaml_reader.h"
#include "simulator/sim_sensor.h"

/// @file
/// Sensor kinds by name: what a scenario's `sensors:` map, `cairn-sim --help` and MujocoSim
/// know about a sensor without knowing its type. BuiltinSensors() is the explicit list of the
/// simulator's own sensors (one line each in sensor_registry.cc).

namespace cairn::sim {

/// A sensor kind: its name, its parameters (type-erased, a copy of its Params struct) and how
/// to load, check and build it.
struct SensorKind {
  std::string name;
  std::string description;
  std::any (*default_params)() = nullptr;
  /// Reads a scenario's overrides into *params (which holds the defaults) and validates.
  /// @throws common::ConfigError naming the file and line.
  void (*load)(common::YamlMap& map, std::any* params) = nullptr;
  /// @throws std::invalid_argument naming the bad field.
  void (*validate)(const std::any& params) = nullptr;
  std::unique_ptr<SimSensor> (*create)(const std::any& params,
                                       const SensorContext& context) = nullptr;
};

/// The kind of sensor class S (see sim_sensor.h for what S provides); one object per class.
template <typename S>
const SensorKind& KindOf() {
  using Params = typename S::Params;
  static const SensorKind kind = [] {
    SensorKind k;
    k.name = S::kName;
    k.description = S::kDescription;
    k.default_params = [] { return std::any(Params{}); };
    k.load = [](common::YamlMap& map, std::any* params) {
      *params = S::kLoadParams(map, std::any_cast<const Params&>(*params));
    };
    k.validate = [](const std::any& params) { std::any_cast<const Params&>(params).Validate(); };
    k.create = [](const std::any& params,
                  const SensorContext& context) -> std::unique_ptr<SimSensor> {
      return std::make_unique<S>(std::any_cast<const Params&>(params), context);
    };
    return k;
  }();
  return kind;
}

/// Closes a Load<Name>Params: unknown keys and invalid values become ConfigErrors naming the
/// file and line.
template <typename Params>
void FinishSensorParams(common::YamlMap& map, const Params& params) {
  map.Finish();
  try {
    params.Validate();
  } catch (const std::invalid_argument& e) {
    throw common::ConfigError(map.Where() + e.what());
  }
}

/// Sensor kinds by name, in the order they were added (the catalogue's order).
class SensorRegistry {
 public:
  SensorRegistry() = default;
  SensorRegistry(const SensorRegistry&) = default;
  SensorRegistry& operator=(const SensorRegistry&) = default;
  SensorRegistry(SensorRegistry&&) = default;
  SensorRegistry& operator=(SensorRegistry&&) = default;

  /// @throws std::invalid_argument when a kind of that name is already there.
  void Add(const SensorKind& kind);
  /// nullptr for an unknown name.
  const SensorKind* Find(const std::string& name) const;
  /// Position of a kind in the registry (kinds().size() for an unknown name).
  size_t IndexOf(const std::string& name) const;
  const std::vector<const SensorKind*>& kinds() const { return kinds_; }
  /// (name, one-line description) of every kind, for --help.
  std::vector<std::pair<std::string, std::string>> Catalogue() const;

 private:
  std::vector<const SensorKind*> kinds_;
};

/// hdl32e, planar_laser, turret, odometry, imu, ground_truth.
const SensorRegistry& BuiltinSensors();

/// The sensors one robot carries, each with its parameters; a sensor not in the set is off.
class SensorSet {
 public:
  SensorSet() = default;
  SensorSet(const SensorSet&) = default;
  SensorSet& operator=(const SensorSet&) = default;
  SensorSet(SensorSet&&) = default;
  SensorSet& operator=(SensorSet&&) = default;

  struct Entry {
    const SensorKind* kind{nullptr};
    std::any params;
  };

  /// Parameters of sensor class S, or nullptr when it is off.
  template <typename S>
  typename S::Params* Find() {
    Entry* e = FindEntry(S::kName);
    return e == nullptr ? nullptr : std::any_cast<typename S::Params>(&e->params);
  }
  template <typename S>
  const typename S::Params* Find() const {
    return const_cast<SensorSet*>(this)->Find<S>();
  }
  /// Turns sensor class S on with `params` (replacing its parameters when it is on).
  template <typename S>
  typename S::Params& Set(typename S::Params params = {}) {
    Set(KindOf<S>(), std::any(std::move(params)));
    return *Find<S>();
  }
  /// Turns a sensor kind on with `params` (of the kind's Params type).
  void Set(const SensorKind& kind, std::any params);
  void Remove(const std::string& name);
  bool Has(const std::string& name) const;

  /// Names of the sensors that are on, in order.
  std::vector<std::string> Names() const;
  const std::vector<Entry>& entries() const { return entries_; }
  /// @throws std::invalid_argument naming the first bad field.
  void Validate() const;

 private:
  Entry* FindEntry(const std::string& name);

  std::vector<Entry> entries_;
};

/// A `sensors:` map: the listed sensors only, each starting from its parameters in `defaults`
/// when it is there (a robot model's), else from its defaults; ordered as in `registry`.
/// @throws common::ConfigError naming the file and line of an unknown sensor or a bad value.
SensorSet LoadSensorSet(common::YamlMap& map, const SensorSet& defaults,
                        const SensorRegistry& registry = BuiltinSensors());

}  // namespace cairn::sim
