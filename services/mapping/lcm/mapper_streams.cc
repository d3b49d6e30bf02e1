#include "services/mapping/lcm/mapper_streams.h"

#include <cmath>
#include <memory>

#include "cairn/lcmt_laser_scan.hpp"

#include "services/mapping/explore_mapper_layer.h"
#include "services/runtime/conversions.h"

namespace cairn::mapping {
namespace {

// A turret line: one vertical fan at one pan step (explore_mapper_layer.h).
common::Result<std::unique_ptr<SensorReading>> ConvertTurretLine(const void* data, int size) {
  cairn::lcmt_laser_scan msg;
  if (msg.decode(data, 0, size) < 0) {
    return common::InvalidArgumentError("the message does not decode as lcmt_laser_scan");
  }
  auto line = runtime::FromLcm(msg);
  if (!line.ok()) return line.status();
  if (!std::isfinite(msg.turret_angle_rad) || std::abs(msg.turret_angle_rad) > 2.0 * M_PI) {
    return common::InvalidArgumentError("the turret angle is not finite or beyond 2 pi");
  }
  auto reading = std::make_unique<TurretLineReading>();
  reading->utime = msg.utime;
  reading->sensor_pose = line->sensor_pose;
  reading->line = std::move(line.value());
  reading->pan_rad = msg.turret_angle_rad;
  return std::unique_ptr<SensorReading>(std::move(reading));
}

}  // namespace

const std::vector<StreamConverter>& RegisteredStreams() {
  // One entry per stream: {"SONAR", [](const void* data, int size) { decode the lcmt_..., check
  // it, return a SonarReading (sonar_mapper_layer.h) }}.
  static const std::vector<StreamConverter> streams{
      {"TURRET_SCAN", ConvertTurretLine},
  };
  return streams;
}

}  // namespace cairn::mapping
