#include "services/mapping/lcm/mapper_streams.h"

namespace cairn::mapping {

const std::vector<StreamConverter>& RegisteredStreams() {
  // One entry per stream: {"SONAR", [](const void* data, int size) { decode the lcmt_..., check
  // it, return a SonarReading (sonar_mapper_layer.h) }}.
  static const std::vector<StreamConverter> streams{};
  return streams;
}

}  // namespace cairn::mapping
