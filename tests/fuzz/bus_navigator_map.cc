// cairn-navigator's map input: LcmMapClient for a cost layer with its directed layer, and one
// for an occupancy layer, on memq://. Tiles and manifests go through the node's decode and the
// clients' real handlers; each input ends with a poll and a look at the newest snapshot.

#include <memory>
#include <string>
#include <vector>

#include "common/robot_profile.h"
#include "planner/lcm/lcm_map_client.h"
#include "tests/fuzz/bus_channels.h"
#include "tests/fuzz/bus_feed.h"
#include "tests/support/memq_node.h"

namespace {

struct Harness {
  Harness() : node(cairn::testing::MemqNodeOptions("cairn-navigator", cairn::fuzz::kRobot)) {
    const auto profile = cairn::common::LoadRobotProfileFile(std::string(CAIRN_SOURCE_DIR) +
                                                             "/config/profiles/pioneer3at.yaml");
    cairn::planner::LcmMapClientParams cost;
    cost.robot = cairn::fuzz::kRobot;
    cost.layer = "cost/pioneer3at";
    cost.directed_layer = "directed/pioneer3at";
    cost.resend_interval_s = 0.0;
    cost.snapshot.incomplete_timeout_s = 0.0;
    cost_client = std::make_unique<cairn::planner::LcmMapClient>(node, cost, profile.footprint_m);
    cairn::planner::LcmMapClientParams occupancy = cost;
    occupancy.layer = "final";
    occupancy.directed_layer.clear();
    occupancy.snapshot.encoding = cairn::planner::MapEncoding::kOccupancy;
    occupancy_client =
        std::make_unique<cairn::planner::LcmMapClient>(node, occupancy, profile.footprint_m);
  }
  cairn::runtime::Node node;
  std::unique_ptr<cairn::planner::LcmMapClient> cost_client;
  std::unique_ptr<cairn::planner::LcmMapClient> occupancy_client;
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static Harness* h = new Harness();
  static const std::vector<std::string> channels = cairn::fuzz::NavigatorMapChannels();
  cairn::fuzz::FeedBus(h->node, channels, data, size);
  h->cost_client->Poll();
  h->occupancy_client->Poll();
  (void)h->cost_client->Latest();
  (void)h->occupancy_client->Latest();
  return 0;
}
