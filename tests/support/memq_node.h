#pragma once

#include <string>

#include "services/runtime/node.h"

// The options of a node under test on memq:// (an in-process bus: no network), without signal
// handlers and, unless asked, without following SIM.CLOCK.

namespace cairn::testing {

inline runtime::NodeOptions MemqNodeOptions(const std::string& process_name,
                                            const std::string& robot = "",
                                            bool follow_sim_clock = false) {
  runtime::NodeOptions options;
  options.process_name = process_name;
  options.robot = robot;
  options.lcm_url = "memq://";
  options.install_signal_handlers = false;
  options.follow_sim_clock = follow_sim_clock;
  return options;
}

}  // namespace cairn::testing
