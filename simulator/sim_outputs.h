#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "common/check.h"

/// @file
/// SimOutputs: what simulation steps produced, as readings grouped by sensor kind ("hdl32e",
/// "imu", ...) plus notable events. Each sensor kind produces one C++ reading type; the group
/// knows it, so a consumer (a test, cairn-sim's LCM publishers) asks for the readings of a
/// sensor by name and type and gets them without any per-sensor field here.

namespace cairn::sim {

template <typename T>
class TypedReadingGroup;

/// The readings one sensor kind produced, all of one type.
class ReadingGroup {
 public:
  explicit ReadingGroup(std::string sensor) : sensor_(std::move(sensor)) {}
  virtual ~ReadingGroup() = default;
  ReadingGroup(const ReadingGroup&) = delete;
  ReadingGroup& operator=(const ReadingGroup&) = delete;

  /// The sensor kind's name ("hdl32e").
  const std::string& sensor() const { return sensor_; }
  virtual size_t size() const = 0;
  bool empty() const { return size() == 0; }
  /// Drops the readings (keeps the storage for the next step).
  virtual void Clear() = 0;

  /// The readings as type T, or nullptr when they are of another type.
  template <typename T>
  const std::vector<T>* As() const {
    const auto* typed = dynamic_cast<const TypedReadingGroup<T>*>(this);
    return typed == nullptr ? nullptr : &typed->readings;
  }
  template <typename T>
  std::vector<T>* As() {
    auto* typed = dynamic_cast<TypedReadingGroup<T>*>(this);
    return typed == nullptr ? nullptr : &typed->readings;
  }

 private:
  std::string sensor_;
};

template <typename T>
class TypedReadingGroup final : public ReadingGroup {
 public:
  using ReadingGroup::ReadingGroup;
  size_t size() const override { return readings.size(); }
  void Clear() override { readings.clear(); }

  std::vector<T> readings;
};

/// Everything one or more steps produced.
class SimOutputs {
 public:
  SimOutputs() = default;
  SimOutputs(SimOutputs&&) = default;
  SimOutputs& operator=(SimOutputs&&) = default;
  SimOutputs(const SimOutputs&) = delete;
  SimOutputs& operator=(const SimOutputs&) = delete;

  /// Appends a reading of sensor kind `sensor`.
  template <typename T>
  void Add(const std::string& sensor, T reading) {
    Mutable<T>(sensor).push_back(std::move(reading));
  }
  /// The readings of a sensor kind, oldest first (empty when it produced none). A type other
  /// than the one the kind produces is a bug (aborts).
  template <typename T>
  const std::vector<T>& Get(const std::string& sensor) const {
    static const std::vector<T> kNone;
    const ReadingGroup* group = Find(sensor);
    if (group == nullptr) return kNone;
    const std::vector<T>* readings = group->As<T>();
    CAIRN_DEMAND(readings != nullptr);
    return *readings;
  }
  /// The same, to move readings out or edit them.
  template <typename T>
  std::vector<T>& Mutable(const std::string& sensor) {
    ReadingGroup* group = Find(sensor);
    if (group == nullptr) {
      groups_.push_back(std::make_unique<TypedReadingGroup<T>>(sensor));
      group = groups_.back().get();
    }
    std::vector<T>* readings = group->As<T>();
    CAIRN_DEMAND(readings != nullptr);
    return *readings;
  }
  /// The readings of sensor class S (its kName and Reading).
  template <typename S>
  const std::vector<typename S::Reading>& Readings() const {
    return Get<typename S::Reading>(S::kName);
  }

  /// Every sensor kind that produced since construction, in the order they first did.
  const std::vector<std::unique_ptr<ReadingGroup>>& groups() const { return groups_; }

  /// Notable events (watchdog stops), one line each.
  std::vector<std::string> events;

  void Clear();
  bool empty() const;

 private:
  ReadingGroup* Find(const std::string& sensor) const;

  std::vector<std::unique_ptr<ReadingGroup>> groups_;
};

}  // namespace cairn::sim
