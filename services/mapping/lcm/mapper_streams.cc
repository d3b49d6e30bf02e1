#include "services/mapping/lcm/mapper_streams.h"

#include <cmath>
#include <cstdint>
#include <memory>
#include <optional>

#include "cairn/lcmt_laser_scan.hpp"
#include "cairn/lcmt_sonar_ping.hpp"

#include "services/mapping/explore_mapper_layer.h"
#include "services/mapping/sonar_mapper_layer.h"
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

// At most this many bins in a ping (a Miniking gives up to 800).
constexpr int kMaxSonarBins = 10000;

// The bin count of an encoded lcmt_sonar_ping, read where it lies (after the type's hash,
// utime, two strings and eight doubles: big-endian, strings as int32 length with their NUL),
// so a count the bytes cannot hold is refused before the generated decoder sizes an array by
// it. nullopt when the bytes end first.
std::optional<int64_t> SonarBinCount(const void* data, int size) {
  const auto* b = static_cast<const uint8_t*>(data);
  auto int32_at = [&](int64_t at) -> std::optional<int64_t> {
    if (at < 0 || at + 4 > size) return std::nullopt;
    const uint32_t v = (uint32_t{b[at]} << 24) | (uint32_t{b[at + 1]} << 16) |
                       (uint32_t{b[at + 2]} << 8) | uint32_t{b[at + 3]};
    return static_cast<int64_t>(static_cast<int32_t>(v));
  };
  int64_t at = 8 + 8;            // hash, utime
  for (int s = 0; s < 2; ++s) {  // robot, frame
    const auto length = int32_at(at);
    if (!length || *length < 0 || *length > size) return std::nullopt;
    at += 4 + *length;
  }
  at += 8 * (3 + 4 + 4);  // position, orientation, pan, range_min, range_max, sound_speed
  return int32_at(at);
}

// A sonar ping: one beam of bins at the head's angle (sonar_mapper_layer.h).
common::Result<std::unique_ptr<SensorReading>> ConvertSonarPing(const void* data, int size) {
  const std::optional<int64_t> count = SonarBinCount(data, size);
  if (!count || *count < 1 || *count > kMaxSonarBins || *count > size) {
    return common::InvalidArgumentError(
        "a ping of " + (count ? std::to_string(*count) : std::string("unreadable")) + " bins (1.." +
        std::to_string(kMaxSonarBins) + ", within the message's bytes)");
  }
  cairn::lcmt_sonar_ping msg;
  if (msg.decode(data, 0, size) < 0) {
    return common::InvalidArgumentError("the message does not decode as lcmt_sonar_ping");
  }
  if (msg.num_bins < 1 || msg.num_bins > kMaxSonarBins ||
      msg.intensities.size() != static_cast<size_t>(msg.num_bins)) {
    return common::InvalidArgumentError("a ping of " + std::to_string(msg.num_bins) + " bins (1.." +
                                        std::to_string(kMaxSonarBins) + ")");
  }
  if (!std::isfinite(msg.pan_rad) || std::abs(msg.pan_rad) > M_PI) {
    return common::InvalidArgumentError("the head's angle is not finite or beyond pi");
  }
  if (!std::isfinite(msg.range_min_m) || !std::isfinite(msg.range_max_m) || msg.range_min_m < 0.0 ||
      msg.range_max_m <= msg.range_min_m || msg.range_max_m > 1000.0) {
    return common::InvalidArgumentError("the ping's range is not 0 <= min < max <= 1000 m");
  }
  auto pose = runtime::PoseFromArrays(msg.sensor_position_m, msg.sensor_orientation_wxyz);
  if (!pose.ok())
    return common::InvalidArgumentError("the ping's pose: " + pose.status().message());
  auto reading = std::make_unique<SonarReading>();
  reading->utime = msg.utime;
  reading->sensor_pose = *pose;
  reading->pan_rad = msg.pan_rad;
  reading->range_min_m = msg.range_min_m;
  reading->range_max_m = msg.range_max_m;
  reading->bins = std::move(msg.intensities);
  return std::unique_ptr<SensorReading>(std::move(reading));
}

}  // namespace

const std::vector<StreamConverter>& RegisteredStreams() {
  // One entry per stream: its name and a function that decodes the message, checks it and
  // makes the reading the layer's header declares.
  static const std::vector<StreamConverter> streams{
      {"TURRET_SCAN", ConvertTurretLine},
      {"SONAR", ConvertSonarPing},
  };
  return streams;
}

}  // namespace cairn::mapping
