#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "common/status.h"
#include "services/mapping/mapper_layer.h"

/// @file
/// The sensor streams beyond the mapper's fixed inputs: for each, how a message on
/// <robot>.<stream> becomes a SensorReading for the layers that take the stream
/// (MapperLayer::ReadingStreams). A layer on a new sensor registers its stream's converter here.

namespace cairn::mapping {

struct StreamConverter {
  std::string stream;  ///< "SONAR": the channel <robot>.SONAR
  /// Decodes and checks one message (bytes from the bus: nothing is trusted). An error status
  /// drops it (counted as bad_<stream, lower case>).
  std::function<common::Result<std::unique_ptr<SensorReading>>(const void* data, int size)> convert;
};

/// The registered converters, one per stream.
const std::vector<StreamConverter>& RegisteredStreams();

}  // namespace cairn::mapping
