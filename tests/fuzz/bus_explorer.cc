// cairn-explorer's inputs, in every mode: ExplorerService as reactive, stateless, frontier and
// next-best-view explorer (the shipped configurations, the pioneer3at profile), each on a memq://
// bus of its own, fed the same messages through the node's decode and its real handlers.

#include <memory>
#include <string>
#include <vector>

#include "common/robot_profile.h"
#include "services/explore/explorer_config.h"
#include "services/explore/lcm/explorer_service.h"
#include "tests/fuzz/bus_channels.h"
#include "tests/fuzz/bus_feed.h"
#include "tests/support/memq_node.h"

namespace {

struct Explorer {
  explicit Explorer(const cairn::explore::ExplorerConfig& config,
                    const cairn::common::RobotProfile& profile)
      : node(cairn::testing::MemqNodeOptions("cairn-explorer", cairn::fuzz::kRobot)),
        service(node, config, profile) {}
  cairn::runtime::Node node;
  cairn::explore::ExplorerService service;
};

std::vector<cairn::explore::ExplorerConfig> Configs() {
  const std::string dir = std::string(CAIRN_SOURCE_DIR) + "/config/explore/";
  std::vector<cairn::explore::ExplorerConfig> configs;
  for (auto mode : {cairn::explore::ExploreMode::kReactive, cairn::explore::ExploreMode::kStateless,
                    cairn::explore::ExploreMode::kFrontier}) {
    configs.push_back(cairn::explore::LoadExplorerConfigFile(dir + "explorer.yaml"));
    configs.back().mode = mode;
  }
  configs.push_back(cairn::explore::LoadExplorerConfigFile(dir + "outdoor_nbv.yaml"));
  for (auto& c : configs) {
    c.out_dir.clear();  // nothing written, nothing saved
    c.save_to.clear();
  }
  return configs;
}

}  // namespace

// Services per input: a finding reproduces from its input alone.
extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::vector<std::string> channels = cairn::fuzz::ExplorerChannels();
  static const std::vector<cairn::explore::ExplorerConfig> configs = Configs();
  static const cairn::common::RobotProfile profile = cairn::common::LoadRobotProfileFile(
      std::string(CAIRN_SOURCE_DIR) + "/config/profiles/pioneer3at.yaml");
  for (const auto& config : configs) {
    Explorer e(config, profile);
    cairn::fuzz::FeedBus(e.node, channels, data, size, [&] { e.service.Tick(); });
    e.service.PublishStatus();
  }
  return 0;
}
