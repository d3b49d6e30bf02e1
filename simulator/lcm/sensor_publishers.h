#pragma once

#include <functional>
#include <string>
#include <vector>

#include "cairn/lcmt_lidar_ranges.hpp"
#include "cairn/lcmt_point_cloud_slice.hpp"

#include "common/channels.h"
#include "common/check.h"
#include "common/point_cloud.h"
#include "services/runtime/node.h"
#include "simulator/sim_outputs.h"

/// @file
/// How cairn-sim puts each sensor kind's readings on the bus: a registry by sensor name of the
/// channel stream (<robot>.<stream>, from common/channels.h) and the conversion of a reading to
/// its LCM message. BuiltinSensorPublishers() is the explicit list (sensor_publishers.cc) that
/// matches the core's BuiltinSensors().

namespace cairn::sim {

/// Publishes the readings of one sensor kind.
struct SensorPublisher {
  std::string sensor;  ///< the kind's name ("hdl32e")
  std::string stream;  ///< channel suffix ("LIDAR"): readings go to <robot>.<stream>
  /// Converts and publishes every reading of `group` (which holds this kind's readings).
  std::function<void(runtime::Node& node, const ReadingGroup& group)> publish;
};

/// A publisher that converts each Reading with `convert` and sends the message on
/// <msg.robot>.<stream>.
template <typename Reading, typename Msg>
SensorPublisher MakeSensorPublisher(std::string sensor, std::string stream,
                                    Msg (*convert)(const Reading&)) {
  SensorPublisher p;
  p.sensor = std::move(sensor);
  p.stream = std::move(stream);
  p.publish = [stream = p.stream, convert](runtime::Node& node, const ReadingGroup& group) {
    const std::vector<Reading>* readings = group.As<Reading>();
    CAIRN_DEMAND(readings != nullptr);
    for (const Reading& reading : *readings) {
      const Msg msg = convert(reading);
      node.Publish(channels::ForRobot(msg.robot, stream.c_str()), msg);
    }
  };
  return p;
}

/// A lidar slice published with LCM's exact encoding of lcmt_point_cloud_slice, written straight
/// from the slice's points: the fields before the arrays by the generated code (a message with
/// no points), the arrays with one byte swap per value. The bytes are those of
/// runtime::ToLcm(slice).encode() (tested), without building that message: the generated
/// encode() writes each float byte by byte, and the message's five arrays were filled and freed
/// for every slice. Node::Publish takes it like any message; `slice` is borrowed.
class FastPointCloudSlice {
 public:
  explicit FastPointCloudSlice(const common::LidarSlice& slice);
  int getEncodedSize() const;
  int encode(void* buf, int offset, int maxlen) const;

 private:
  const common::LidarSlice* slice_;
  cairn::lcmt_point_cloud_slice head_;  ///< every field but the points
};

/// A lidar slice with a grid of ranges published with LCM's exact encoding of
/// lcmt_lidar_ranges, written straight from the slice's range image (a byte swap per range) or,
/// when it has none, from its points: the bytes are those of runtime::ToLcmRanges(slice).encode()
/// (tested), without the message's two arrays filled and freed for every slice and written by
/// the generated code value by value. encode() refuses (-1) a slice without a grid
/// (common::HasRangeGrid) or with a point off it.
class FastLidarRanges {
 public:
  explicit FastLidarRanges(const common::LidarSlice& slice);
  int getEncodedSize() const;
  int encode(void* buf, int offset, int maxlen) const;

 private:
  const common::LidarSlice* slice_;
  cairn::lcmt_lidar_ranges head_;  ///< every field but the rays (num_rays 0)
  int64_t rays_{0};
};

/// Publishers by sensor name.
class SensorPublishers {
 public:
  SensorPublishers() = default;
  SensorPublishers(const SensorPublishers&) = default;
  SensorPublishers& operator=(const SensorPublishers&) = default;
  SensorPublishers(SensorPublishers&&) = default;
  SensorPublishers& operator=(SensorPublishers&&) = default;

  /// @throws std::invalid_argument when the sensor already has one.
  void Add(SensorPublisher publisher);
  /// nullptr when the sensor has none.
  const SensorPublisher* Find(const std::string& sensor) const;
  const std::vector<SensorPublisher>& publishers() const { return publishers_; }

 private:
  std::vector<SensorPublisher> publishers_;
};

/// One for each of the simulator's own sensors.
const SensorPublishers& BuiltinSensorPublishers();

}  // namespace cairn::sim
