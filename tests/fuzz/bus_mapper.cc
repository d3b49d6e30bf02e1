// cairn-mapper's inputs: MapperService (terrain, occupancy and OctoMap layers, the pioneer3at
// profile) on memq://. Lidar slices, scans, poses, odometry, IMU, map control requests, resend
// requests and store replies go through the node's decode and the service's real handlers.

#include <memory>
#include <string>
#include <vector>

#include "common/robot_profile.h"
#include "services/mapping/lcm/mapper_service.h"
#include "tests/fuzz/bus_channels.h"
#include "tests/fuzz/bus_feed.h"
#include "tests/support/memq_node.h"

namespace {

struct Harness {
  Harness() : node(cairn::testing::MemqNodeOptions("cairn-mapper", cairn::fuzz::kRobot)) {
    cairn::mapping::MapperParams params;
    params.robot = cairn::fuzz::kRobot;
    params.core.terrain.publish_period_s = 0.01;
    params.core.terrain.registry_period_s = 0.01;
    const auto profile = cairn::common::LoadRobotProfileFile(std::string(CAIRN_SOURCE_DIR) +
                                                             "/config/profiles/pioneer3at.yaml");
    service = std::make_unique<cairn::mapping::MapperService>(
        node, params, std::vector<cairn::common::RobotProfile>{profile},
        [](const std::string& name) -> cairn::common::Result<cairn::common::RobotProfile> {
          return cairn::common::NotFoundError("no profile " + name);
        });
  }
  cairn::runtime::Node node;
  std::unique_ptr<cairn::mapping::MapperService> service;
};

}  // namespace

// A service per input: inputs stay independent (a finding reproduces from its input alone), and
// the workers stop before the process exits (a worker left running meets destroyed statics).
extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::vector<std::string> channels = cairn::fuzz::MapperChannels();
  Harness h;
  cairn::fuzz::FeedBus(h.node, channels, data, size);
  h.service->Stop();
  return 0;
}
