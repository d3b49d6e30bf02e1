#include "simulator/sensor_registry.h"

#include <algorithm>
#include <stdexcept>

#include "simulator/sensors/ground_truth_sensor.h"
#include "simulator/sensors/imu_sensor.h"
#include "simulator/sensors/lidar_sensor.h"
#include "simulator/sensors/odometry_sensor.h"
#include "simulator/sensors/planar_laser_sensor.h"
#include "simulator/sensors/sonar_sensor.h"
#include "simulator/sensors/turret_sensor.h"

namespace cairn::sim {

const SensorRegistry& BuiltinSensors() {
  // The simulator's sensors, in catalogue order: a new sensor kind adds one line here.
  static const SensorRegistry registry = [] {
    SensorRegistry r;
    r.Add(KindOf<LidarSensor>());
    r.Add(KindOf<PlanarLaserSensor>());
    r.Add(KindOf<TurretSensor>());
    r.Add(KindOf<OdometrySensor>());
    r.Add(KindOf<ImuSensor>());
    r.Add(KindOf<GroundTruthSensor>());
    r.Add(KindOf<SonarSensor>());
    return r;
  }();
  return registry;
}

// --- SensorRegistry ----------------------------------------------------------------------------

void SensorRegistry::Add(const SensorKind& kind) {
  if (Find(kind.name) != nullptr) {
    throw std::invalid_argument("sensor kind '" + kind.name + "' is registered twice");
  }
  kinds_.push_back(&kind);
}

const SensorKind* SensorRegistry::Find(const std::string& name) const {
  for (const SensorKind* kind : kinds_) {
    if (kind->name == name) return kind;
  }
  return nullptr;
}

size_t SensorRegistry::IndexOf(const std::string& name) const {
  for (size_t i = 0; i < kinds_.size(); ++i) {
    if (kinds_[i]->name == name) return i;
  }
  return kinds_.size();
}

std::vector<std::pair<std::string, std::string>> SensorRegistry::Catalogue() const {
  std::vector<std::pair<std::string, std::string>> out;
  for (const SensorKind* kind : kinds_) out.emplace_back(kind->name, kind->description);
  return out;
}

// --- SensorSet ---------------------------------------------------------------------------------

SensorSet::Entry* SensorSet::FindEntry(const std::string& name) {
  for (Entry& e : entries_) {
    if (e.kind->name == name) return &e;
  }
  return nullptr;
}

void SensorSet::Set(const SensorKind& kind, std::any params) {
  if (Entry* e = FindEntry(kind.name)) {
    e->kind = &kind;
    e->params = std::move(params);
  } else {
    entries_.push_back({&kind, std::move(params)});
  }
}

void SensorSet::Remove(const std::string& name) {
  entries_.erase(std::remove_if(entries_.begin(), entries_.end(),
                                [&](const Entry& e) { return e.kind->name == name; }),
                 entries_.end());
}

bool SensorSet::Has(const std::string& name) const {
  return const_cast<SensorSet*>(this)->FindEntry(name) != nullptr;
}

std::vector<std::string> SensorSet::Names() const {
  std::vector<std::string> names;
  for (const Entry& e : entries_) names.push_back(e.kind->name);
  return names;
}

void SensorSet::Validate() const {
  for (const Entry& e : entries_) e.kind->validate(e.params);
}

// --- loading -----------------------------------------------------------------------------------

SensorSet LoadSensorSet(common::YamlMap& map, const SensorSet& defaults,
                        const SensorRegistry& registry) {
  SensorSet set;
  for (const std::string& name : map.Keys()) {
    const SensorKind* kind = registry.Find(name);
    if (kind == nullptr) {
      std::string known;
      for (const auto& [n, d] : registry.Catalogue()) known += (known.empty() ? "" : ", ") + n;
      map.Fail(map.Raw(name), "unknown sensor '" + name + "' (known: " + known + ")");
    }
    common::YamlMap child = map.Child(name);
    const auto& from = defaults.entries();
    const auto it = std::find_if(from.begin(), from.end(),
                                 [&](const SensorSet::Entry& e) { return e.kind->name == name; });
    std::any params = it != from.end() ? it->params : kind->default_params();
    kind->load(child, &params);
    set.Set(*kind, std::move(params));
  }
  // The registry's order, whatever the file's: sensors are built and listed in it.
  SensorSet ordered;
  for (const SensorKind* kind : registry.kinds()) {
    for (const SensorSet::Entry& e : set.entries()) {
      if (e.kind->name == kind->name) ordered.Set(*e.kind, e.params);
    }
  }
  return ordered;
}

}  // namespace cairn::sim
