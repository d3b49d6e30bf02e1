// cairn-sim's inputs: SimService over the demo scenario (the tunnel world, the Pioneer 3-AT
// "p3at" with its lidar, laser, odometry and IMU) on memq://, fed velocity commands, body-velocity
// requests and SIM.CONTROL requests (spawn, move, remove, doors, reset, pause, speed, sensor
// triggers, list) through the node's decode and the real handlers, with a physics step and its
// readings published after every message. The simulator is built once: a model compiles in
// tenths of a second, and SIM.CONTROL's own bounds (spawn slots, sizes) are what keep a long
// run of inputs within its memory.

#include <memory>
#include <string>
#include <vector>

#include "common/channels.h"
#include "simulator/lcm/sim_service.h"
#include "simulator/mujoco_sim.h"
#include "simulator/scenario.h"
#include "tests/fuzz/bus_channels.h"
#include "tests/fuzz/bus_feed.h"
#include "tests/support/memq_node.h"

namespace {

struct Harness {
  Harness()
      : node(cairn::testing::MemqNodeOptions("cairn-sim")),
        sim(cairn::sim::LoadScenarioFile(std::string(CAIRN_SOURCE_DIR) + "/config/sim/demo.yaml",
                                         cairn::sim::SimPaths::InTree(CAIRN_SOURCE_DIR))) {
    cairn::sim::SimServiceParams params;
    params.max_clock_rate_hz = 1e9;
    service = std::make_unique<cairn::sim::SimService>(node, sim, params);
  }
  cairn::runtime::Node node;
  cairn::sim::MujocoSim sim;
  std::unique_ptr<cairn::sim::SimService> service;
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static Harness* h = new Harness();
  static const std::vector<std::string> channels = cairn::fuzz::SimChannels();
  cairn::fuzz::FeedBus(h->node, channels, data, size, [] {
    h->service->HandlePending();
    h->service->StepAndPublish(1);
  });
  return 0;
}
